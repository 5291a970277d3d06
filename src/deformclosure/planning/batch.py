"""Batch runs: many part or mesh files × CLI commands, results in a resumable SQLite file.

A **job** is one part or mesh file, one command of the ``deformclosure`` CLI (``plan``,
``optimize``, ``check``, ``mesh``, ``slice``) and that command's options. A worker runs
the command in-process on a private copy of the input files and sends back the JSON
report the command writes with ``-o``; the parent process stores it in an SQLite file,
one row per job, each row in its own transaction as soon as the job finishes (SPEC §5,
"Batch"). A run that is killed therefore loses at most the jobs that were running, and
running the same batch again skips every job already in the file.

Job key
    ``sha256`` of the part file's bytes, the command, the command's *parsed* options
    (every parameter value after click's parsing and defaults, so ``--method exact`` and
    no ``--method`` give the same key; input files named by options, such as
    ``--fingers``, enter through their bytes) and ``deformclosure.__version__``. Paths
    and output options (``--plot``, ``--export-graph``, ``--quiet``) are not part of the
    key: moving or renaming a catalogue keeps its results, and two files with the same
    bytes are one job.

Schedulers
    ``"processes"`` (a local process pool, the default), ``"inline"`` (the calling
    process, one job at a time; for debugging) or the address of a Dask scheduler
    (``"tcp://host:8786"``) or a :class:`distributed.Client`. Workers receive the file
    bytes, not paths, so a cluster needs no shared file system, only the same version
    of deformclosure.

Table ``jobs`` of the results file::

    key TEXT PRIMARY KEY  -- hex sha256, see above
    part TEXT             -- the part or mesh file as named in the job list
    command TEXT          -- e.g. "plan"
    options TEXT          -- JSON list of the option strings, as given
    status TEXT           -- "ok" or "failed"
    result TEXT           -- JSON report of the command (SI units), NULL if failed
    error TEXT            -- one-line message if failed, else NULL
    started REAL          -- Unix time (s) the worker started the job
    finished REAL         -- Unix time (s) it finished
    seconds REAL          -- run time (s) in the worker
    version TEXT          -- deformclosure version that ran the job

Examples
--------
>>> from deformclosure.planning import load_jobs, run_batch, read_results
>>> jobs = load_jobs("examples", command="mesh")                # doctest: +SKIP
>>> summary = run_batch(jobs, "results.sqlite", workers=2)       # doctest: +SKIP
>>> [(r["part"], r["status"]) for r in read_results("results.sqlite")]  # doctest: +SKIP
"""

from __future__ import annotations

import math

import concurrent.futures as cf
import csv
import hashlib
import io
import json
import multiprocessing
import os
import shlex
import sqlite3
import sys
import tempfile
import threading
import time
import uuid
from collections import deque
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Iterator, Sequence

from ..errors import BatchError, DeformClosureError

__all__ = [
    "Job",
    "BatchSummary",
    "load_jobs",
    "run_batch",
    "run_job",
    "read_results",
    "result_summary",
    "format_results",
    "job_key",
    "SCHEMA",
]

#: Commands that cannot be a job (they run batches or need no input file).
_NOT_JOBS = frozenset({"batch", "results", "demo"})
#: Parameters that name outputs or only change what is printed: not part of the key.
_OUTPUT_PARAMS = frozenset({"output", "plot", "export_graph", "quiet"})
#: Options the runner sets itself.
_RESERVED = ("-o", "--output", "-h", "--help")
#: Suffixes meshio knows that are too generic to mean "a mesh" in a folder of parts.
_AMBIGUOUS_SUFFIXES = frozenset({".dat", ".xml", ".svg", ".wkt", ".node", ".ele", ".txt"})

#: The results table (one row per job).
SCHEMA = """CREATE TABLE IF NOT EXISTS jobs (
    key TEXT PRIMARY KEY,
    part TEXT NOT NULL,
    command TEXT NOT NULL,
    options TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('ok', 'failed')),
    result TEXT,
    error TEXT,
    started REAL,
    finished REAL,
    seconds REAL,
    version TEXT
)"""
_COLUMNS = ("key", "part", "command", "options", "status", "result", "error", "started",
            "finished", "seconds", "version")


def _version() -> str:
    from .. import __version__  # late: the package imports this module while it loads

    return __version__


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


# --------------------------------------------------------------------------- jobs


