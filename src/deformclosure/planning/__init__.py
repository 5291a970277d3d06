"""Planning: grasps of many jaw pairs and batch runs over many parts.

* :mod:`~deformclosure.planning.plan` ranks every jaw pair of one part.
* :mod:`~deformclosure.planning.batch` runs CLI commands on many part or mesh files
  (local processes or a Dask cluster) into a resumable SQLite results file.
"""

from .batch import BatchSummary, Job, format_results, load_jobs, read_results, run_batch
from .plan import PlanResult, plan_grasps

__all__ = [
    "plan_grasps",
    "PlanResult",
    "run_batch",
    "load_jobs",
    "read_results",
    "format_results",
    "Job",
    "BatchSummary",
]
