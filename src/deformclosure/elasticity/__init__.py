"""Elasticity of linear-triangle meshes: CST stiffness, strains, free-body solves, external K,
and the neo-Hookean finite-strain law (SPEC §8)."""

from .critical_distance import (averaged_strain_magnitude, averaged_strains, averaging_operator,
                                default_critical_distance)
from .external import check_stiffness, read_stiffness
from .neohookean import NeoHookean, lame_constants
from .solve import FreeBodySolver, pinned_dofs, rigid_modes
from .stiffness import (assemble, constitutive_matrix, element_b_matrices, element_stiffness,
                        stiffness_matrix)
from .strain import element_strains, element_stresses, principal_strains, strain_magnitude

__all__ = [
    "stiffness_matrix", "constitutive_matrix", "element_b_matrices", "element_stiffness",
    "assemble", "element_strains", "element_stresses", "principal_strains",
    "strain_magnitude", "FreeBodySolver", "rigid_modes", "pinned_dofs", "read_stiffness",
    "check_stiffness", "default_critical_distance", "averaging_operator", "averaged_strains",
    "averaged_strain_magnitude", "NeoHookean", "lame_constants",
]