@dataclass(frozen=True)
class Job:
    """One part or mesh file × one CLI command with its options.

    Build jobs with :meth:`Job.from_spec` or :func:`load_jobs`, which check the command
    and its options and compute the key.

    Attributes
    ----------
    part : str
        The part or mesh file as named in the job list (stored in the results file).
    command : str
        CLI command, e.g. ``"plan"``.
    options : tuple of str
        The command's options as given (without the part file and ``-o``).
    key : str
        Hex sha256 of the inputs, the parsed options and the package version.
    path : str
        Absolute path of the part file.
    argv : tuple of str
        The options passed to the worker: ``--name=value`` split in two and the paths
        of file options made absolute.
    inputs : tuple of (int, str, str)
        Input files named by options: index of the path in ``argv``, absolute path and
        sha256 of the bytes used for the key.
    digest : str
        sha256 of the part file's bytes used for the key.
    """

    part: str
    command: str
    options: tuple[str, ...]
    key: str
    path: str
    argv: tuple[str, ...]
    inputs: tuple[tuple[int, str, str], ...]
    digest: str

    @classmethod
    def from_spec(cls, part: str | os.PathLike, command: str = "plan",
                  options: Sequence[str] | str = (), base_dir: str | os.PathLike | None = None,
                  where: str | None = None) -> Job:
        """Check one job and compute its key.

        Parameters
        ----------
        part : path-like
            Part or mesh file; relative paths are relative to ``base_dir``.
        command : str
            A ``deformclosure`` command that takes a part file (``plan``, ``optimize``,
            ``check``, ``mesh``, ``slice``).
        options : sequence of str or str
            The command's options; a string is split like a shell would (:mod:`shlex`).
            Relative paths of file options are relative to ``base_dir``.
        base_dir : path-like, optional
            Folder of relative paths (default: the working directory).
        where : str, optional
            Where the job comes from, for error messages (e.g. ``"jobs.csv: line 3"``).

        Raises
        ------
        BatchError
            Unknown command, bad options, ``-o`` among the options, missing file.
        """
        where = f"{where}: " if where else ""
        base = Path(base_dir) if base_dir is not None else Path.cwd()
        if isinstance(options, str):
            try:
                options = shlex.split(options)
            except ValueError as err:
                raise BatchError(f"{where}options {options!r}: {err}") from None
        options = tuple(str(o) for o in options)
        cmd = _command(command, where)
        argv, inputs, params = _parse_options(cmd, command, str(part), options, base, where)
        part_str = str(part)
        p = Path(part_str)
        path = p if p.is_absolute() else base / p
        if not path.is_file():
            raise BatchError(f"{where}part {part_str!r}: file not found "
                             f"(relative paths are relative to {base})")
        display = part_str if p.is_absolute() or base_dir is None else str(Path(base_dir) / p)
        digest = _sha256(path.read_bytes())
        key = job_key(digest, command, params)
        return cls(part=display, command=command, options=options, key=key,
                   path=str(path.resolve()), argv=argv, inputs=inputs, digest=digest)


def _command(name: str, where: str):
    """The click command ``name``, checked to be a job command."""
    from ..cli.common import INPUTS
    from ..cli.main import cli

    choices = sorted(set(cli.commands) - _NOT_JOBS)
    if not isinstance(name, str) or name not in choices:
        raise BatchError(f"{where}command {name!r}: not a job command; choose one of "
                         f"{', '.join(choices)}")
    return cli.commands[name]


def _parse_options(cmd, command: str, part: str, options: tuple[str, ...], base: Path,
                   where: str) -> tuple[tuple[str, ...], tuple[tuple[int, str, str], ...], dict]:
    """Validate ``options`` with click; resolve file options; the parameters for the key."""
    import click

    bad = [o for o in options if o in _RESERVED or o.startswith("--output=")
           or (o.startswith("-o") and not o.startswith("--"))]
    if bad:
        raise BatchError(f"{where}options: {bad[0]} is set by the batch runner; remove it "
                         f"(each job's report goes to the results file)")
    # Parameters whose values are file paths: inputs (hashed) and outputs (made absolute).
    path_opts: dict[str, click.Parameter] = {}
    for prm in cmd.params:
        if isinstance(prm, click.Option) and isinstance(prm.type, click.Path):
            for name in (*prm.opts, *prm.secondary_opts):
                path_opts[name] = prm
    argv: list[str] = []
    for tok in options:  # --name=value -> --name value, so paths sit in their own token
        name, eq, value = tok.partition("=")
        if eq and name.startswith("--") and name in {o for p in cmd.params
                                                     for o in getattr(p, "opts", ())}:
            argv += [name, value]
        else:
            argv.append(tok)
    inputs = []
    for i in range(len(argv) - 1):
        prm = path_opts.get(argv[i])
        if prm is None or argv[i + 1].startswith("-") and argv[i + 1] != "-":
            continue
        f = Path(argv[i + 1])
        f = (f if f.is_absolute() else base / f).resolve()
        argv[i + 1] = str(f)
        if prm.name in _OUTPUT_PARAMS:
            continue
        if not f.is_file():
            raise BatchError(f"{where}{argv[i]}: file not found ({f})")
        inputs.append((i + 1, str(f), _sha256(f.read_bytes())))
    try:
        ctx = cmd.make_context(command, [part, *argv], resilient_parsing=False)
    except click.ClickException as err:
        raise BatchError(f"{where}{command} {shlex.join(options)}: {err.format_message()}") from None
    except click.exceptions.Exit:  # pragma: no cover - --help/--version are rejected above
        raise BatchError(f"{where}{command}: options {shlex.join(options)} only print") from None
    first_arg = next((p.name for p in cmd.params if isinstance(p, click.Argument)), None)
    digests = {path: digest for _, path, digest in inputs}
    params = {}
    for name, value in ctx.params.items():
        if name == first_arg or name in _OUTPUT_PARAMS:
            continue
        if isinstance(value, str) and value in digests:
            value = {"sha256": digests[value]}
        params[name] = value
    return tuple(argv), tuple(inputs), params


def job_key(digest: str, command: str, params: dict, version: str | None = None) -> str:
    """Key of a job: hex sha256 of the inputs, the parsed options and the package version.

    Parameters
    ----------
    digest : str
        sha256 (hex) of the part or mesh file's bytes.
    command : str
        CLI command.
    params : dict
        The command's parameter values after parsing (defaults included), input files
        replaced by ``{"sha256": ...}`` of their bytes; JSON-serialisable.
    version : str, optional
        Package version (default: the installed ``deformclosure.__version__``).

    Returns
    -------
    str
        64 hex digits.
    """
    blob = json.dumps({"part": digest, "command": command, "params": params,
                       "version": version or _version()},
                      sort_keys=True, separators=(",", ":"), default=list)
    return _sha256(blob.encode())


