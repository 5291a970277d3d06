"""The worker side of a batch: one job in, one stored row's worth out.

A worker receives a job's files as :class:`~deformclosure.jsonfile.Source` objects (name
and bytes) — the part and every file an option names — never paths to copy, so it parses
exactly the bytes of the job key, and a Dask worker needs no shared file system. It calls
:func:`deformclosure.reports.run` and returns the report as JSON text; a failure is
returned as a one-line message naming the user's file, never raised.

Local worker processes ignore Ctrl-C (the batch process handles it), use one BLAS
thread, and die with the batch process (:func:`init_worker`).
"""

from __future__ import annotations

import os
import signal
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from ..errors import DeformClosureError
from .jobs import Job, _version, one_line, sha256

__all__ = ["run_job", "payload", "failed", "JobFailed", "init_worker", "mp_context",
           "worker_environ"]

#: One BLAS thread per worker process, as Dask's nanny sets for its workers: N worker
#: processes then use N cores without oversubscription, and every scheduler sums in the
#: same order, so a job gives the same bits on the local pool and on a Dask cluster.
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "VECLIB_MAXIMUM_THREADS": "1"}


class JobFailed(Exception):
    """A job that cannot be handed to a worker (its file changed or cannot be read)."""


def failed(error: str) -> dict:
    """The outcome of a job that failed before or outside its worker."""
    now = time.time()
    return {"status": "failed", "result": None, "error": one_line(error), "started": now,
            "finished": now, "seconds": 0.0}


def payload(job: Job, version: str) -> dict:
    """What a worker needs for ``job``: the command, its parameters with every input file
    as a Source, and the package version. The files are read now and checked against the
    digests of the key; :class:`JobFailed` if one changed or cannot be read."""
    from ..jsonfile import Source

    def source(path: str, digest: str, shown: str) -> Source:
        try:
            data = Path(path).read_bytes()
        except OSError as err:
            raise JobFailed(f"{shown}: cannot read ({err.strerror or err})") from None
        if sha256(data) != digest:
            raise JobFailed(f"{shown}: the file changed after the batch started; run the "
                            "batch again")
        return Source(shown, data)

    from .jobs import SIDECAR

    params, sidecar = dict(job.params), None
    for name, path, digest in job.inputs:
        if name == SIDECAR:            # a drawing's material file travels with the drawing
            sidecar = source(path, digest, path)
        else:
            params[name] = source(path, digest, path)
    part = source(job.path, job.digest, job.part)
    return {"command": job.command, "part": Source(part.name, part.data, sidecar),
            "params": params, "version": version}


def run_job(payload: dict) -> dict:
    """Run one job in this process (the worker side; picklable for any executor).

    Parameters
    ----------
    payload : dict
        From :func:`payload`: ``command``, ``part`` (a Source), ``params`` (input files
        as Sources, outputs as absolute paths) and ``version``.

    Returns
    -------
    dict
        ``status`` ("ok"/"failed"), ``result`` (compact JSON text of the report, or None),
        ``error`` (one line, or None), ``started``, ``finished`` (Unix time, s),
        ``seconds``. Exceptions of the command are recorded, never raised (Ctrl-C is).
    """
    started, t0 = time.time(), time.perf_counter()
    status, result, error = "failed", None, None
    try:
        result = _execute(payload)
        status = "ok"
    except DeformClosureError as err:
        error = str(err)
    except KeyboardInterrupt:
        raise
    except SystemExit as err:
        error = f"the command exited with code {err.code}"
    except BaseException as err:  # noqa: BLE001 - a job's failure must not stop the batch
        error = f"{type(err).__name__}: {err}"
    return {"status": status, "result": result,
            "error": None if error is None else one_line(error), "started": started,
            "finished": time.time(), "seconds": time.perf_counter() - t0}


def _execute(payload: dict) -> str:
    """The job's report as compact JSON text; its plots and exports written."""
    from .. import reports
    from ..outputs import json_text

    if payload["version"] != _version():
        raise DeformClosureError(f"the worker runs deformclosure {_version()} but the batch "
                                 f"{payload['version']}; install the same version on every "
                                 "worker")
    command, params = payload["command"], payload["params"]
    report = reports.run(command, payload["part"], params)
    outputs = {o.name for o in reports.options_of(command) if o.role == "output"}
    if any(params.get(name) is not None for name in outputs - {"output"}):
        report.save(report=False)
    return json_text(report.data, compact=True)


# ----------------------------------------------------------------------------- processes


@contextmanager
def worker_environ() -> Iterator[None]:
    """Set :data:`WORKER_ENV` for the processes started inside; restore it afterwards."""
    saved = {k: os.environ.get(k) for k in WORKER_ENV}
    os.environ.update(WORKER_ENV)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def mp_context():
    """The start method of local workers: a fork server that has imported the report
    modules once (fork from a parent with threads is unsafe; spawn re-imports numpy and
    scipy per worker), with one BLAS thread; spawn where there is no fork server."""
    import multiprocessing

    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")  # pragma: no cover - Windows
    from multiprocessing import forkserver

    from ..reports import COMMANDS, JOB_COMMANDS

    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload([__name__, *(f"deformclosure.reports.{COMMANDS[c]}"
                                            for c in JOB_COMMANDS)])
    with worker_environ():  # the server (and so every worker) has one BLAS thread
        forkserver.ensure_running()
    return ctx


def init_worker(batch_pid: int) -> None:
    """Pool initializer: ignore Ctrl-C; exit when the batch process ``batch_pid`` is gone.

    Ctrl-C reaches every process of the terminal's group: the batch process handles it
    (it stops the workers, says what is kept and exits 130), so workers ignore SIGINT.

    After ``kill -9`` of the batch, pool workers would live on: they wait on a queue
    they hold the write end of, and the fork server they come from waits for them (each
    holds its lifeline), so neither the kernel's parent-death signal nor the end of the
    fork server can stop them. A daemon thread of each worker waits for the batch
    process to end — on a pidfd where there is one (Linux >= 5.3: no polling, not fooled
    by a reused PID), else polling it every second — and ends the worker.
    """
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except (ValueError, OSError):  # pragma: no cover - not the main thread
        pass
    try:
        fd = os.pidfd_open(batch_pid)
    except (AttributeError, OSError):  # pragma: no cover - not Linux, or gone already
        fd = None
    if fd is None and not _alive(batch_pid):
        os._exit(1)
    threading.Thread(target=_watch, args=(batch_pid, fd), name="deformclosure-watch-batch",
                     daemon=True).start()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # pragma: no cover - alive, another user's process
        return True
    return True


def _watch(pid: int, fd: int | None) -> None:
    """End this process when process ``pid`` ends (its pidfd ``fd`` becomes readable)."""
    import select

    while True:
        if fd is not None:
            if select.select([fd], [], [])[0]:
                os._exit(1)
        elif _alive(pid):  # pragma: no cover - without pidfd
            time.sleep(1.0)
        else:  # pragma: no cover
            os._exit(1)
