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
    and output options (``--plot``, ``--export-graph``, ``--quiet``, ``--verbose``) are
    not part of the key: moving or renaming a catalogue keeps its results, and two files
    with the same bytes are one job.

Schedulers
    ``"processes"`` (a local process pool, the default), ``"inline"`` (the calling
    process, one job at a time; for debugging) or the address of a Dask scheduler
    (``"tcp://host:8786"``) or a :class:`distributed.Client`. Workers receive the file
    bytes, not paths, so a cluster needs no shared file system, only the same version
    of deformclosure.

Results file
    An SQLite database marked as ours (``PRAGMA application_id`` = :data:`APPLICATION_ID`,
    table ``meta`` with ``format`` = ``deformclosure-results/1``), created atomically
    (written beside the target and renamed onto it) so it exists complete or not at all.
    Any other file — text, or another program's SQLite database — is refused unchanged.
    Table ``jobs`` (one row per job)::

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

    Table ``job_lists`` holds the identity of every job list run into the file (sha256 of
    its sorted job keys without the version): a different list is refused unless
    ``append=True`` (``--append``), so two catalogues never mix by mistake.

Hostile inputs
    A job list is untrusted text: fields of at most :data:`MAX_FIELD` characters, no NUL,
    and every file it names inside its own folder (symbolic links resolved) unless
    ``allow_outside``. The results file, the scheduler and write access are all checked
    before any job runs, and the file is only created once the run can start. Stored rows
    are read by the strict JSON rules; a bad one is "unreadable", never a traceback.
    Ctrl-C: workers ignore SIGINT, the parent stops them and raises
    :class:`BatchInterrupted`. Each job's private folder lives in one folder per run
    (``deformclosure-run-<pid>-<hex>`` in the temporary folder, with a marker), removed
    at the end; those of killed runs are removed by the next run on the host.