def _folder_files(folder: Path) -> list[Path]:
    import meshio

    suffixes = tuple(sorted(set(meshio.extension_to_filetypes) - _AMBIGUOUS_SUFFIXES)) + (".json",)
    return sorted(f for f in folder.iterdir()
                  if f.is_file() and not f.name.startswith(".") and f.name.lower().endswith(suffixes))


def load_jobs(path: str | os.PathLike, command: str = "plan",
              options: Sequence[str] | str = ()) -> list[Job]:
    """Read a batch: a folder of part or mesh files, or a job list (JSON or CSV).

    Parameters
    ----------
    path : path-like
        * a folder: one job per part or mesh file in it (``*.json`` and the mesh formats
          meshio reads; not recursive), each running ``command`` with ``options``;
        * a ``.json`` list: ``[{"part": "a.json", "command": "optimize", "options":
          ["--at", "0,10", "12,10"]}, ...]`` (an entry may also be just a path string);
        * a ``.csv`` file with a header ``part,command,options``, options as one
          shell-quoted string.

        Paths in a list are relative to the list's folder. An entry without a command
        or options (a missing key, an empty CSV cell) gets ``command`` and ``options``.
    command : str
        Default command (``"plan"``).
    options : sequence of str or str
        Default options (a string is split like a shell would).

    Returns
    -------
    list of Job
        In the order of the folder (sorted by name) or of the list.

    Raises
    ------
    BatchError
        Missing folder or list, unreadable or malformed list, empty batch, unknown
        command, bad options, missing part file.
    """
    p = Path(path)
    if not p.exists():
        raise BatchError(f"{path}: not found; give a folder of part/mesh files or a job list "
                         f"(.json or .csv)")
    if p.is_dir():
        files = _folder_files(p)
        if not files:
            raise BatchError(f"{path}: no part or mesh files in this folder")
        return [Job.from_spec(f.name, command, options, base_dir=p, where=str(f)) for f in files]
    suffix = p.suffix.lower()
    if suffix not in (".json", ".csv"):
        raise BatchError(f"{path}: a job list must be .json or .csv (or give a folder)")
    from ..jsonfile import read_text_file

    text = read_text_file(p, BatchError, "job list")
    if "\x00" in text:
        raise BatchError(f"{path}: the job list contains NUL bytes; it is not a text job list")
    specs = _json_specs(p, text) if suffix == ".json" else _csv_specs(p, text)
    if not specs:
        raise BatchError(f"{path}: the job list is empty")
    return [Job.from_spec(part, cmd or command, options if opts is None else opts,
                          base_dir=p.parent, where=where)
            for where, part, cmd, opts in specs]


def _json_specs(p: Path, text: str) -> list[tuple[str, str, str | None, Any]]:
    from ..jsonfile import parse_json

    data = parse_json(text, str(p), BatchError, "job list")
    if not isinstance(data, list):
        raise BatchError(f"{p}: a JSON job list is a list of "
                         '{"part": ..., "command": ..., "options": [...]} objects')
    specs = []
    for i, entry in enumerate(data):
        where = f"{p}: job [{i}]"
        if isinstance(entry, str):
            entry = {"part": entry}
        if not isinstance(entry, dict):
            raise BatchError(f"{where}: expected an object with 'part', 'command', 'options'")
        unknown = set(entry) - {"part", "command", "options"}
        if unknown:
            raise BatchError(f"{where}: unknown key {sorted(unknown)[0]!r} "
                             "(keys: part, command, options)")
        part, cmd, opts = entry.get("part"), entry.get("command"), entry.get("options")
        if not isinstance(part, str) or not part:
            raise BatchError(f"{where}: 'part' must be a file path (string)")
        if cmd is not None and not isinstance(cmd, str):
            raise BatchError(f"{where}: 'command' must be a string")
        if opts is not None and not (isinstance(opts, str) or (
                isinstance(opts, list) and all(isinstance(o, (str, int, float)) and
                                               not isinstance(o, bool) for o in opts))):
            raise BatchError(f"{where}: 'options' must be a list of strings")
        if isinstance(opts, list):
            opts = [str(o) for o in opts]
        specs.append((where, part, cmd, opts))
    return specs


def _csv_specs(p: Path, text: str) -> list[tuple[str, str, str | None, Any]]:
    reader = csv.DictReader(io.StringIO(text))
    fields = [f.strip() for f in reader.fieldnames or []]
    if "part" not in fields or set(fields) - {"part", "command", "options"}:
        raise BatchError(f"{p}: a CSV job list needs the header part,command,options "
                         f"(got {','.join(fields) or 'nothing'})")
    specs = []
    for row in reader:
        row = {(k or "").strip(): (v or "").strip() for k, v in row.items() if k is not None}
        where = f"{p}: line {reader.line_num}"
        if not any(row.values()):
            continue
        if not row.get("part"):
            raise BatchError(f"{where}: 'part' is empty")
        # An empty cell takes the default, as a missing key does in a JSON list.
        specs.append((where, row["part"], row.get("command") or None,
                      row.get("options") or None))
    return specs


# --------------------------------------------------------------------------- worker


