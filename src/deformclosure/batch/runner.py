"""Running a batch: the jobs not yet in the results file, each committed as it finishes.

Schedulers
    ``"processes"`` (a :class:`concurrent.futures.ProcessPoolExecutor`, the default),
    ``"inline"`` (the calling process, one job at a time; for debugging) or the address
    of a Dask scheduler (``"tcp://host:8786"``) or a :class:`distributed.Client`
    (:mod:`.cluster`). Workers receive the files' bytes, not paths.

Only this process writes the results file, one transaction per finished job, so a run
killed at any moment keeps every finished job and the next run skips them. Ctrl-C:
workers ignore SIGINT, this process stops them and raises :class:`BatchInterrupted`.
"""

from __future__ import annotations

import concurrent.futures as cf
import os
import sys
import time
import uuid
from collections import deque
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

from ..errors import BatchError
from ..limits import usable_cpus
from . import cluster, store, worker
from .jobs import Job, _version, list_identity

__all__ = ["run_batch", "BatchSummary", "BatchInterrupted"]


@dataclass(frozen=True)
class BatchSummary:
    """What a batch run did.

    Attributes
    ----------
    db_path : str
        The results file.
    n_jobs : int
        Distinct jobs in the batch (entries with the same key count once).
    n_duplicates : int
        Entries whose key equals an earlier entry's (same bytes, command and options).
    n_run : int
        Jobs run now.
    n_skipped : int
        Jobs already in the results file (ok, or failed without ``retry_failed``).
    n_ok, n_failed : int
        Status of the batch's jobs in the results file after the run (run now or before).
    seconds : float
        Wall time of the run (s).
    failures : tuple of dict
        ``{"part", "command", "options", "error"}`` of every failed job of the batch.
    """

    db_path: str
    n_jobs: int
    n_duplicates: int
    n_run: int
    n_skipped: int
    n_ok: int
    n_failed: int
    seconds: float
    failures: tuple[dict, ...] = ()

    @property
    def exit_code(self) -> int:
        """0 if every job of the batch is ok, 1 if some failed."""
        return 1 if self.n_failed else 0

    def to_dict(self) -> dict:
        """Plain-Python form (JSON-serialisable)."""
        d = asdict(self)
        d["failures"] = [dict(f) for f in self.failures]
        d["exit_code"] = self.exit_code
        return d


class BatchInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a batch; every job finished before is in the results file.

    Attributes
    ----------
    db_path : str
    n_finished : int
        Jobs finished (and committed) in this run.
    n_kept : int
        Jobs of the batch in the results file (this run's and earlier ones).
    """

    def __init__(self, db_path: str, n_finished: int, n_kept: int):
        super().__init__(db_path, n_finished, n_kept)
        self.db_path, self.n_finished, self.n_kept = db_path, n_finished, n_kept

    def __str__(self) -> str:
        return (f"interrupted; {self.n_kept} job{'s' * (self.n_kept != 1)} finished "
                f"{'are' if self.n_kept != 1 else 'is'} kept in {self.db_path}; run the same "
                "command to resume")


def run_batch(jobs: Sequence[Job] | str | os.PathLike, db_path: str | os.PathLike,
              scheduler: Any = "processes", workers: int | None = None,
              retry_failed: bool = False, progress: bool = True,
              append: bool = False, mp_context=None) -> BatchSummary:
    """Run the jobs not yet in the results file; commit each one as it finishes.

    Parameters
    ----------
    jobs : sequence of Job, or path-like
        Jobs from :func:`~deformclosure.batch.load_jobs`, or a folder / job list to load
        with its defaults.
    db_path : path-like
        SQLite results file, created if missing (table :data:`~deformclosure.batch.SCHEMA`).
    scheduler : str or distributed.Client
        ``"processes"`` (local process pool), ``"inline"`` (this process, one job at a
        time) or a Dask scheduler address ``"tcp://host:port"`` (``tls://`` with the
        Dask configuration's TLS settings; or a connected client). Dask is needed only
        for the last (``pip install "deformclosure[cluster]"``).
    workers : int, optional
        Local pool size (default: the CPUs this process may use, at most one per job);
        with Dask, the most jobs in flight at once (default: twice the cluster's threads).
    retry_failed : bool
        Run again the jobs recorded as failed (default: keep them).
    progress : bool
        Show a progress bar (tqdm, on stderr).
    append : bool
        Add this batch to a results file made for another job list (refused otherwise).
    mp_context : multiprocessing context, optional
        Start method of the local pool (default: a fork server that has imported the
        report modules; spawn where there is none).

    Returns
    -------
    BatchSummary

    Raises
    ------
    BatchError
        Bad jobs, results file or scheduler — found before any job runs, and before the
        results file is created: a file that is not ours (left unchanged), a corrupt,
        read-only or other job list's results file, a scheduler that does not answer.
        A job's own failure is never raised: it is recorded with ``status = "failed"``
        and its one-line message.
    BatchInterrupted
        Ctrl-C (a :class:`KeyboardInterrupt`): the workers are stopped, every finished
        job is kept.

    Notes
    -----
    On a local pool, a worker process that dies (crash, out of memory) takes down the
    jobs in flight; each of them is run again alone, and the one that kills its process
    again is recorded as failed.
    """
    t0 = time.perf_counter()
    jobs, unique, shown = _preflight(jobs, db_path, scheduler, workers)
    client, own = cluster.connect(scheduler) if cluster.is_dask(scheduler) else (None, False)
    conn = rec = None
    try:
        conn = store.open_for_run(Path(shown), shown, list_identity(list(unique.values())),
                                  set(unique), _source(jobs), append)
        rec = _Recorder(conn, shown, store.statuses(conn, shown, unique))
        todo = deque(j for k, j in unique.items() if k not in rec.status
                     or (retry_failed and rec.status[k] == "failed"))
        n_run = len(todo)
        with rec.bar(n_run, progress):
            _run(todo, rec, scheduler, workers, client, mp_context)
        failures = (store.failures(conn, shown, unique)
                    if any(rec.status.get(k) == "failed" for k in unique) else [])
    except KeyboardInterrupt:
        # counted from the file: Ctrl-C may land between a row's commit and its count here
        try:
            kept = store.statuses(conn, shown, unique) if conn is not None else {}
        except BatchError:
            kept = dict(rec.status) if rec is not None else {}
        n_before = sum(1 for k in kept if rec is not None and k in rec.initial)
        n_done = max(len(kept) - n_before, rec.n_finished if rec else 0)
        raise BatchInterrupted(shown, n_done, len(kept)) from None
    finally:
        if conn is not None:
            conn.close()
        if own:
            client.close()
    return BatchSummary(db_path=shown, n_jobs=len(unique), n_duplicates=len(jobs) - len(unique),
                        n_run=n_run, n_skipped=len(unique) - n_run,
                        n_ok=sum(rec.status.get(k) == "ok" for k in unique),
                        n_failed=len(failures), seconds=time.perf_counter() - t0,
                        failures=tuple(failures))


def _preflight(jobs, db_path, scheduler, workers) -> tuple[list[Job], dict[str, Job], str]:
    """Everything that can refuse the run, checked before the results file is created or
    changed: the jobs, the scheduler's form, the file itself (read only) and its folder.
    Returns the jobs, the distinct ones by key, and the file's name."""
    jobs = _job_list(jobs)
    if not isinstance(db_path, (str, os.PathLike)) or not os.fspath(db_path):
        raise BatchError(f"results file {db_path!r}: give a file path")
    cluster.check_scheduler(scheduler, workers)
    unique: dict[str, Job] = {}
    for j in jobs:
        unique.setdefault(j.key, j)
    shown = os.fspath(db_path)
    state = store.inspect_results(Path(shown), shown)
    store.check_writable(Path(shown), shown, exists=state != "missing")
    return jobs, unique, shown


def _job_list(jobs) -> list[Job]:
    from .lists import load_jobs

    if isinstance(jobs, (str, os.PathLike)):
        jobs = load_jobs(jobs)
    jobs = list(jobs)
    if not all(isinstance(j, Job) for j in jobs):
        raise BatchError("jobs: expected Job objects from load_jobs() or a folder/list path")
    return jobs


def _source(jobs: Sequence[Job]) -> str:
    """A short description of where the jobs come from (stored with the list identity)."""
    parts = sorted({str(Path(j.path).parent) for j in jobs})
    return f"{len(jobs)} jobs in {', '.join(parts[:3])}{', ...' if len(parts) > 3 else ''}"


class _Recorder:
    """Commits each finished job at once and keeps the counts and the progress bar."""

    def __init__(self, conn, shown: str, status: dict[str, str]):
        self.conn, self.shown, self.status = conn, shown, status
        self.initial = frozenset(status)        # rows of earlier runs
        self.version = _version()
        self.n_finished = self.n_bad = 0
        self._bar = None

    def bar(self, total: int, progress: bool):
        from ..log import progress_bar

        self._bar = progress_bar(total, "batch", "job", file=sys.stderr,
                                 disable=not progress or total == 0, dynamic_ncols=True)
        return self._bar

    def __call__(self, job: Job, out: dict) -> None:
        store.store_row(self.conn, self.shown, job, out, self.version)
        self.n_finished += 1
        ok = out["status"] == "ok"
        self.status[job.key] = "ok" if ok else self.status.get(job.key, "failed")
        self.n_bad += not ok
        if self._bar is not None:
            self._bar.update(1)
            if self.n_bad:
                self._bar.set_postfix(failed=self.n_bad, refresh=False)


def _run(todo: deque, record: _Recorder, scheduler, workers, client, mp_context) -> None:
    """Run ``todo`` on the scheduler; ``record`` each job as it finishes."""
    if not todo:
        return
    version = record.version
    if client is not None:
        _run_dask(todo, record, version, client, cluster.capacity(client, workers))
    elif scheduler == "inline":
        for job in todo:
            record(job, _run_here(job, version))
    else:
        n = workers or usable_cpus()
        with worker.worker_environ():  # for spawned workers: set while the pool lives
            pool = _LocalPool(max(1, min(n, len(todo))), mp_context or worker.mp_context())
            try:
                _drive(pool.submit, pool.wait_first, 2 * pool.workers, todo, record, version,
                       pool.rerun_alone)
            except BaseException:
                pool.close(cancel=True)
                raise
            pool.close()


def _run_here(job: Job, version: str) -> dict:
    try:
        return worker.run_job(worker.payload(job, version))
    except worker.JobFailed as err:
        return worker.failed(str(err))


def _run_dask(todo: deque, record, version: str, client, capacity: int) -> None:
    futures: list = []

    def submit(payload: dict):
        fut = client.submit(worker.run_job, payload, pure=False,
                            key=f"deformclosure-job-{uuid.uuid4().hex}")
        futures.append(fut)
        return fut

    try:
        _drive(submit, lambda fs: cluster.wait_first(client, fs), capacity, todo, record,
               version)
    except BaseException:
        client.cancel([f for f in futures if not f.done()])
        raise


def _drive(submit: Callable, wait_first: Callable, capacity: int, todo: deque, record,
           version: str, rerun_alone: Callable | None = None) -> None:
    """Keep ``capacity`` jobs in flight; ``record`` each as it finishes. Jobs lost with a
    worker process that died go to ``rerun_alone`` (with those still in flight)."""
    from concurrent.futures.process import BrokenProcessPool

    inflight: dict[Any, Job] = {}
    while todo or inflight:
        while todo and len(inflight) < capacity:
            job = todo.popleft()
            try:
                inflight[submit(worker.payload(job, version))] = job
            except worker.JobFailed as err:
                record(job, worker.failed(str(err)))
            except BrokenProcessPool:
                # a worker died after the last wait: the pool refuses new jobs. Put this
                # one back, settle those in flight (the lost ones alone) on a new pool.
                todo.appendleft(job)
                if rerun_alone is None:
                    raise
                rerun_alone([], inflight, record, version)
                inflight.clear()
        if not inflight:
            continue
        lost = []
        for fut in wait_first(list(inflight)):
            job = inflight.pop(fut)
            try:
                out = fut.result()
            except BrokenProcessPool:
                lost.append(job)
                continue
            except Exception as err:  # noqa: BLE001 - e.g. distributed's KilledWorker
                out = worker.failed(f"{type(err).__name__}: {err}")
            record(job, out)
        if lost:
            rerun_alone(lost, inflight, record, version)
            inflight.clear()


class _LocalPool:
    """A :class:`~concurrent.futures.ProcessPoolExecutor` of workers that ignore Ctrl-C and
    die with this process, restarted when a worker process dies."""

    def __init__(self, workers: int, ctx):
        self.workers, self.ctx = workers, ctx
        self.pool = self._new(workers)

    def _new(self, n: int) -> cf.ProcessPoolExecutor:
        return cf.ProcessPoolExecutor(n, mp_context=self.ctx, initializer=worker.init_worker,
                                      initargs=(os.getpid(),))

    def submit(self, payload: dict) -> cf.Future:
        return self.pool.submit(worker.run_job, payload)

    @staticmethod
    def wait_first(futures) -> set:
        return cf.wait(futures, return_when=cf.FIRST_COMPLETED).done

    def rerun_alone(self, lost: list, inflight: dict, record, version: str) -> None:
        """A worker process died: every job in flight fails with BrokenProcessPool.
        Collect them, restart the pool, and run each lost job alone in a fresh process,
        so only the job that kills its process again is recorded as failed."""
        from concurrent.futures.process import BrokenProcessPool

        for fut in cf.wait(list(inflight)).done:
            try:
                record(inflight[fut], fut.result())
            except BrokenProcessPool:
                lost.append(inflight[fut])
        self.pool.shutdown(wait=False, cancel_futures=True)
        self.pool = self._new(self.workers)
        for job in lost:
            try:
                payload = worker.payload(job, version)
            except worker.JobFailed as err:
                record(job, worker.failed(str(err)))
                continue
            with self._new(1) as alone:
                try:
                    out = alone.submit(worker.run_job, payload).result()
                except BrokenProcessPool:
                    out = worker.failed("the worker process died while running this job "
                                        "(crash or out of memory)")
            record(job, out)

    def close(self, cancel: bool = False) -> None:
        """Wait for the jobs in flight; with ``cancel``, stop the workers at once (their
        jobs are lost, not recorded: a later run does them)."""
        if cancel:
            for proc in list((getattr(self.pool, "_processes", None) or {}).values()):
                try:
                    proc.terminate()
                except (OSError, AttributeError, ValueError):  # pragma: no cover
                    pass
        self.pool.shutdown(wait=not cancel, cancel_futures=cancel)