Examples
--------
>>> from deformclosure.planning import load_jobs, run_batch, read_results
>>> jobs = load_jobs("examples", command="mesh")                # doctest: +SKIP
>>> summary = run_batch(jobs, "results.sqlite", workers=2)       # doctest: +SKIP
>>> [(r["part"], r["status"]) for r in read_results("results.sqlite")]  # doctest: +SKIP
"""

from __future__ import annotations

import concurrent.futures as cf
import csv
import hashlib
import io
import json
import math
import multiprocessing
import os
import re
import shlex
import shutil
import signal
import socket
import sqlite3
import stat
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

#: Commands that cannot be a job (they run batches or need no input file).
_NOT_JOBS = frozenset({"batch", "results", "demo"})
#: Parameters that name outputs or only change what is printed: not part of the key.
_OUTPUT_PARAMS = frozenset({"output", "plot", "export_graph", "export_fields", "quiet",
                            "verbose"})
#: Options taking a file or inline JSON (``--material``): a file is an input of the job.
_FILE_OR_JSON = frozenset({"material"})
#: Options the runner sets itself.
_RESERVED = ("-o", "--output", "-h", "--help")
#: Suffixes meshio knows that are too generic to mean "a mesh" in a folder of parts.
_AMBIGUOUS_SUFFIXES = frozenset({".dat", ".xml", ".svg", ".wkt", ".node", ".ele", ".txt"})
#: Longest field of a job list (a path, a command, the options), in characters.
MAX_FIELD = 4096

#: ``PRAGMA application_id`` of a results file ("DCLR"): how we recognise our own files.
APPLICATION_ID = 0x44434C52
#: ``PRAGMA user_version`` of the current results-file layout.
_SCHEMA_VERSION = 1
_FORMAT = "deformclosure-results/1"
_SQLITE_MAGIC = b"SQLite format 3\x00"

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
_META_SCHEMA = "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT)"
_LISTS_SCHEMA = """CREATE TABLE IF NOT EXISTS job_lists (
    identity TEXT PRIMARY KEY,
    n_jobs INTEGER,
    source TEXT,
    added REAL
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
    ident : str
        The key without the package version: what identifies the job in a job list
        (see :func:`run_batch`, ``append``). Empty for a hand-made Job (then ``key``).
    """

    part: str
    command: str
    options: tuple[str, ...]
    key: str
    path: str
    argv: tuple[str, ...]
    inputs: tuple[tuple[int, str, str], ...]
    digest: str
    ident: str = ""

    @classmethod
    def from_spec(cls, part: str | os.PathLike, command: str = "plan",
                  options: Sequence[str] | str = (), base_dir: str | os.PathLike | None = None,
                  where: str | None = None, root: str | os.PathLike | None = None,
                  options_root: str | os.PathLike | None = None) -> Job:
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
        root : path-like, optional
            Folder the part file must lie in, symbolic links resolved (default: anywhere).
        options_root : path-like, optional
            Folder every file named by an option (read or written) must lie in.

        Raises
        ------
        BatchError
            Unknown command, bad options, ``-o`` among the options, missing file, a
            field with a NUL character or longer than :data:`MAX_FIELD`, a file outside
            ``root`` / ``options_root``.
        """
        where = f"{where}: " if where else ""
        part_str = os.fspath(part) if isinstance(part, os.PathLike) else part
        if not isinstance(part_str, str):
            raise BatchError(f"{where}part: must be a file path (string)")
        _check_field(where, "part", part_str)
        if isinstance(command, str):
            _check_field(where, "command", command)
        if isinstance(options, str):
            _check_field(where, "options", options)
            try:
                options = shlex.split(options)
            except ValueError as err:
                raise BatchError(f"{where}options {options!r}: {err}") from None
        options = tuple(str(o) for o in options)
        for i, o in enumerate(options):
            _check_field(where, f"options[{i}]", o)
        base = Path(base_dir) if base_dir is not None else Path.cwd()
        root_p = _resolve(Path(root), where, "job list folder") if root is not None else None
        opt_root = (_resolve(Path(options_root), where, "job list folder")
                    if options_root is not None else None)
        cmd = _command(command, where)
        argv, inputs, params = _parse_options(cmd, command, part_str, options, base, where,
                                              opt_root)
        p = Path(part_str)
        path = p if p.is_absolute() else base / p
        real = _resolve(path, where, f"part {part_str!r}")
        if root_p is not None and not _inside(real, root_p):
            raise BatchError(f"{where}part {part_str!r}: outside the job list's folder "
                             f"{root_p}; move the file into it, or pass --allow-outside "
                             "(allow_outside=True) if you trust this job list")
        try:
            found = path.is_file()
        except OSError as err:
            raise BatchError(f"{where}part {part_str!r}: cannot read ({err.strerror or err})") from None
        if not found:
            raise BatchError(f"{where}part {part_str!r}: file not found "
                             f"(relative paths are relative to {base})")
        digest = _digest(path, where, f"part {part_str!r}")
        display = part_str if p.is_absolute() or base_dir is None else str(Path(base_dir) / p)
        key = job_key(digest, command, params)
        return cls(part=display, command=command, options=options, key=key,
                   path=str(real), argv=argv, inputs=inputs, digest=digest,
                   ident=_job_ident(digest, command, params))


def _check_field(where: str, name: str, value: str) -> None:
    """Refuse a NUL character or an over-long field of a job (one line naming it)."""
    if "\x00" in value:
        raise BatchError(f"{where}{name}: contains a NUL character; a job list holds text "
                         "only (paths, a command, options) — fix or re-save the list")
    if len(value) > MAX_FIELD:
        raise BatchError(f"{where}{name}: {len(value)} characters, more than the {MAX_FIELD} "
                         "a job-list field may have; shorten it")


def _resolve(path: Path, where: str, what: str) -> Path:
    """``path`` with symbolic links resolved; one-line error for a loop or a bad name."""
    try:
        return path.resolve()
    except (OSError, RuntimeError) as err:
        reason = getattr(err, "strerror", None) or str(err)
        raise BatchError(f"{where}{what}: cannot resolve the path ({reason})") from None


def _inside(path: Path, root: Path) -> bool:
    return path == root or root in path.parents


def _digest(path: Path, where: str, what: str) -> str:
    """sha256 of a regular input file of bounded size; one-line errors."""
    from ..jsonfile import check_input_file

    try:
        check_input_file(path, BatchError, "input file")
        return _sha256(path.read_bytes())
    except BatchError as err:
        raise BatchError(f"{where}{what}: {err}") from None
    except OSError as err:
        raise BatchError(f"{where}{what}: cannot read ({err.strerror or err})") from None


def _command(name: str, where: str):
    """The click command ``name``, checked to be a job command."""
    from ..cli.main import cli

    choices = sorted(set(cli.commands) - _NOT_JOBS)
    if not isinstance(name, str) or name not in choices:
        shown = repr(name) if not isinstance(name, str) or len(name) < 80 else repr(name[:80] + "...")
        raise BatchError(f"{where}command {shown}: not a job command; choose one of "
                         f"{', '.join(choices)}")
    return cli.commands[name]


def _parse_options(cmd, command: str, part: str, options: tuple[str, ...], base: Path,
                   where: str, root: Path | None = None
                   ) -> tuple[tuple[str, ...], tuple[tuple[int, str, str], ...], dict]:
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
        if isinstance(prm, click.Option) and (isinstance(prm.type, click.Path)
                                              or prm.name in _FILE_OR_JSON):
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
        if prm.name in _FILE_OR_JSON and argv[i + 1].lstrip().startswith("{"):
            continue                                # inline JSON: part of the options
        f = Path(argv[i + 1])
        f = _resolve(f if f.is_absolute() else base / f, where, argv[i])
        if root is not None and not _inside(f, root):
            raise BatchError(f"{where}{argv[i]} {argv[i + 1]!r}: outside the job list's folder "
                             f"{root}; keep the job's files in it, or pass --allow-outside "
                             "(allow_outside=True) if you trust this job list")
        argv[i + 1] = str(f)
        if prm.name in _OUTPUT_PARAMS:
            continue
        try:
            found = f.is_file()
        except OSError:
            found = False
        if not found:
            raise BatchError(f"{where}{argv[i]}: file not found ({f})")
        inputs.append((i + 1, str(f), _digest(f, where, argv[i])))
    try:
        ctx = cmd.make_context(command, [part, *argv], resilient_parsing=False)
    except click.ClickException as err:
        shown = shlex.join(options)
        shown = shown if len(shown) <= 200 else shown[:200] + "..."
        raise BatchError(f"{where}{command} {shown}: "
                         f"{_one_line(err.format_message())}") from None
    except click.exceptions.Exit:  # pragma: no cover - --help/--version are rejected above
        raise BatchError(f"{where}{command}: options {shlex.join(options)} only print") from None
    except DeformClosureError as err:  # an option's own check (a callback)
        raise BatchError(f"{where}{command}: {_one_line(str(err))}") from None
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


def _key_blob(digest: str, command: str, params: dict, version: str | None) -> bytes:
    d = {"part": digest, "command": command, "params": params}
    if version is not None:
        d["version"] = version
    return json.dumps(d, sort_keys=True, separators=(",", ":"), default=list).encode()


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
    return _sha256(_key_blob(digest, command, params, version or _version()))


def _job_ident(digest: str, command: str, params: dict) -> str:
    """The job's key without the version: the same job list keeps its identity across
    versions of the package."""
    return _sha256(_key_blob(digest, command, params, None))


def _list_identity(jobs: Sequence[Job]) -> str:
    """Identity of a job list: sha256 of its sorted, distinct job idents."""
    return _sha256("\n".join(sorted({j.ident or j.key for j in jobs})).encode())


def _folder_files(folder: Path) -> list[Path]:
    import meshio

    suffixes = tuple(sorted(set(meshio.extension_to_filetypes) - _AMBIGUOUS_SUFFIXES)) + (".json",)
    try:
        return sorted(f for f in folder.iterdir()
                      if f.is_file() and not f.name.startswith(".")
                      and f.name.lower().endswith(suffixes))
    except OSError as err:
        raise BatchError(f"{folder}: cannot list the folder ({err.strerror or err})") from None


def load_jobs(path: str | os.PathLike, command: str = "plan",
              options: Sequence[str] | str = (), allow_outside: bool = False) -> list[Job]:
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

        Paths in a list are relative to the list's folder, and must stay inside it
        (symbolic links resolved): ``../x.json`` or ``/etc/x`` in a list is refused
        unless ``allow_outside``. An entry without a command or options (a missing key,
        an empty CSV cell) gets ``command`` and ``options``. A field may not hold a NUL
        character nor be longer than :data:`MAX_FIELD` characters.
    command : str
        Default command (``"plan"``).
    options : sequence of str or str
        Default options (a string is split like a shell would). Being yours, not the
        list's, files they name may lie anywhere.
    allow_outside : bool
        Let a job list name files outside its folder (only for lists you trust).

    Returns
    -------
    list of Job
        In the order of the folder (sorted by name) or of the list.

    Raises
    ------
    BatchError
        Missing folder or list, unreadable or malformed list, empty batch, unknown
        command, bad options, missing part file, a path outside the list's folder.
    """
    p = Path(path)
    try:
        exists, is_dir = p.exists(), p.is_dir()
    except (OSError, ValueError) as err:
        raise BatchError(f"{path!r}: cannot read ({getattr(err, 'strerror', None) or err})") from None
    if not exists:
        raise BatchError(f"{path}: not found; give a folder of part/mesh files or a job list "
                         f"(.json or .csv)")
    if is_dir:
        files = _folder_files(p)
        if not files:
            raise BatchError(f"{path}: no part or mesh files in this folder")
        return [Job.from_spec(f.name, command, options, base_dir=p, where=str(f)) for f in files]
    suffix = p.suffix.lower()
    if suffix not in (".json", ".csv"):
        raise BatchError(f"{path}: a job list must be .json or .csv (or give a folder)")
    from ..jsonfile import read_text_file

    text = read_text_file(p, BatchError, "job list")
    specs = _json_specs(p, text) if suffix == ".json" else _csv_specs(p, text)
    if not specs:
        raise BatchError(f"{path}: the job list is empty")
    root = None if allow_outside else p.parent
    return [Job.from_spec(part, cmd or command, options if opts is None else opts,
                          base_dir=p.parent, where=where, root=root,
                          options_root=root if opts is not None else None)
            for where, part, cmd, opts in specs]


def _line_col(text: str, index: int) -> tuple[int, int]:
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def _json_specs(p: Path, text: str) -> list[tuple[str, str, str | None, Any]]:
    from ..jsonfile import parse_json

    if "\x00" in text:
        # A raw NUL is no JSON; name the entry and field if the list parses with it as
        # an escaped character, else its line and column.
        try:
            specs = _json_specs(p, text.replace("\x00", "\\u0000"))
        except BatchError:
            specs = None
        if specs is not None:
            for where, part, cmd, opts in specs:
                fields = [("part", part), ("command", cmd or ""), *(
                    [("options", opts)] if isinstance(opts, str) else
                    [(f"options[{i}]", o) for i, o in enumerate(opts or ())])]
                for name, value in fields:
                    if "\x00" in value:
                        _check_field(f"{where}: ", name, value)
        line, col = _line_col(text, text.index("\x00"))
        raise BatchError(f"{p}: line {line} column {col}: a NUL byte; a job list is text — "
                         "fix or re-save it")
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
            name = sorted(unknown)[0]
            shown = repr(name) if len(name) <= 80 and "\x00" not in name else "(a long or binary name)"
            raise BatchError(f"{where}: unknown key {shown} (keys: part, command, options)")
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


def _long_cell(text: str, start_line: int) -> int:
    """Column (0-based) of the first cell longer than :data:`MAX_FIELD` in the CSV record
    starting on line ``start_line`` (1-based), -1 if none."""
    pos = 0
    for _ in range(start_line - 1):
        nxt = text.find("\n", pos)
        if nxt < 0:
            return -1
        pos = nxt + 1
    col, length, quoted, i = 0, 0, False, pos
    while i < len(text):
        c = text[i]
        if quoted:
            if c == '"':
                if text.startswith('"', i + 1):
                    length += 1
                    i += 1
                else:
                    quoted = False
            else:
                length += 1
        elif c == '"':
            quoted = True
        elif c == ",":
            col, length = col + 1, 0
        elif c == "\n":
            return -1
        else:
            length += 1
        if length > MAX_FIELD:
            return col
        i += 1
    return -1


def _csv_specs(p: Path, text: str) -> list[tuple[str, str, str | None, Any]]:
    reader = csv.reader(io.StringIO(text))
    header: list[str] | None = None
    done_line = 0                                   # last line of the last record read
    specs = []

    def field_name(col: int) -> str:
        if header is not None and col < len(header) and header[col] in ("part", "command", "options"):
            return f"'{header[col]}'"
        return f"column {col + 1}"

    while True:
        try:
            row = next(reader)
        except StopIteration:
            break
        except csv.Error as err:
            line = done_line + 1
            col = _long_cell(text, line)
            if col >= 0:
                raise BatchError(f"{p}: line {line}: {field_name(col)}: more than the "
                                 f"{MAX_FIELD} characters a job-list field may have; "
                                 "shorten it") from None
            raise BatchError(f"{p}: line {line}: not valid CSV ({err}); fix the job list") from None
        start, done_line = done_line + 1, reader.line_num
        where = f"{p}: line {start}"
        for col, cell in enumerate(row):
            _check_field(f"{where}: ", field_name(col), cell)
        if header is None:
            if not row:
                continue
            header = [c.strip() for c in row]
            if "part" not in header or set(header) - {"part", "command", "options"} \
                    or len(set(header)) != len(header):
                got = ",".join(header)
                got = got if len(got) <= 80 else got[:80] + "..."
                raise BatchError(f"{p}: a CSV job list needs the header part,command,options "
                                 f"(got {got or 'nothing'})")
            continue
        cells = {name: row[i].strip() if i < len(row) else "" for i, name in enumerate(header)}
        extra = [c for c in row[len(header):] if c.strip()]
        if extra:
            raise BatchError(f"{where}: {len(row)} cells but the header has {len(header)}; "
                             "quote a cell that holds a comma (\"--at 0,10 12,10\")")
        if not any(cells.values()):
            continue
        if not cells.get("part"):
            raise BatchError(f"{where}: 'part' is empty")
        # An empty cell takes the default, as a missing key does in a JSON list.
        specs.append((where, cells["part"], cells.get("command") or None,
                      cells.get("options") or None))
    if header is None:
        raise BatchError(f"{p}: a CSV job list needs the header part,command,options "
                         "(got nothing)")
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
    with tempfile.TemporaryDirectory(prefix="job-", dir=_job_root(payload)) as tmp:
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
            except click.exceptions.Abort:
                # click turns Ctrl-C into Abort: it stops the batch, it is no job failure.
                raise KeyboardInterrupt from None
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


def _payload(job: Job, version: str, tmp_root: str | os.PathLike | None = None) -> dict:
    """Read the job's files for a worker; check they did not change since the key.

    ``tmp_root`` is the run's temporary folder; a worker on this host puts the job's
    private folder in it (elsewhere, in a folder of its own, see :func:`_job_root`).
    """
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
            "part_bytes": data, "argv": list(job.argv), "inputs": inputs, "version": version,
            "tmp_root": None if tmp_root is None else str(tmp_root), "host": _HOST}


# --------------------------------------------------------------------------- temporary folders
#
# Each job runs in a private folder (the copies of its input files, the report). They all
# live in one folder per run, ``deformclosure-run-<pid>-<hex>`` in the system's temporary
# folder, holding a marker file with the pid (and start time) of the process that made it.
# The run removes it when it ends; a run that was killed leaves it, and the next run on
# this host removes every such folder whose process is gone — only folders with our name,
# our marker, our user id and a dead pid.

_HOST = socket.gethostname()
_RUN_PREFIX = "deformclosure-run-"
_RUN_MARKER = ".deformclosure-run"
_RUN_NAME = re.compile(r"deformclosure-run-(\d+)-[0-9a-f]{8}\Z")
_process_run: tuple[int, Path] | None = None
_process_run_lock = threading.Lock()


def _proc_start(pid: int) -> str | None:
    """Start time of process ``pid`` (clock ticks since boot, Linux), or None."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as fh:
            return fh.read().rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return None


def _alive(pid: int, start: str | None) -> bool:
    """Whether process ``pid`` runs and is the one that started at ``start``."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError, OverflowError):
        return True                      # another user's process, or cannot tell: keep
    if start is not None:
        now = _proc_start(pid)
        if now is not None and now != start:
            return False                 # the pid was reused
    return True


def _make_run_dir(base: str | os.PathLike | None = None) -> Path:
    """A new per-run folder with its marker (pid, start time, host)."""
    base = Path(base if base is not None else tempfile.gettempdir())
    pid = os.getpid()
    while True:
        d = base / f"{_RUN_PREFIX}{pid}-{uuid.uuid4().hex[:8]}"
        try:
            d.mkdir(mode=0o700)
            break
        except FileExistsError:  # pragma: no cover - 32 random bits
            continue
    (d / _RUN_MARKER).write_text(json.dumps({"pid": pid, "start": _proc_start(pid),
                                             "host": _HOST}))
    return d


def _clean_stale_runs(base: str | os.PathLike | None = None) -> int:
    """Remove the run folders under ``base`` (default: the system's temporary folder)
    whose batch process is gone; never raises. Returns how many were removed."""
    base = Path(base if base is not None else tempfile.gettempdir())
    removed = 0
    try:
        entries = list(os.scandir(base))
    except OSError:
        return 0
    for e in entries:
        m = _RUN_NAME.match(e.name)
        if not m:
            continue
        try:
            if not e.is_dir(follow_symlinks=False):
                continue
            if hasattr(os, "getuid") and e.stat(follow_symlinks=False).st_uid != os.getuid():
                continue
            marker = Path(e.path, _RUN_MARKER)
            if marker.is_symlink():
                continue
            info = json.loads(marker.read_text(encoding="utf-8"))
            pid = info["pid"]
            if not isinstance(pid, int) or pid != int(m.group(1)) or info.get("host") != _HOST:
                continue
            start = info.get("start")
            if _alive(pid, start if isinstance(start, str) else None):
                continue
            shutil.rmtree(e.path, ignore_errors=True)
            removed += 1
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            continue
    return removed


def _job_root(payload: dict) -> Path:
    """Where a worker makes a job's private folder: the run's folder when it is on this
    host, else a run folder of this worker process (removed when the process exits)."""
    global _process_run
    root = payload.get("tmp_root")
    if root and payload.get("host") == _HOST and (Path(root) / _RUN_MARKER).is_file():
        return Path(root)
    with _process_run_lock:
        if _process_run is None or _process_run[0] != os.getpid() or not _process_run[1].is_dir():
            import atexit
            from multiprocessing import util

            _clean_stale_runs()
            d = _make_run_dir()
            atexit.register(shutil.rmtree, d, True)
            util.Finalize(None, shutil.rmtree, args=(d, True), exitpriority=0)
            _process_run = (os.getpid(), d)
        return _process_run[1]


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
    """Worker initializer: ignore Ctrl-C; exit when the batch process ``pid`` is gone.

    Ctrl-C reaches every process of the terminal's group: the batch process handles it
    (it stops the workers, says what is kept and exits 130), so workers ignore SIGINT
    rather than each printing a ``KeyboardInterrupt`` traceback.

    Pool workers wait on a queue the killed parent can no longer close (they hold its
    write end themselves), so after ``kill -9`` of the batch they would live on.
    """
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except (ValueError, OSError):  # pragma: no cover - not the main thread
        pass
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
        """Wait for the jobs in flight; with ``cancel``, stop the workers at once (their
        jobs are lost, not recorded: a later run does them)."""
        try:
            if cancel:
                procs = getattr(self.pool, "_processes", None) or {}
                for proc in list(procs.values()):
                    try:
                        proc.terminate()
                    except (OSError, AttributeError, ValueError):  # pragma: no cover
                        pass
            self.pool.shutdown(wait=not cancel, cancel_futures=cancel)
        finally:
            self.env.__exit__(None, None, None)


#: Seconds to wait for a Dask scheduler to answer before giving up.
CONNECT_TIMEOUT = 10.0


def _dask_error(address: str, reason: str) -> BatchError:
    return BatchError(f"--scheduler {address}: {reason}")


def _probe_scheduler(distributed, address: str, timeout: float) -> None:
    """Check, within ``timeout`` seconds, that ``address`` is a Dask scheduler we can
    reach (TLS from the Dask configuration); one-line errors. Run in its own thread and
    event loop, so it works from a notebook (a running loop) too."""
    import asyncio

    from distributed.comm import connect

    security = None
    try:   # as distributed.Client does: a configured security loader, else the config
        from distributed.client import _maybe_call_security_loader

        security = _maybe_call_security_loader(address)
    except ImportError:  # pragma: no cover - another version of distributed
        pass
    except Exception as err:  # noqa: BLE001 - the user's loader failed
        raise _dask_error(address, f"the Dask security loader failed ({type(err).__name__}: "
                                   f"{_one_line(str(err))[:200]})") from None
    if not isinstance(security, distributed.Security):
        security = distributed.Security()   # the Dask configuration's TLS settings, if any

    async def identity():
        comm = await connect(address, timeout=timeout, **security.get_connection_args("client"))
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            await comm.close()

    def run():
        return asyncio.run(asyncio.wait_for(identity(), timeout))

    with cf.ThreadPoolExecutor(1, thread_name_prefix="deformclosure-probe") as pool:
        fut = pool.submit(run)
        try:
            reply = fut.result(timeout + 5.0)
        except (TimeoutError, asyncio.TimeoutError, cf.TimeoutError):
            raise _dask_error(address, f"no answer within {timeout:g} s; check the address and "
                                       "that the scheduler runs (dask scheduler)") from None
        except OSError as err:
            raise _dask_error(address, f"cannot connect ({_one_line(str(err)) or type(err).__name__}); "
                                       "check the address and that the scheduler runs") from None
        except TypeError as err:
            if "ssl" in str(err).lower() or "tls" in str(err).lower():
                raise _dask_error(address, "tls:// needs the TLS settings in the Dask configuration "
                                           "(distributed.comm.tls.ca-file, .client.cert, "
                                           ".client.key); see docs/batch.md") from None
            raise _dask_error(address, f"not a Dask scheduler ({type(err).__name__})") from None
        except Exception as err:  # noqa: BLE001 - garbage from whatever listens there
            raise _dask_error(address, f"not a Dask scheduler, or it does not speak to us "
                                       f"({type(err).__name__})") from None
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise _dask_error(address, f"answers as {str(kind)[:40]!r}, not a Dask scheduler; give "
                                   "the scheduler's address (port 8786 by default)")


def _check_address(address: str) -> None:
    """Reject, without any network access, an address Dask cannot use."""
    try:
        from distributed.comm import parse_address, parse_host_port
        from distributed.comm.registry import get_backend
    except ImportError:
        raise _dask_error(address, "Dask is not installed; pip install distributed "
                                   "(or use --scheduler processes)") from None
    try:
        scheme, loc = parse_address(address)
        get_backend(scheme)
        if scheme in ("tcp", "tls", "ws", "wss"):
            host, port = parse_host_port(loc)
            if not host or not 0 < int(port) < 65536:
                raise ValueError("no host, or a port outside 1-65535")
    except (ValueError, TypeError) as err:
        raise _dask_error(address, f"not a usable scheduler address ({_one_line(str(err))}); "
                                   "give one like tcp://HOST:8786") from None


class _Dask:
    """A Dask cluster reached through its scheduler (or a given ``distributed.Client``).

    An address is checked and probed (a short identity request, :data:`CONNECT_TIMEOUT`
    seconds at most) before the client connects, so a wrong or dead address fails at
    once with one line, before the results file is touched.
    """

    def __init__(self, scheduler: Any, workers: int | None):
        if isinstance(scheduler, str):
            _check_address(scheduler)
        import distributed

        self.distributed = distributed
        self.own = isinstance(scheduler, str)
        if self.own:
            timeout = float(CONNECT_TIMEOUT)
            _probe_scheduler(distributed, scheduler, timeout)
            try:
                self.client = distributed.Client(scheduler, timeout=f"{timeout:g}s",
                                                 set_as_default=False)
            except Exception as err:  # noqa: BLE001 - one line, whatever Dask raised
                raise _dask_error(scheduler, f"cannot connect to the Dask scheduler "
                                             f"({_one_line(str(err)) or type(err).__name__})") from None
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
        if scheduler in ("processes", "inline"):
            return
        if "://" in scheduler:
            _check_address(scheduler)
            return
    elif hasattr(scheduler, "submit") and hasattr(scheduler, "nthreads"):
        return
    shown = repr(scheduler) if len(repr(scheduler)) < 100 else repr(scheduler)[:100] + "..."
    raise BatchError(f"--scheduler {shown}: choose 'processes', 'inline' or a Dask "
                     "scheduler address such as tcp://host:8786")


def _is_dask(scheduler: Any) -> bool:
    return not (isinstance(scheduler, str) and scheduler in ("processes", "inline"))


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
#
# A results file is recognised before anything writes to it: the first 100 bytes must be
# an SQLite header with our application_id (or, for a file of an earlier version, no id
# and nothing but our ``jobs`` table). Anything else is refused without being opened for
# writing, so another program's database is never changed. Every open runs ``PRAGMA
# quick_check``; every SQLite error becomes one line naming the file.

_FIX_RUN = "delete it or give another -o"
_FIX_READ = "restore a copy, or run the batch again into a new file (-o)"


def _db_error(shown: str, err: BaseException, fix: str = _FIX_RUN) -> BatchError:
    """One-line BatchError for an SQLite error on the results file ``shown``."""
    msg = _one_line(str(err))[:300]
    low = msg.lower()
    if (isinstance(err, sqlite3.DatabaseError) and not isinstance(err, sqlite3.OperationalError)
            and not isinstance(err, sqlite3.IntegrityError)) \
            or any(w in low for w in ("malformed", "not a database", "corrupt")):
        return BatchError(f"results file {shown} is corrupt: {msg}; {fix}")
    if any(w in low for w in ("readonly", "read-only", "permission", "unable to open")):
        return BatchError(f"results file {shown}: cannot write ({msg}); make the file and its "
                          "folder writable, or give another -o")
    if "full" in low:
        return BatchError(f"results file {shown}: cannot write ({msg}); free some disk space "
                          "and run the same command again (finished jobs are kept)")
    if "locked" in low or "busy" in low:
        return BatchError(f"results file {shown}: in use by another process ({msg}); wait for "
                          "it to finish, or give another -o")
    return BatchError(f"results file {shown}: SQLite error ({msg}); {fix}")


def _not_ours(shown: str, what: str, fix: str = "give another -o") -> BatchError:
    return BatchError(f"{shown}: not a deformclosure results file ({what}); it was left "
                      f"unchanged — {fix}")


def _inspect_results(p: Path, shown: str, fix: str = "give another -o") -> str:
    """``"missing"``, ``"empty"`` (0 bytes: an empty SQLite database, nothing to lose),
    ``"ours"`` or ``"legacy"`` (a results file of an earlier version), found without
    writing anything; BatchError for any other file."""
    try:
        st = p.stat()
    except FileNotFoundError:
        if p.is_symlink():
            raise BatchError(f"{shown}: a symbolic link to a missing file; give another -o") from None
        return "missing"
    except (OSError, ValueError) as err:
        raise BatchError(f"results file {shown}: cannot read ({getattr(err, 'strerror', None) or err})") from None
    if stat.S_ISDIR(st.st_mode):
        raise BatchError(f"{shown}: is a folder; give a file name for the results file")
    if not stat.S_ISREG(st.st_mode):
        raise BatchError(f"{shown}: not a regular file; give a file name for the results file")
    if st.st_size == 0:
        return "empty"
    try:
        with open(p, "rb") as fh:
            head = fh.read(100)
    except OSError as err:
        raise BatchError(f"results file {shown}: cannot read ({err.strerror or err})") from None
    if len(head) < 100 or not head.startswith(_SQLITE_MAGIC):
        raise _not_ours(shown, "not an SQLite database", fix)
    app_id = int.from_bytes(head[68:72], "big")
    layout = int.from_bytes(head[60:64], "big")
    if app_id == APPLICATION_ID:
        if layout > _SCHEMA_VERSION:
            raise BatchError(f"{shown}: written by a newer deformclosure (layout {layout}); "
                             "upgrade deformclosure to use it")
        return "ours"
    if app_id != 0:
        raise _not_ours(shown, f"an SQLite database of another program, application_id "
                               f"{app_id:#x}", fix)
    # No id: a results file of an earlier version has exactly our table `jobs`. Read the
    # main file alone first (immutable: no -wal/-shm file is touched); only if its schema
    # is empty and a -wal file exists may the tables be in the log, read the usual way.
    tables, cols = _legacy_schema(p, shown, immutable=True)
    if not tables and Path(f"{p}-wal").exists():
        tables, cols = _legacy_schema(p, shown, immutable=False)
    if tables != ["jobs"] or tuple(cols) != _COLUMNS:
        listed = ", ".join(tables[:5]) + (", ..." if len(tables) > 5 else "")
        raise _not_ours(shown, f"an SQLite database with tables {listed or '(none)'}", fix)
    return "legacy"


def _legacy_schema(p: Path, shown: str, immutable: bool) -> tuple[list[str], list[str]]:
    """Tables of an SQLite file without our id, and the columns of ``jobs``; read only."""
    conn = None
    try:
        if immutable:
            conn = sqlite3.connect(p.resolve().as_uri() + "?immutable=1", uri=True)
        else:
            conn = _connect_ro(p)
        tables = sorted(r[0] for r in conn.execute(
            "SELECT name FROM sqlite_master WHERE type IN ('table', 'view') "
            "AND name NOT LIKE 'sqlite_%'"))
        cols = [r[1] for r in conn.execute("PRAGMA table_info(jobs)")] if tables == ["jobs"] else []
    except sqlite3.Error as err:
        raise _db_error(shown, err) from None
    finally:
        if conn is not None:
            conn.close()
    return tables, cols


def _connect_ro(p: Path) -> sqlite3.Connection:
    """A read-only connection (opened through a ``file:`` URI: nothing is written)."""
    uri = p.resolve().as_uri() + "?mode=ro"
    try:
        conn = sqlite3.connect(uri, uri=True, timeout=60.0)
        conn.execute("SELECT 1 FROM sqlite_master LIMIT 1").fetchall()
        return conn
    except sqlite3.OperationalError:
        if Path(str(p) + "-wal").exists():
            raise
        # A read-only folder: no -shm can be made; without a -wal file nothing is pending.
        return sqlite3.connect(p.resolve().as_uri() + "?immutable=1", uri=True)


def _check_structure(conn: sqlite3.Connection, shown: str, fix: str) -> None:
    """``PRAGMA quick_check`` and the ``jobs`` columns; BatchError, connection left open."""
    rows = conn.execute("PRAGMA quick_check").fetchall()
    if [tuple(r) for r in rows] != [("ok",)]:
        detail = _one_line(" ".join(str(r[0]) for r in rows[:3]))[:300]
        raise BatchError(f"results file {shown} is corrupt: {detail}; {fix}")
    cols = [r[1] for r in conn.execute("PRAGMA table_info(jobs)")]
    if tuple(cols) != _COLUMNS:
        raise _not_ours(shown, f"no table jobs with columns {', '.join(_COLUMNS)}", fix)


def _open_read(p: Path, shown: str) -> sqlite3.Connection:
    """A checked read-only connection to an existing results file."""
    state = _inspect_results(p, shown, fix=_FIX_READ)
    if state == "missing":
        raise BatchError(f"{shown}: results file not found; run deformclosure batch ... -o {shown} first")
    if state == "empty":
        raise BatchError(f"{shown}: an empty file, not a deformclosure results file (yet); run "
                         f"deformclosure batch ... -o {shown} first")
    folder = p.parent if str(p.parent) else Path(".")
    try:
        if os.access(p, os.W_OK) and os.access(folder, os.W_OK | os.X_OK):
            # Ours, and writable: the usual connection, so that closing it removes the
            # -wal/-shm files as the batch does; query_only: reading changes no row.
            conn = sqlite3.connect(str(p), timeout=60.0)
            conn.execute("PRAGMA query_only = ON")
        else:
            conn = _connect_ro(p)
    except sqlite3.Error as err:
        raise _db_error(shown, err, _FIX_READ) from None
    try:
        _check_structure(conn, shown, _FIX_READ)
    except sqlite3.Error as err:
        conn.close()
        raise _db_error(shown, err, _FIX_READ) from None
    except BaseException:
        conn.close()
        raise
    return conn


def _check_writable(p: Path, shown: str, exists: bool) -> None:
    """Write access to the file and its folder (SQLite writes its -wal/-shm files beside
    it), checked before any job runs."""
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.is_dir():
        raise BatchError(f"{shown}: folder {folder} does not exist; create it first")
    if exists and not os.access(p, os.W_OK):
        raise BatchError(f"results file {shown}: not writable; make it writable (chmod u+w) "
                         "or give another -o")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise BatchError(f"results file {shown}: its folder {folder} is not writable (SQLite "
                         "keeps its journal beside the file); make it writable or give another -o")


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - Windows
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


def _create_results(p: Path, shown: str, replace_empty: bool = False) -> None:
    """Make an empty results file atomically: built beside ``p``, then linked onto it
    (if another run made ``p`` meanwhile, theirs is kept). With ``replace_empty``, ``p``
    is an empty (0-byte) file, replaced if it still is."""
    folder = p.parent if str(p.parent) else Path(".")
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".creating", dir=folder)
    except OSError as err:
        raise BatchError(f"results file {shown}: cannot create it in {folder} "
                         f"({err.strerror or err}); make the folder writable or give another -o") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        conn = sqlite3.connect(str(tmp), isolation_level=None)
        try:
            conn.execute("BEGIN")
            conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            conn.execute(f"PRAGMA user_version = {_SCHEMA_VERSION}")
            conn.execute(SCHEMA)
            conn.execute(_META_SCHEMA)
            conn.execute(_LISTS_SCHEMA)
            conn.executemany("INSERT INTO meta (key, value) VALUES (?, ?)",
                             [("format", _FORMAT), ("created_by", f"deformclosure {_version()}"),
                              ("created", _iso(time.time()))])
            conn.execute("COMMIT")
            # WAL: a commit is one append to the log, and a killed writer leaves the file
            # consistent; the mode is stored in the file.
            conn.execute("PRAGMA journal_mode=WAL")
        finally:
            conn.close()
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        if replace_empty:
            if p.is_file() and p.stat().st_size == 0:
                os.replace(tmp, p)
        else:
            try:
                os.link(tmp, p)
            except FileExistsError:
                pass                               # made meanwhile by another run
            except OSError:                        # no hard links here
                if not p.exists():
                    os.replace(tmp, p)
        _fsync_dir(folder)
    except sqlite3.Error as err:
        raise BatchError(f"results file {shown}: cannot create it ({_one_line(str(err))}); "
                         "give another -o") from None
    except OSError as err:
        raise BatchError(f"results file {shown}: cannot create it ({err.strerror or err}); "
                         "give another -o") from None
    finally:
        for q in (tmp, Path(f"{tmp}-wal"), Path(f"{tmp}-shm"), Path(f"{tmp}-journal")):
            try:
                q.unlink()
            except OSError:
                pass


def _open_for_run(p: Path, shown: str, ident: str, keys: set, source: str,
                  append: bool) -> sqlite3.Connection:
    """Create or open the results file for a run: recognised as ours, intact, writable,
    made for this job list (or ``append``). Nothing runs before this succeeds."""
    state = _inspect_results(p, shown)
    _check_writable(p, shown, exists=state != "missing")
    if state in ("missing", "empty"):
        _create_results(p, shown, replace_empty=state == "empty")
        state = _inspect_results(p, shown)
        if state in ("missing", "empty"):
            raise BatchError(f"results file {shown}: cannot create it; give another -o")
    try:
        conn = sqlite3.connect(str(p), timeout=60.0)
    except sqlite3.Error as err:
        raise _db_error(shown, err) from None
    try:
        _check_structure(conn, shown, _FIX_RUN)
        conn.isolation_level = None          # explicit transaction below
        if conn.execute("PRAGMA journal_mode").fetchone()[0].lower() != "wal":
            conn.execute("PRAGMA journal_mode=WAL")
        # FULL: a committed row also survives a power cut.
        conn.execute("PRAGMA synchronous=FULL")
        # One write transaction now: a read-only file or folder, a full disk or a file
        # in use fails here, before any job runs.
        conn.execute("BEGIN IMMEDIATE")
        try:
            if state == "legacy":            # a results file of an earlier version: mark it
                conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
                conn.execute(f"PRAGMA user_version = {_SCHEMA_VERSION}")
            conn.execute(_META_SCHEMA)
            conn.execute(_LISTS_SCHEMA)
            conn.execute("INSERT OR IGNORE INTO meta (key, value) VALUES ('format', ?)",
                         (_FORMAT,))
            known = {r[0] for r in conn.execute("SELECT identity FROM job_lists")}
            if ident not in known:
                n_rows = conn.execute("SELECT COUNT(*) FROM jobs").fetchone()[0]
                if known and n_rows and not append:
                    same = sum(1 for (k,) in conn.execute("SELECT key FROM jobs") if k in keys)
                    raise BatchError(
                        f"results file {shown}: made for another job list ({n_rows} "
                        f"job{'s' * (n_rows != 1)} in it, "
                        f"{same} of them in this batch); pass --append (append=True) to add this "
                        "batch's jobs to it, or give another -o")
                conn.execute("INSERT INTO job_lists (identity, n_jobs, source, added) "
                             "VALUES (?, ?, ?, ?)", (ident, len(keys), source[:MAX_FIELD], time.time()))
            conn.execute("INSERT OR REPLACE INTO meta (key, value) VALUES ('last_run', ?)",
                         (_iso(time.time()),))
            conn.execute("COMMIT")
        except BaseException:
            try:
                conn.execute("ROLLBACK")
            except sqlite3.Error:
                pass
            raise
        conn.isolation_level = ""            # back to the default: `with conn` per job
    except sqlite3.Error as err:
        conn.close()
        raise _db_error(shown, err) from None
    except BaseException:
        conn.close()
        raise
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


def _iso(t: Any) -> str | None:
    """ISO 8601 UTC (``2025-01-31T12:00:00.000Z``) of a Unix time, None if not one."""
    import datetime as dt

    if not _is_num(t):
        return None
    try:
        return dt.datetime.fromtimestamp(t, dt.timezone.utc).isoformat(
            timespec="milliseconds").replace("+00:00", "Z")
    except (OverflowError, OSError, ValueError):
        return None


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
              append: bool = False) -> BatchSummary:
    """Run the jobs not yet in the results file; commit each one as it finishes.

    Parameters
    ----------
    jobs : sequence of Job, or path-like
        Jobs from :func:`load_jobs`, or a folder / job list to load with its defaults.
    db_path : path-like
        SQLite results file, created if missing (table :data:`SCHEMA`).
    scheduler : str or distributed.Client
        ``"processes"`` (local process pool), ``"inline"`` (this process, one job at a
        time) or a Dask scheduler address ``"tcp://host:port"`` (``tls://`` with the
        Dask configuration's TLS settings; or a connected client).
    workers : int, optional
        Local pool size (default: the CPUs this process may use, at most one per job);
        with Dask, the most jobs in flight at once (default: twice the cluster's threads).
    retry_failed : bool
        Run again the jobs recorded as failed (default: keep them).
    progress : bool
        Show a progress bar (tqdm, on stderr).
    append : bool
        Add this batch to a results file made for another job list (refused otherwise).

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
    if not isinstance(db_path, (str, os.PathLike)) or not os.fspath(db_path):
        raise BatchError(f"results file {db_path!r}: give a file path")
    _check_scheduler(scheduler, workers)
    version = _version()
    unique: dict[str, Job] = {}
    for j in jobs:
        unique.setdefault(j.key, j)
    shown = os.fspath(db_path)
    path = Path(shown)
    # Everything that can refuse the run is checked before the file is created or
    # changed: the file itself (read only), its folder, then the scheduler.
    state = _inspect_results(path, shown)
    _check_writable(path, shown, exists=state != "missing")
    _clean_stale_runs()
    dask = _Dask(scheduler, workers) if _is_dask(scheduler) else None
    conn = ex = run_dir = None
    status: dict[str, str] = {}
    n_run = n_finished = 0
    try:
        conn = _open_for_run(path, shown, _list_identity(list(unique.values())), set(unique),
                             _source(jobs), append)
        try:
            status = {k: s for k, s in conn.execute("SELECT key, status FROM jobs")
                      if k in unique}
        except sqlite3.Error as err:
            raise _db_error(shown, err) from None
        todo = deque(j for k, j in unique.items()
                     if k not in status or (retry_failed and status[k] == "failed"))
        n_run = len(todo)
        if todo:
            run_dir = _make_run_dir()
            ex = dask if dask is not None else _executor(scheduler, workers, n_run)
        bar = tqdm(total=n_run, disable=not progress or n_run == 0, unit="job", desc="batch",
                   file=sys.stderr, dynamic_ncols=True)
        n_bad = 0

        def store(job: Job, out: dict) -> None:
            nonlocal n_bad, n_finished
            try:
                _store(conn, job, out, version)
            except sqlite3.Error as err:
                raise _db_error(shown, err) from None
            n_finished += 1
            status[job.key] = "ok" if out["status"] == "ok" else status.get(job.key, "failed")
            n_bad += out["status"] != "ok"
            bar.update(1)
            if n_bad:
                bar.set_postfix(failed=n_bad, refresh=False)

        try:
            if ex is not None:
                _drive(ex, todo, store, version, run_dir)
        finally:
            bar.close()
        closing, ex = ex, None
        if closing is not None:
            closing.close()
        if dask is not None and dask is not closing:
            dask.close()
        dask = None
        failures = []
        if any(status.get(k) == "failed" for k in unique):
            try:
                raw = conn.execute(f"SELECT {', '.join(_COLUMNS)} FROM jobs "
                                   "WHERE status = 'failed'").fetchall()
            except sqlite3.Error as err:
                raise _db_error(shown, err) from None
            rows = {r["key"]: r for r in map(_decode_row, raw)}
            failures = [{"part": rows[k]["part"], "command": rows[k]["command"],
                         "options": rows[k]["options"], "error": rows[k]["error"]}
                        for k in unique if k in rows]
    except KeyboardInterrupt:
        if ex is not None:
            ex.close(cancel=True)
        if dask is not None and dask is not ex:
            dask.close(cancel=True)
        raise BatchInterrupted(shown, n_finished,
                               sum(1 for k in unique if k in status)) from None
    except BaseException:
        if ex is not None:
            ex.close(cancel=True)
        if dask is not None and dask is not ex:
            dask.close(cancel=True)
        raise
    finally:
        if conn is not None:
            conn.close()
        if run_dir is not None:
            shutil.rmtree(run_dir, ignore_errors=True)
    n_ok = sum(status.get(k) == "ok" for k in unique)
    return BatchSummary(db_path=shown, n_jobs=len(unique),
                        n_duplicates=len(jobs) - len(unique), n_run=n_run,
                        n_skipped=len(unique) - n_run, n_ok=n_ok, n_failed=len(failures),
                        seconds=time.perf_counter() - t0, failures=tuple(failures))


def _source(jobs: Sequence[Job]) -> str:
    """A short description of where the jobs come from (stored with the list identity)."""
    parts = sorted({str(Path(j.path).parent) for j in jobs})
    return f"{len(jobs)} jobs in {', '.join(parts[:3])}{', ...' if len(parts) > 3 else ''}"


def _drive(ex, todo: deque, store, version: str, tmp_root: str | os.PathLike | None = None) -> None:
    """Keep the executor busy; hand each finished job to ``store`` as it arrives."""
    inflight: dict[Any, Job] = {}
    while todo or inflight:
        while todo and len(inflight) < ex.capacity():
            job = todo.popleft()
            try:
                payload = _payload(job, version, tmp_root)
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
                    store(job, ex.run_isolated(_payload(job, version, tmp_root)))
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
        Only rows with this stored status.

    Returns
    -------
    list of dict
        One dict per job with the columns of :data:`SCHEMA`; ``options`` is a list and
        ``result`` the parsed JSON report (``None`` for a failed job). Stored values are
        read as untrusted: JSON by the strict reader's rules (no NaN or Infinity, bounded
        nesting and integers), numbers finite, text UTF-8. A row that breaks them comes
        back with ``status = "unreadable"``, ``result = None`` and the reason in
        ``error`` — it never raises.

    Raises
    ------
    BatchError
        Missing file, not a results file, or a corrupt one.
    """
    if status not in (None, "ok", "failed"):
        raise BatchError(f"status = {status!r}: choose 'ok', 'failed' or None")
    shown = os.fspath(db_path)
    conn = _open_read(Path(shown), shown)
    try:
        conn.text_factory = bytes          # decoded per cell: bad UTF-8 marks one row only
        sql = f"SELECT {', '.join(_COLUMNS)} FROM jobs"
        rows = conn.execute(sql + (" WHERE status = ?" if status else ""),
                            (status,) if status else ()).fetchall()
    except sqlite3.Error as err:
        raise _db_error(shown, err, _FIX_READ) from None
    finally:
        conn.close()
    out = [_decode_row(r) for r in rows]
    out.sort(key=lambda d: (d["part"], d["command"], d["options"], d["key"]))
    return out


def _is_num(v: Any) -> bool:
    """A finite real number (not a bool)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _all_finite(value: Any) -> bool:
    stack = [value]
    while stack:
        v = stack.pop()
        if isinstance(v, float) and not math.isfinite(v):
            return False
        if isinstance(v, dict):
            stack.extend(v.values())
        elif isinstance(v, list):
            stack.extend(v)
    return True


def _stored_json(text: str, column: str) -> tuple[Any, str | None]:
    """Parse a stored JSON text by the strict reader's rules: (value, None) or (None, why)."""
    from ..jsonfile import parse_json

    try:
        value = parse_json(text, column, BatchError, "stored value")
    except BatchError as err:
        return None, _one_line(str(err))[:200]
    if not _all_finite(value):
        return None, f"{column}: NaN or Infinity in the stored JSON"
    return value, None


def _decode_row(raw: Sequence[Any]) -> dict:
    """A stored row as a dict, checked; a bad row gets ``status = "unreadable"``."""
    d: dict[str, Any] = {}
    problems: list[str] = []
    for col, v in zip(_COLUMNS, raw):
        if isinstance(v, (bytes, bytearray)):
            try:
                v = bytes(v).decode("utf-8")
            except UnicodeDecodeError:
                problems.append(f"{col} is not UTF-8 text")
                v = None
        d[col] = v
    for col in ("key", "part", "command", "status", "error", "version"):
        if d[col] is not None and not isinstance(d[col], str):
            problems.append(f"{col} is not text")
            d[col] = None
        elif isinstance(d[col], str) and "\x00" in d[col]:
            problems.append(f"{col} holds a NUL character")
            d[col] = d[col].replace("\x00", "\\0")
    for col in ("key", "part", "command"):
        d[col] = d[col] if d[col] is not None else ""
    if d["status"] not in ("ok", "failed"):
        problems.append(f"status {str(d['status'])[:20]!r} is neither 'ok' nor 'failed'")
    options = d["options"]
    d["options"] = []
    if isinstance(options, str):
        value, why = _stored_json(options, "options")
        if why:
            problems.append(why)
        elif not isinstance(value, list) or not all(isinstance(o, str) for o in value):
            problems.append("options: not a list of strings")
        else:
            d["options"] = value
    else:
        problems.append("options is not text")
    result = d["result"]
    d["result"] = None
    if isinstance(result, str):
        value, why = _stored_json(result, "result")
        if why:
            problems.append(why)
        elif not isinstance(value, dict):
            problems.append("result: not a JSON object")
        else:
            d["result"] = value
    elif result is not None:
        problems.append("result is not text")
    for col in ("started", "finished", "seconds"):
        if d[col] is not None and not _is_num(d[col]):
            problems.append(f"{col} is not a finite number")
            d[col] = None
    if problems:
        d["status"] = "unreadable"
        d["result"] = None
        d["error"] = "; ".join(problems)
    return d


#: Scalar fields of the reports shown by ``results`` (SI units, SPEC §5).
_SCALARS = ("model", "verdict", "sigma_star", "quality", "U_A", "U_L", "sigma_L",
            "deform_closure", "order", "energy")
_FIELDS = (*_SCALARS, "n_pairs", "top_a", "top_b", "n_axes", "top_angle", "top_point",
           "top_sigma_star", "top_quality", "n_nodes", "n_triangles")
_TEXT = frozenset({"model", "verdict"})
_BOOL = frozenset({"deform_closure"})
_INT = frozenset({"order"})


def _typed(key: str, v: Any) -> Any:
    """``v`` if it has the type field ``key`` should have (stored reports are not
    trusted), else None."""
    if key in _TEXT:
        return v[:100] if isinstance(v, str) else None
    if key in _BOOL:
        return v if isinstance(v, bool) else None
    if key in _INT:
        return v if isinstance(v, int) and not isinstance(v, bool) else None
    return v if _is_num(v) else None


def _node(v: Any) -> int | None:
    return v if isinstance(v, int) and not isinstance(v, bool) else None


def _xy(v: Any) -> tuple[float, float] | None:
    if isinstance(v, list) and len(v) == 2 and all(_is_num(c) for c in v):
        return float(v[0]), float(v[1])
    return None


def _two_xy(v: Any) -> tuple[tuple[float, float], tuple[float, float]] | None:
    if isinstance(v, list) and len(v) == 2:
        a, b = _xy(v[0]), _xy(v[1])
        if a is not None and b is not None:
            return a, b
    return None


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
        The fields present, SI units (m, J). A field of the wrong type (a stored report
        is not trusted) is None.
    """
    if not isinstance(result, dict):
        return {}
    out = {k: _typed(k, result[k]) for k in _SCALARS
           if k in result and not isinstance(result[k], (dict, list))}
    axes = result.get("axes")
    if isinstance(axes, list):                   # a pad plan: grasp axes, best first
        out["n_axes"] = len(axes)
        if axes and isinstance(axes[0], dict):
            top = axes[0]
            out.update(top_angle=_typed("angle", top.get("angle")),
                       top_sigma_star=_typed("sigma_star", top.get("sigma_star")),
                       top_quality=_typed("quality", top.get("quality")))
            point = _xy(top.get("point"))
            if point is not None:
                out["top_point"] = " ".join(f"{v:.6g}" for v in point)
    pairs = result.get("pairs")
    if isinstance(pairs, list):
        out["n_pairs"] = len(pairs)
        # the plan's proposal: its `top` list (pulling pairs excluded), else the best row
        ranked = result.get("top") if isinstance(result.get("top"), list) and result["top"] \
            else pairs
        if ranked and isinstance(ranked[0], dict):
            top = ranked[0]
            out.update(top_a=_node(top.get("a")), top_b=_node(top.get("b")),
                       top_sigma_star=_typed("sigma_star", top.get("sigma_star")),
                       top_quality=_typed("quality", top.get("quality")))
    if isinstance(result.get("nodes"), list) and isinstance(result.get("triangles"), list):
        out.update(n_nodes=len(result["nodes"]), n_triangles=len(result["triangles"]))
    return out


#: Units of the summary fields, as suffixes of the CSV columns.
_UNITS = {"sigma_star": "m", "quality": "J", "U_A": "J", "U_L": "J", "sigma_L": "m",
          "energy": "J", "top_sigma_star": "m", "top_quality": "J", "top_angle": "rad"}
#: Columns of ``results --format csv`` after the row's own columns, in this order (those
#: present in some row). Lengths in m, energies in J, angles in rad.
CSV_FIGURES = (
    "model", "verdict", "sigma_star_m", "quality_J", "U_A_J", "U_A_infinite", "U_L_J",
    "sigma_L_m", "jaw_a", "jaw_b", "jaw_a_x_m", "jaw_a_y_m", "jaw_b_x_m", "jaw_b_y_m",
    "axis_x_m", "axis_y_m", "axis_angle_rad", "deform_closure", "order", "energy_J",
    "n_pairs", "top_a", "top_b", "n_axes", "top_angle_rad", "top_point_x_m", "top_point_y_m",
    "top_jaw_a_x_m", "top_jaw_a_y_m", "top_jaw_b_x_m", "top_jaw_b_y_m", "top_sigma_star_m",
    "top_quality_J", "n_nodes", "n_triangles")
#: The row's own columns in the CSV: times ISO 8601 UTC, run time in s.
CSV_COLUMNS = ("key", "part", "command", "options", "status", "error", "started_utc",
               "finished_utc", "seconds_s", "version")


def _jaw_columns(prefix: str, xy) -> dict:
    if xy is None:
        return {}
    (ax, ay), (bx, by) = xy
    return {f"{prefix}jaw_a_x_m": ax, f"{prefix}jaw_a_y_m": ay,
            f"{prefix}jaw_b_x_m": bx, f"{prefix}jaw_b_y_m": by}


def _csv_figures(result: Any) -> dict:
    """The CSV figure columns of a report (see :data:`CSV_FIGURES`): the summary with
    units in the names, and the jaw/contact coordinates the report holds."""
    if not isinstance(result, dict):
        return {}
    out = {}
    for k, v in result_summary(result).items():
        if k != "top_point":
            out[f"{k}_{_UNITS[k]}" if k in _UNITS else k] = v
    if isinstance(result.get("U_A_infinite"), bool):
        out["U_A_infinite"] = result["U_A_infinite"]
    jaws = result.get("jaws")
    if isinstance(jaws, list) and len(jaws) == 2 and all(_node(j) is not None for j in jaws):
        out.update(jaw_a=jaws[0], jaw_b=jaws[1])                  # paper model: node ids
    out.update(_jaw_columns("", _two_xy(result.get("jaw_positions"))
                            or _two_xy(result.get("contacts"))))
    axis = result.get("axis")
    if isinstance(axis, dict) and _xy(axis.get("point")) is not None:
        (x, y), angle = _xy(axis["point"]), axis.get("angle")
        out.update(axis_x_m=x, axis_y_m=y, axis_angle_rad=angle if _is_num(angle) else None)
    for kind in ("axes", "pairs"):                                 # a plan: the best grasp
        best = result.get(kind)
        if kind == "pairs" and isinstance(result.get("top"), list) and result["top"]:
            best = result["top"]                        # paper plans: pulling pairs excluded
        if isinstance(best, list) and best and isinstance(best[0], dict):
            top = best[0]
            point = _xy(top.get("point"))
            if point is not None:
                out.update(top_point_x_m=point[0], top_point_y_m=point[1])
            out.update(_jaw_columns("top_", _two_xy(top.get("jaw_positions"))
                                    or _two_xy(top.get("contacts"))))
    return out


def _describe(row: dict) -> str:
    if row["status"] == "unreadable":
        return f"unreadable row: {row.get('error')}"
    if row["status"] != "ok":
        return f"error: {row['error']}"
    s = result_summary(row["result"])

    def g(v, u=""):
        return "-" if v is None else (f"{v:.4g}{u}" if isinstance(v, float) else f"{v}{u}")

    if "n_axes" in s:
        if s.get("top_angle") is None:
            return f"{s['n_axes']} axes"
        return (f"best axis {math.degrees(s['top_angle']):.1f} deg through ({s.get('top_point')}) m "
                f"sigma*={g(s.get('top_sigma_star'), ' m')} Q={g(s.get('top_quality'), ' J')} "
                f"({s['n_axes']} axes)")
    if "top_quality" in s or "n_pairs" in s:
        if "top_a" not in s:
            return f"{s['n_pairs']} pairs"
        return (f"best {g(s['top_a'])}-{g(s['top_b'])} sigma*={g(s.get('top_sigma_star'), ' m')} "
                f"Q={g(s.get('top_quality'), ' J')} ({s['n_pairs']} pairs)")
    if "sigma_star" in s or "quality" in s:
        v = f" {s['verdict']}" if s.get("verdict") else ""
        return f"sigma*={g(s.get('sigma_star'), ' m')} Q={g(s.get('quality'), ' J')}{v}"
    if "deform_closure" in s:
        dc = s["deform_closure"]
        return f"deform closure: {'-' if dc is None else 'yes' if dc else 'no'}, order {g(s.get('order'))}"
    if "n_nodes" in s:
        return f"{s['n_nodes']} nodes, {s['n_triangles']} triangles"
    return "ok"


def _csv_cell(v: Any) -> Any:
    return "" if v is None else v


def format_results(rows: Sequence[dict], fmt: str = "table") -> str:
    """Render rows of :func:`read_results` as a text table, CSV or JSON.

    Parameters
    ----------
    rows : sequence of dict
    fmt : {"table", "csv", "json"}
        ``table``: one line per job (part, command, status, key figures, seconds) and a
        count. ``csv``: the row's columns (:data:`CSV_COLUMNS`: ``options``
        shell-quoted, ``started_utc``/``finished_utc`` ISO 8601 UTC, ``seconds_s``) and
        the figures of the report with their units in the names (:data:`CSV_FIGURES`:
        ``sigma_star_m``, ``quality_J``, the jaw or contact coordinates in m, ...).
        ``json``: a list of the full rows, reports included.

    Returns
    -------
    str
    """
    if fmt == "json":
        return json.dumps(list(rows), indent=2, allow_nan=False)
    if fmt == "csv":
        figures = [_csv_figures(r.get("result")) for r in rows]
        present = set().union(*figures) if figures else set()
        fields = [f for f in CSV_FIGURES if f in present]
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow([*CSV_COLUMNS, *fields])
        for r, fig in zip(rows, figures):
            own = {"key": r.get("key"), "part": r.get("part"), "command": r.get("command"),
                   "options": shlex.join(r.get("options") or []), "status": r.get("status"),
                   "error": r.get("error"), "started_utc": _iso(r.get("started")),
                   "finished_utc": _iso(r.get("finished")),
                   "seconds_s": r.get("seconds") if _is_num(r.get("seconds")) else None,
                   "version": r.get("version")}
            w.writerow([_csv_cell(own[c]) for c in CSV_COLUMNS]
                       + [_csv_cell(fig.get(f)) for f in fields])
        return buf.getvalue()
    if fmt != "table":
        raise BatchError(f"format = {fmt!r}: choose 'table', 'csv' or 'json'")
    if not rows:
        return "no jobs"
    table = [(r["part"], " ".join([r["command"], *r["options"]]), r["status"],
              f"{r['seconds']:.2f}" if _is_num(r.get("seconds")) else "-", _describe(r))
             for r in rows]
    head = ("part", "command", "status", "seconds", "result (SI units)")
    wid = [min(48, max(len(t[i]) for t in [head, *table])) for i in range(4)]

    def fmt_row(t):
        cells = [f"{t[i][:wid[i]]:<{wid[i]}}" if i != 3 else f"{t[i]:>{wid[i]}}" for i in range(4)]
        return "  ".join(cells + [t[4]])

    n_ok = sum(r["status"] == "ok" for r in rows)
    n_bad = sum(r["status"] == "failed" for r in rows)
    n_unreadable = len(rows) - n_ok - n_bad
    count = f"{len(rows)} job{'s' * (len(rows) != 1)}: {n_ok} ok, {n_bad} failed"
    if n_unreadable:
        count += f", {n_unreadable} unreadable"
    lines = [fmt_row(head), *(fmt_row(t) for t in table), count]
    return "\n".join(line.rstrip() for line in lines)