class _ThreadRouter(io.TextIOBase):
    """``sys.stdout``/``sys.stderr`` stand-in that sends each thread's text to its own buffer.

    Dask workers run jobs in threads; ``contextlib.redirect_stdout`` would mix them up.
    """

    def __init__(self, default):
        self._default = default
        self._local = threading.local()

    def _target(self):
        return getattr(self._local, "target", None) or self._default

    @property
    def encoding(self) -> str:  # click checks the encoding of the stream it writes to
        return "utf-8"

    @property
    def errors(self) -> str:
        return "replace"

    def write(self, s: str) -> int:
        return self._target().write(s)

    def flush(self) -> None:
        self._target().flush()

    def isatty(self) -> bool:
        return False

    def writable(self) -> bool:
        return True


_router_lock = threading.Lock()
_router_users = 0
_router_saved: tuple[Any, Any] | None = None


@contextmanager
def _captured(buf: io.StringIO) -> Iterator[None]:
    """Send what this thread prints (stdout and stderr) to ``buf``."""
    global _router_users, _router_saved
    with _router_lock:
        if _router_users == 0:
            _router_saved = (sys.stdout, sys.stderr)
            sys.stdout, sys.stderr = _ThreadRouter(sys.stdout), _ThreadRouter(sys.stderr)
        _router_users += 1
        routers = (sys.stdout, sys.stderr)
    for r in routers:
        if isinstance(r, _ThreadRouter):
            r._local.target = buf
    try:
        yield
    finally:
        for r in routers:
            if isinstance(r, _ThreadRouter):
                r._local.target = None
        with _router_lock:
            _router_users -= 1
            if _router_users == 0 and _router_saved is not None:
                if sys.stdout is routers[0] and sys.stderr is routers[1]:
                    sys.stdout, sys.stderr = _router_saved
                _router_saved = None


class _JobFailed(Exception):
    """A job ended without an exception we can report as is (usage error, exit code)."""


def _one_line(text: str) -> str:
    return " ".join(str(text).split()) or "(no message)"


def run_job(payload: dict) -> dict:
    """Run one job in this process (the worker side; picklable for any executor).

    Parameters
    ----------
    payload : dict
        Built by the runner: ``command``, ``part`` (display name), ``part_name``,
        ``part_bytes``, ``argv``, ``inputs`` (list of ``[index, name, bytes, display]``)
        and ``version``.

    Returns
    -------
    dict
        ``status`` ("ok"/"failed"), ``result`` (JSON text or None), ``error`` (one line
        or None), ``started``, ``finished`` (Unix time, s), ``seconds``. Exceptions of
        the command are recorded, never raised.
    """
    started, t0 = time.time(), time.perf_counter()
    status, result, error = "failed", None, None
    names: dict[str, str] = {}
    try:
        result = _execute(payload, names)
        status = "ok"
    except (DeformClosureError, _JobFailed) as err:
        error = str(err)
    except KeyboardInterrupt:
        raise
    except SystemExit as err:
        error = f"the command exited with code {err.code}"
    except BaseException as err:  # noqa: BLE001 - a job's failure must not stop the batch
        error = f"{type(err).__name__}: {err}"
    if error is not None:
        # The worker ran on private copies: name the user's files in the message.
        for tmp, shown in sorted(names.items(), key=lambda kv: -len(kv[0])):
            error = error.replace(tmp, shown)
        error = _one_line(error)
    return {"status": status, "result": result, "error": error, "started": started,
            "finished": time.time(), "seconds": time.perf_counter() - t0}


def _execute(payload: dict, names: dict[str, str]) -> str | None:
    import click

    from ..cli.common import INPUTS
    from ..cli.main import cli

    if payload["version"] != _version():
        raise _JobFailed(f"the worker runs deformclosure {_version()} but the batch "
                         f"{payload['version']}; install the same version on every worker")
    with tempfile.TemporaryDirectory(prefix="deformclosure-job-") as tmp:
        tmp = Path(tmp)
        part = tmp / "part" / payload["part_name"]
        part.parent.mkdir()
        part.write_bytes(payload["part_bytes"])
        names[str(part)] = payload["part"]
        argv = list(payload["argv"])
        files = [str(part)]
        for j, (index, name, data, shown) in enumerate(payload["inputs"]):
            f = tmp / f"input{j}" / name
            f.parent.mkdir()
            f.write_bytes(data)
            argv[index] = str(f)
            names[str(f)] = shown
            files.append(str(f))
        report = tmp / "report.json"
        buf = io.StringIO()
        token = INPUTS.set(tuple(files))    # the report's provenance: the job's own inputs
        with _captured(buf):
            try:
                rv = cli.main(args=[payload["command"], str(part), *argv, "-o", str(report)],
                              prog_name="deformclosure", standalone_mode=False)
            except click.exceptions.Exit as err:
                rv = err.exit_code
            except click.ClickException as err:
                raise _JobFailed(err.format_message()) from None
            finally:
                INPUTS.reset(token)
        if rv not in (None, 0):
            lines = [ln for ln in buf.getvalue().splitlines() if ln.strip()]
            raise _JobFailed(lines[-1] if lines else f"the command returned exit code {rv}")
        if not report.exists():
            return None
        data = json.loads(report.read_text())
    return json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _payload(job: Job, version: str) -> dict:
    """Read the job's files for a worker; check they did not change since the key."""
    data = Path(job.path).read_bytes()
    if _sha256(data) != job.digest:
        raise _JobFailed(f"{job.part}: the file changed after the batch started; run the batch again")
    inputs = []
    for index, path, digest in job.inputs:
        b = Path(path).read_bytes()
        if _sha256(b) != digest:
            raise _JobFailed(f"{path}: the file changed after the batch started; run the batch again")
        inputs.append([index, Path(path).name, b, job.argv[index]])
    return {"command": job.command, "part": job.part, "part_name": Path(job.path).name,
            "part_bytes": data, "argv": list(job.argv), "inputs": inputs, "version": version}


