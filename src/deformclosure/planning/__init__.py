"""Planning: both planners — where should the jaws go on one part?

* :mod:`~deformclosure.planning.pads` ranks grasp axes for pads (SPEC §6, the default),
  screening every axis and verifying the best with the code path of ``optimize``;
* :mod:`~deformclosure.planning.plan` ranks every jaw pair for the paper's point jaws
  (SPEC §4), every quality within ε.

Batch runs over many parts live in :mod:`deformclosure.batch`.
"""

from .pads import PadPlan, plan_pads
from .plan import PlanResult, plan_grasps

__all__ = [
    "plan_grasps",
    "PlanResult",
    "plan_pads",
    "PadPlan",
]
