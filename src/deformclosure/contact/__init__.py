"""Contact mechanics shared by every model (SPEC §6, §7): the rigid bodies
(:mod:`.bodies`), the contact rows between them and the part's boundary (:mod:`.rows`: one
builder, the SPEC §3 and §7 rules as :class:`~.rows.RowRule` presets), the boundary
compliance of a free part in one gauge (:mod:`.compliance`) and one entry point for the
frictionless contact problem (:mod:`.solve`: pivoting LCP, balanced dual QP, exact squeeze
path); Coulomb friction on the same rows (:mod:`.friction`: the exact event-driven
stick/slip path, SPEC §9).

The pads on a grasp axis (:mod:`deformclosure.pads`) and a part placed among fixed
fingers (:mod:`deformclosure.dspace`) solve the same frictionless contact problem on the
same gauged compliance; they differ only in their coordinates.
"""

from .compliance import BoundaryCompliance, gauge_functionals, mean_rotation_row, nodal_areas
from .friction import FrictionPath, FrictionProblem, FrictionState, trace_friction
from .path import ContactPath
from .rows import EQUILIBRIUM_RULE, PLACEMENT_RULE, BoundaryModel, ContactRows, RowRule, contact_rows
from .solve import ContactProblem, ContactSolution, solve_contact, trace_contact

__all__ = ["BoundaryCompliance", "gauge_functionals", "mean_rotation_row", "nodal_areas",
           "ContactPath", "ContactProblem", "ContactSolution", "solve_contact", "trace_contact",
           "FrictionProblem", "FrictionState", "FrictionPath", "trace_friction",
           "BoundaryModel", "ContactRows", "RowRule", "EQUILIBRIUM_RULE", "PLACEMENT_RULE", "contact_rows"]