# --------------------------------------------------------------------------- executors


#: One BLAS thread per worker process, as Dask's nanny sets for its workers: N worker
#: processes then use N cores without oversubscription, and every scheduler sums in the
#: same order, so a job gives the same bits on the local pool and on a Dask cluster.
_WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
               "VECLIB_MAXIMUM_THREADS": "1"}


@contextmanager
def _worker_environ() -> Iterator[None]:
    """Set :data:`_WORKER_ENV` for the processes started inside; restore it afterwards."""
    saved = {k: os.environ.get(k) for k in _WORKER_ENV}
    os.environ.update(_WORKER_ENV)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _mp_context():
    # forkserver: workers fork from a clean server that has already imported the package
    # (fork from a parent with threads is unsafe; spawn re-imports numpy/scipy per worker).
    if "forkserver" in multiprocessing.get_all_start_methods():
        from multiprocessing import forkserver

        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["deformclosure.planning.batch", "deformclosure.cli.main"])
        with _worker_environ():  # the server (and so every worker) has one BLAS thread
            forkserver.ensure_running()
        return ctx
    return multiprocessing.get_context("spawn")  # pragma: no cover - Windows, macOS


def _watch_parent(pid: int) -> None:
    """Worker initializer: exit when the batch process ``pid`` is gone.

    Pool workers wait on a queue the killed parent can no longer close (they hold its
    write end themselves), so after ``kill -9`` of the batch they would live on.
    """
    try:  # a pidfd cannot be fooled by the reuse of the PID (Linux >= 5.3)
        fd = os.pidfd_open(pid)
    except (AttributeError, OSError):
        fd = None

    def watch() -> None:
        import select

        while True:
            if fd is not None:
                if select.select([fd], [], [], 5.0)[0]:
                    os._exit(1)
                continue
            time.sleep(1.0)
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                os._exit(1)
            except PermissionError:  # pragma: no cover - alive, another user's process
                pass

    threading.Thread(target=watch, name="deformclosure-watch-batch", daemon=True).start()


class _Inline:
    """Run jobs in the calling process, one at a time."""

    def capacity(self) -> int:
        return 1

    def submit(self, payload: dict) -> cf.Future:
        fut: cf.Future = cf.Future()
        fut.set_result(run_job(payload))
        return fut

    def wait(self, futures):
        return set(futures)

    def close(self, cancel: bool = False) -> None:
        pass


class _Processes:
    """A local process pool; a worker that dies (crash, out of memory) is survived."""

    def __init__(self, workers: int):
        self.workers = workers
        self.env = _worker_environ()  # for spawned workers: set while the pool lives
        self.env.__enter__()
        self.ctx = _mp_context()
        self.pool = self._pool(workers)
        self.fn = run_job  # the worker function (a test may swap it)

    def _pool(self, n: int) -> cf.ProcessPoolExecutor:
        return cf.ProcessPoolExecutor(n, mp_context=self.ctx, initializer=_watch_parent,
                                      initargs=(os.getpid(),))

    def capacity(self) -> int:
        # Few jobs in flight: a pool that breaks takes only these down with it.
        return 2 * self.workers

    def submit(self, payload: dict) -> cf.Future:
        return self.pool.submit(self.fn, payload)

    def wait(self, futures):
        return cf.wait(futures, return_when=cf.FIRST_COMPLETED).done

    def wait_all(self, futures):
        return cf.wait(futures).done

    def restart(self) -> None:
        self.pool.shutdown(wait=False, cancel_futures=True)
        self.pool = self._pool(self.workers)

    def run_isolated(self, payload: dict) -> dict:
        """Run one job alone in a fresh process: only its own crash can break it."""
        with self._pool(1) as pool:
            try:
                return pool.submit(self.fn, payload).result()
            except cf.process.BrokenProcessPool:
                now = time.time()
                return {"status": "failed", "result": None, "started": now, "finished": now,
                        "seconds": 0.0, "error": "the worker process died while running this "
                        "job (crash or out of memory)"}

    def close(self, cancel: bool = False) -> None:
        try:
            self.pool.shutdown(wait=not cancel, cancel_futures=cancel)
        finally:
            self.env.__exit__(None, None, None)


class _Dask:
    """A Dask cluster reached through its scheduler (or a given ``distributed.Client``)."""

    def __init__(self, scheduler: Any, workers: int | None):
        import distributed

        self.distributed = distributed
        self.own = isinstance(scheduler, str)
        if self.own:
            try:
                self.client = distributed.Client(scheduler, timeout="20s", set_as_default=False)
            except (OSError, TimeoutError, ValueError) as err:
                raise BatchError(f"--scheduler {scheduler}: cannot connect to the Dask "
                                 f"scheduler ({_one_line(str(err)) or type(err).__name__})") from None
        else:
            self.client = scheduler
        self.workers = workers

    def capacity(self) -> int:
        if self.workers:
            return self.workers
        return max(2, 2 * sum(self.client.nthreads().values()))

    def submit(self, payload: dict):
        return self.client.submit(run_job, payload, pure=False,
                                  key=f"deformclosure-job-{uuid.uuid4().hex}")

    def wait(self, futures):
        with self.client.as_current():  # wait() looks up "the" client; ours is not the default
            return self.distributed.wait(futures, return_when="FIRST_COMPLETED").done

    def close(self, cancel: bool = False) -> None:
        if self.own:
            self.client.close()


