"""deformclosure: D-space, deform closure and optimal two-jaw grasps of deformable planar parts.

Implements and extends K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure
Grasps of Deformable Parts", International Journal of Robotics Research 24(11), 2005.

The top level re-exports the core pipeline; plotting and the CLI are imported lazily
from their own subpackages.
"""

from importlib.metadata import PackageNotFoundError, version

from .elasticity import (FreeBodySolver, element_strains, principal_strains, read_stiffness,
                         rigid_modes, stiffness_matrix, strain_magnitude)
from .errors import (BatchError, DeformClosureError, FingerError, GraspError, MeshError,
                     PartError, StiffnessError)
from .grasp import (ContactGraph, GraspAnalysis, contact_graph, grasp_model, optimize_separation,
                    pair_stiffness, release_energies, release_energy)
from .dspace.escape import FingerRelease, release_energy_fingers
from .mesh import Mesh, mesh_part, read_mesh, write_mesh
from .part import Material, MeshOptions, Part, demo_part, notched_part

from .planning.plan import PlanResult, plan_grasps  # noqa: E402

try:
    __version__ = version("deformclosure")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0"

__all__ = [
    "__version__",
    "Part", "Material", "MeshOptions", "demo_part", "notched_part",
    "Mesh", "mesh_part", "read_mesh", "write_mesh",
    "stiffness_matrix", "element_strains", "principal_strains", "strain_magnitude",
    "FreeBodySolver", "rigid_modes", "read_stiffness",
    "pair_stiffness", "contact_graph", "ContactGraph", "release_energy", "release_energies",
    "grasp_model", "optimize_separation", "GraspAnalysis", "plan_grasps", "PlanResult",
    "release_energy_fingers", "FingerRelease",
    "DeformClosureError", "PartError", "MeshError", "StiffnessError", "GraspError",
    "FingerError", "BatchError",
]
