"""Planning: grasps of many jaw pairs of one part.

* :mod:`~deformclosure.planning.plan` ranks every jaw pair of one part.

Batch runs over many parts live in :mod:`deformclosure.batch`.
"""

from .plan import PlanResult, plan_grasps

__all__ = [
    "plan_grasps",
    "PlanResult",
]