def _check_scheduler(scheduler: Any, workers: int | None) -> None:
    """Reject a bad scheduler or worker count before anything else is done."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise BatchError(f"--workers = {workers!r}: must be a whole number >= 1")
    if isinstance(scheduler, str):
        if scheduler in ("processes", "inline") or "://" in scheduler:
            return
    elif hasattr(scheduler, "submit") and hasattr(scheduler, "nthreads"):
        return
    raise BatchError(f"--scheduler {scheduler!r}: choose 'processes', 'inline' or a Dask "
                     "scheduler address such as tcp://host:8786")


def _executor(scheduler: Any, workers: int | None, n_jobs: int):
    _check_scheduler(scheduler, workers)
    if scheduler == "processes":
        n = workers or (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                        else os.cpu_count() or 1)
        return _Processes(max(1, min(n, n_jobs)))
    if scheduler == "inline":
        return _Inline()
    return _Dask(scheduler, workers)


# --------------------------------------------------------------------------- results file


def _connect(db_path: str | os.PathLike, create: bool) -> sqlite3.Connection:
    p = Path(db_path)
    if not create and not p.is_file():
        raise BatchError(f"{db_path}: results file not found")
    if create and not p.parent.is_dir():
        raise BatchError(f"{db_path}: folder {p.parent} does not exist")
    try:
        conn = sqlite3.connect(str(p), timeout=60.0)
        if create:
            # WAL: a commit is one append to the log, and a killed writer leaves the file
            # consistent; FULL: a committed row also survives a power cut.
            conn.execute("PRAGMA journal_mode=WAL")
            conn.execute("PRAGMA synchronous=FULL")
            with conn:
                conn.execute(SCHEMA)
        cols = [r[1] for r in conn.execute("PRAGMA table_info(jobs)")]
    except sqlite3.DatabaseError as err:
        raise BatchError(f"{db_path}: not a deformclosure results file ({err})") from None
    if tuple(cols) != _COLUMNS:
        conn.close()
        raise BatchError(f"{db_path}: not a deformclosure results file (no table jobs with "
                         f"columns {', '.join(_COLUMNS)})")
    return conn


_UPSERT = f"""INSERT INTO jobs ({', '.join(_COLUMNS)}) VALUES ({', '.join('?' * len(_COLUMNS))})
ON CONFLICT(key) DO UPDATE SET {', '.join(f'{c} = excluded.{c}' for c in _COLUMNS[1:])}
WHERE jobs.status != 'ok'"""


def _store(conn: sqlite3.Connection, job: Job, out: dict, version: str) -> None:
    """Commit one finished job in its own transaction (never overwrites an ok row)."""
    row = (job.key, job.part, job.command, json.dumps(list(job.options)), out["status"],
           out["result"], out["error"], out["started"], out["finished"], out["seconds"], version)
    with conn:
        conn.execute(_UPSERT, row)


def _failed(error: str) -> dict:
    now = time.time()
    return {"status": "failed", "result": None, "error": _one_line(error), "started": now,
            "finished": now, "seconds": 0.0}


# --------------------------------------------------------------------------- runner


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


def run_batch(jobs: Sequence[Job] | str | os.PathLike, db_path: str | os.PathLike,
              scheduler: Any = "processes", workers: int | None = None,
              retry_failed: bool = False, progress: bool = True) -> BatchSummary:
    """Run the jobs not yet in the results file; commit each one as it finishes.

    Parameters
    ----------
    jobs : sequence of Job, or path-like
        Jobs from :func:`load_jobs`, or a folder / job list to load with its defaults.
    db_path : path-like
        SQLite results file, created if missing (table :data:`SCHEMA`).
    scheduler : str or distributed.Client
        ``"processes"`` (local process pool), ``"inline"`` (this process, one job at a
        time) or a Dask scheduler address ``"tcp://host:port"`` (or a connected client).
    workers : int, optional
        Local pool size (default: the CPUs this process may use, at most one per job);
        with Dask, the most jobs in flight at once (default: twice the cluster's threads).
    retry_failed : bool
        Run again the jobs recorded as failed (default: keep them).
    progress : bool
        Show a progress bar (tqdm, on stderr).

    Returns
    -------
    BatchSummary

    Raises
    ------
    BatchError
        Bad jobs, results file or scheduler. A job's own failure is never raised: it is
        recorded with ``status = "failed"`` and its one-line message.

    Notes
    -----
    Only this process writes the results file, one transaction per finished job, so a
    run killed at any moment keeps every finished job, and the next run skips them
    (SPEC §5, "Batch"). On a local pool, a worker process that dies takes down the jobs
    in flight; each of them is run again alone, and the one that kills its process
    again is recorded as failed.
    """
    from tqdm import tqdm

    t0 = time.perf_counter()
    if isinstance(jobs, (str, os.PathLike)):
        jobs = load_jobs(jobs)
    jobs = list(jobs)
    if not all(isinstance(j, Job) for j in jobs):
        raise BatchError("jobs: expected Job objects from load_jobs() or a folder/list path")
    _check_scheduler(scheduler, workers)
    version = _version()
    unique: dict[str, Job] = {}
    for j in jobs:
        unique.setdefault(j.key, j)
    conn = _connect(db_path, create=True)
    try:
        status = {k: s for k, s in conn.execute("SELECT key, status FROM jobs")
                  if k in unique}
        todo = deque(j for k, j in unique.items()
                     if k not in status or (retry_failed and status[k] == "failed"))
        n_run = len(todo)
        ex = _executor(scheduler, workers, n_run) if todo else None
        bar = tqdm(total=n_run, disable=not progress or n_run == 0, unit="job", desc="batch",
                   file=sys.stderr, dynamic_ncols=True)
        n_bad = 0

        def store(job: Job, out: dict) -> None:
            nonlocal n_bad
            _store(conn, job, out, version)
            status[job.key] = "ok" if out["status"] == "ok" else status.get(job.key, "failed")
            n_bad += out["status"] != "ok"
            bar.update(1)
            if n_bad:
                bar.set_postfix(failed=n_bad, refresh=False)

        try:
            if ex is not None:
                _drive(ex, todo, store, version)
        except BaseException:
            if ex is not None:
                ex.close(cancel=True)
            raise
        else:
            if ex is not None:
                ex.close()
        finally:
            bar.close()
        failures = []
        if any(status.get(k) == "failed" for k in unique):
            rows = {r[0]: r for r in conn.execute(
                "SELECT key, part, command, options, error FROM jobs WHERE status = 'failed'")}
            failures = [{"part": rows[k][1], "command": rows[k][2],
                         "options": json.loads(rows[k][3]), "error": rows[k][4]}
                        for k in unique if k in rows]
    finally:
        conn.close()
    n_ok = sum(status.get(k) == "ok" for k in unique)
    return BatchSummary(db_path=str(db_path), n_jobs=len(unique),
                        n_duplicates=len(jobs) - len(unique), n_run=n_run,
                        n_skipped=len(unique) - n_run, n_ok=n_ok, n_failed=len(failures),
                        seconds=time.perf_counter() - t0, failures=tuple(failures))


def _drive(ex, todo: deque, store, version: str) -> None:
    """Keep the executor busy; hand each finished job to ``store`` as it arrives."""
    inflight: dict[Any, Job] = {}
    while todo or inflight:
        while todo and len(inflight) < ex.capacity():
            job = todo.popleft()
            try:
                payload = _payload(job, version)
            except (OSError, _JobFailed) as err:
                store(job, _failed(str(err) if isinstance(err, _JobFailed)
                                   else f"{job.part}: cannot read ({err.strerror or err})"))
                continue
            inflight[ex.submit(payload)] = job
        if not inflight:
            continue
        suspects = []
        for fut in ex.wait(list(inflight)):
            job = inflight.pop(fut)
            try:
                out = fut.result()
            except cf.process.BrokenProcessPool:
                suspects.append(job)
                continue
            except Exception as err:  # noqa: BLE001 - e.g. distributed's KilledWorker
                out = _failed(f"{type(err).__name__}: {err}")
            store(job, out)
        if suspects:
            # A worker process died: every job in flight fails with BrokenProcessPool.
            # Collect them all, then run each alone so only the culprit is recorded failed.
            for fut in ex.wait_all(list(inflight)):
                job = inflight.pop(fut)
                try:
                    store(job, fut.result())
                except cf.process.BrokenProcessPool:
                    suspects.append(job)
            ex.restart()
            for job in suspects:
                try:
                    store(job, ex.run_isolated(_payload(job, version)))
                except (OSError, _JobFailed) as err:
                    store(job, _failed(str(err)))


# --------------------------------------------------------------------------- reading


def read_results(db_path: str | os.PathLike, status: str | None = None) -> list[dict]:
    """Rows of a results file, sorted by part, command and options.

    Parameters
    ----------
    db_path : path-like
        Results file written by :func:`run_batch`.
    status : {"ok", "failed"}, optional
        Only rows with this status.

    Returns
    -------
    list of dict
        One dict per job with the columns of :data:`SCHEMA`; ``options`` is a list and
        ``result`` the parsed JSON report (``None`` for a failed job).

    Raises
    ------
    BatchError
        Missing file, or not a results file.
    """
    if status not in (None, "ok", "failed"):
        raise BatchError(f"status = {status!r}: choose 'ok', 'failed' or None")
    conn = _connect(db_path, create=False)
    try:
        sql = f"SELECT {', '.join(_COLUMNS)} FROM jobs"
        rows = conn.execute(sql + (" WHERE status = ?" if status else ""),
                            (status,) if status else ()).fetchall()
    except sqlite3.DatabaseError as err:
        raise BatchError(f"{db_path}: cannot read results ({err})") from None
    finally:
        conn.close()
    out = []
    for r in rows:
        d = dict(zip(_COLUMNS, r))
        d["options"] = json.loads(d["options"])
        d["result"] = None if d["result"] is None else json.loads(d["result"])
        out.append(d)
    out.sort(key=lambda d: (d["part"], d["command"], d["options"], d["key"]))
    return out


#: Scalar fields of the reports shown by ``results`` (SI units, SPEC §5).
_SCALARS = ("model", "verdict", "sigma_star", "quality", "U_A", "U_L", "sigma_L",
            "deform_closure", "order", "energy")
_FIELDS = (*_SCALARS, "n_pairs", "top_a", "top_b", "n_axes", "top_angle", "top_point",
           "top_sigma_star", "top_quality", "n_nodes", "n_triangles")


def result_summary(result: dict | None) -> dict:
    """The key scalar fields of a job's JSON report, flat.

    Parameters
    ----------
    result : dict or None
        A report of ``optimize`` (``model``, ``verdict``, ``sigma_star``, ``quality``,
        ``U_A``, ``U_L``, ``sigma_L``), ``check`` (``deform_closure``, ``order``,
        ``energy``), ``plan`` (paper: ``n_pairs`` and the best pair: ``top_a``, ``top_b``,
        ``top_sigma_star``, ``top_quality``; pads: ``n_axes`` and the best axis:
        ``top_angle`` (rad), ``top_point`` ("x y", m), ``top_sigma_star``, ``top_quality``)
        or ``mesh`` (``n_nodes``, ``n_triangles``).

    Returns
    -------
    dict
        The fields present, SI units (m, J).
    """
    if not isinstance(result, dict):
        return {}
    out = {k: result[k] for k in _SCALARS if k in result and not isinstance(result[k], (dict, list))}
    axes = result.get("axes")
    if isinstance(axes, list):                   # a pad plan: grasp axes, best first
        out["n_axes"] = len(axes)
        if axes and isinstance(axes[0], dict):
            top = axes[0]
            out.update(top_angle=top.get("angle"), top_sigma_star=top.get("sigma_star"),
                       top_quality=top.get("quality"))
            if isinstance(top.get("point"), list):
                out["top_point"] = " ".join(f"{v:.6g}" for v in top["point"])
    pairs = result.get("pairs")
    if isinstance(pairs, list):
        out["n_pairs"] = len(pairs)
        if pairs and isinstance(pairs[0], dict):
            top = pairs[0]
            out.update(top_a=top.get("a"), top_b=top.get("b"),
                       top_sigma_star=top.get("sigma_star"), top_quality=top.get("quality"))
    if isinstance(result.get("nodes"), list) and isinstance(result.get("triangles"), list):
        out.update(n_nodes=len(result["nodes"]), n_triangles=len(result["triangles"]))
    return out


def _describe(row: dict) -> str:
    if row["status"] != "ok":
        return f"error: {row['error']}"
    s = result_summary(row["result"])
    g = lambda v, u="": "-" if v is None else (f"{v:.4g}{u}" if isinstance(v, float) else f"{v}{u}")  # noqa: E731
    if "n_axes" in s:
        if "top_angle" not in s:
            return f"{s['n_axes']} axes"
        return (f"best axis {math.degrees(s['top_angle']):.1f} deg through ({s.get('top_point')}) m "
                f"sigma*={g(s['top_sigma_star'], ' m')} Q={g(s['top_quality'], ' J')} "
                f"({s['n_axes']} axes)")
    if "top_quality" in s or "n_pairs" in s:
        if "top_a" not in s:
            return f"{s['n_pairs']} pairs"
        return (f"best {s['top_a']}-{s['top_b']} sigma*={g(s['top_sigma_star'], ' m')} "
                f"Q={g(s['top_quality'], ' J')} ({s['n_pairs']} pairs)")
    if "sigma_star" in s or "quality" in s:
        v = f" {s['verdict']}" if "verdict" in s else ""
        return f"sigma*={g(s.get('sigma_star'), ' m')} Q={g(s.get('quality'), ' J')}{v}"
    if "deform_closure" in s:
        return f"deform closure: {'yes' if s['deform_closure'] else 'no'}, order {s.get('order')}"
    if "n_nodes" in s:
        return f"{s['n_nodes']} nodes, {s['n_triangles']} triangles"
    return "ok"


def format_results(rows: Sequence[dict], fmt: str = "table") -> str:
    """Render rows of :func:`read_results` as a text table, CSV or JSON.

    Parameters
    ----------
    rows : sequence of dict
    fmt : {"table", "csv", "json"}
        ``table``: one line per job (part, command, status, key figures, seconds) and a
        count. ``csv``: the columns of the results file except ``result``, with
        ``options`` shell-quoted and the key fields of :func:`result_summary`.
        ``json``: a list of the full rows, reports included.

    Returns
    -------
    str
    """
    if fmt == "json":
        return json.dumps(list(rows), indent=2, allow_nan=False)
    if fmt == "csv":
        fields = [f for f in _FIELDS if any(f in result_summary(r["result"]) for r in rows)]
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        cols = [c for c in _COLUMNS if c != "result"]
        w.writerow(cols + fields)
        for r in rows:
            s = result_summary(r["result"])
            w.writerow([shlex.join(r[c]) if c == "options" else r[c] for c in cols]
                       + [s.get(f) for f in fields])
        return buf.getvalue()
    if fmt != "table":
        raise BatchError(f"format = {fmt!r}: choose 'table', 'csv' or 'json'")
    if not rows:
        return "no jobs"
    table = [(r["part"], " ".join([r["command"], *r["options"]]), r["status"],
              "-" if r["seconds"] is None else f"{r['seconds']:.2f}", _describe(r)) for r in rows]
    head = ("part", "command", "status", "seconds", "result (SI units)")
    wid = [min(48, max(len(t[i]) for t in [head, *table])) for i in range(4)]

    def fmt_row(t):
        cells = [f"{t[i][:wid[i]]:<{wid[i]}}" if i != 3 else f"{t[i]:>{wid[i]}}" for i in range(4)]
        return "  ".join(cells + [t[4]])

    n_bad = sum(r["status"] != "ok" for r in rows)
    lines = [fmt_row(head), *(fmt_row(t) for t in table),
             f"{len(rows)} job{'s' * (len(rows) != 1)}: {len(rows) - n_bad} ok, {n_bad} failed"]
    return "\n".join(line.rstrip() for line in lines)
