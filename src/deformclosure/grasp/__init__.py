"""Two-jaw grasps: pair stiffness, contact graph, release energy, optimal separation (SPEC §4)."""

from .analysis import GraspAnalysis, GraspModel, grasp_model, optimize_separation
from .contact_graph import ContactGraph, contact_graph, pulling_pairs
from .elastic_limit import ElasticLimit, elastic_limit
from .jaws import jaw_patches
from .pair_stiffness import PairStiffness, all_pairs, pair_stiffness
from .release import Release, equilibrium_mask, release_energies, release_energy
from .separation import SeparationResult, optimize_separation_arrays, quality_at, vertex_energies

__all__ = [
    "GraspAnalysis", "GraspModel", "grasp_model", "optimize_separation",
    "ContactGraph", "contact_graph", "pulling_pairs",
    "ElasticLimit", "elastic_limit", "jaw_patches",
    "PairStiffness", "all_pairs", "pair_stiffness",
    "Release", "equilibrium_mask", "release_energies", "release_energy",
    "SeparationResult", "optimize_separation_arrays", "quality_at", "vertex_energies",
]
