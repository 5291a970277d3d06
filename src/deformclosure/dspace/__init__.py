"""D-space and deform closure for any finger set (paper §3; SPEC §2-3).

Pipeline: configurations ``q`` of a meshed part → energies (:mod:`.energy`, linear and
corotational) → topology-preserving set ``D_T`` (:mod:`.topology`) → fingers and
D-obstacles, ``D_free`` (:mod:`.fingers`, :mod:`.obstacles`) → slices with one node
moving (:mod:`.slices`) → frictionless contact equilibrium (:mod:`.equilibrium`) →
deform closure with a certificate (:mod:`.closure`); the release energy ``U_A`` of any
finger set from the contact energy over the part's placements (:mod:`.placement_energy`,
:mod:`.escape`).

Conventions: node arrays ``(n, 2)`` in metres, triangles ``(m, 3)`` counter-clockwise,
configurations ``(n, 2)``/``(2n,)`` or batches ``(b, n, 2)``/``(b, 2n)``; SI throughout.
See ``docs/dspace.md``.

References
----------
K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure Grasps of Deformable
Parts", IJRR 24(11), 2005, §3.
"""

from .closure import (ClosureResult, ContactGroup, ContactPrimitive, ContactReport, RigidClosure,
                      contact_groups, deform_closure, relative_curvature, rigid_closure)
from .escape import FingerRelease, PlacementGrid, PlacementLandscape, release_energy_fingers
from .energy import (as_configurations, configuration_strains, corotational_energy, deformation_gradients,
                     element_energies, linear_energy, polar_rotation, strain_energy)
from .equilibrium import EquilibriumResult, area_centroid, equilibrium
from .fingers import (FINGER_TYPES, DiscFinger, Finger, HalfPlaneFinger, PointFinger, PolygonFinger, as_fingers,
                      fingers_from_dict, fingers_to_dict, load_fingers, write_fingers)
from .placement_energy import PlacementEnergy, PlacementState
from .obstacles import TOUCH_TOLERANCE, boundary_gaps, dobstacle_mask, in_dfree, in_dobstacle, touch_tolerance
from .slices import SliceResult, dfree_slice
from .topology import (DEFAULT_MIN_AREA_RATIO, boundary_crossings, in_dt, inverted_triangles, loop_edges,
                       signed_areas, topology_violations)

__all__ = [
    # energy
    "as_configurations", "deformation_gradients", "polar_rotation", "configuration_strains",
    "element_energies", "linear_energy", "corotational_energy", "strain_energy",
    # topology
    "DEFAULT_MIN_AREA_RATIO", "loop_edges", "signed_areas", "inverted_triangles", "boundary_crossings",
    "in_dt", "topology_violations",
    # fingers
    "Finger", "PointFinger", "DiscFinger", "PolygonFinger", "HalfPlaneFinger", "FINGER_TYPES",
    "as_fingers", "load_fingers", "fingers_from_dict", "fingers_to_dict", "write_fingers",
    # obstacles
    "TOUCH_TOLERANCE", "touch_tolerance", "in_dobstacle", "dobstacle_mask", "in_dfree", "boundary_gaps",
    # slices
    "SliceResult", "dfree_slice",
    # equilibrium
    "EquilibriumResult", "equilibrium", "area_centroid",
    # closure
    "ContactPrimitive", "ContactGroup", "RigidClosure", "ContactReport", "ClosureResult",
    "contact_groups", "relative_curvature", "rigid_closure", "deform_closure",
    # release energy over placements (SPEC §7)
    "PlacementEnergy", "PlacementState", "PlacementGrid", "PlacementLandscape", "FingerRelease",
    "release_energy_fingers",
]
