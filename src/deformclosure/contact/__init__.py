"""Contact mechanics shared by every model (SPEC §6, §7): the boundary compliance of a
free part in one gauge.

The pads on a grasp axis (:mod:`deformclosure.pads`) and a part placed among fixed
fingers (:mod:`deformclosure.dspace`) solve the same frictionless contact problem on the
same gauged compliance; they differ only in their coordinates.
"""

from .compliance import BoundaryCompliance, gauge_functionals, mean_rotation_row, nodal_areas

__all__ = ["BoundaryCompliance", "gauge_functionals", "mean_rotation_row", "nodal_areas"]
