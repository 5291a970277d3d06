"""Batch runs: many part or mesh files × report commands, results in a resumable SQLite file.

A **job** is one part or mesh file, one report command (``plan``, ``optimize``, ``check``,
``mesh``, ``slice``) and that command's options, parsed as the CLI parses them. A worker
runs :func:`deformclosure.reports.run` on the bytes of the job's files and sends back the
JSON report; the batch process stores it in an SQLite file, one row per job, each in its
own transaction as soon as the job finishes (SPEC §5, "Batch"). A run that is killed
loses at most the jobs that were running, and running the same batch again skips every
job already in the file.

* :mod:`.jobs` — :class:`Job`, its checks and its key (:func:`job_key`);
* :mod:`.lists` — :func:`load_jobs`: a folder, a JSON or a CSV job list;
* :mod:`.store` — the results file (marking, creation, checks, one row per job);
* :mod:`.worker` — one job in a worker (:func:`run_job`), worker processes;
* :mod:`.cluster` — a Dask cluster as the scheduler (optional);
* :mod:`.runner` — :func:`run_batch`: scheduling, crash recovery, Ctrl-C;
* :mod:`.results` — :func:`read_results`, :func:`result_summary`, :func:`format_results`.

Layering: above :mod:`deformclosure.reports`, below :mod:`deformclosure.cli`; importing
it loads no click, matplotlib or Dask.

Examples
--------
>>> from deformclosure.batch import load_jobs, run_batch, read_results
>>> jobs = load_jobs("examples", command="mesh")                # doctest: +SKIP
>>> summary = run_batch(jobs, "results.sqlite", workers=2)       # doctest: +SKIP
>>> [(r["part"], r["status"]) for r in read_results("results.sqlite")]  # doctest: +SKIP
"""

from __future__ import annotations

from .jobs import MAX_FIELD, Job, job_key
from .lists import load_jobs
from .results import format_results, read_results, result_summary
from .runner import BatchInterrupted, BatchSummary, run_batch
from .store import APPLICATION_ID, SCHEMA
from .worker import run_job

__all__ = [
    "Job",
    "BatchSummary",
    "BatchInterrupted",
    "load_jobs",
    "run_batch",
    "run_job",
    "read_results",
    "result_summary",
    "format_results",
    "job_key",
    "SCHEMA",
    "APPLICATION_ID",
    "MAX_FIELD",
]
