"""A batch job: one part or mesh file, one report command and its options, and its key.

:meth:`Job.from_spec` checks a job the way the CLI would check the command line — the
options are parsed by :func:`deformclosure.reports.parse_argv`, the table the CLI is built
from — and computes the job key from the bytes of the files it reads.

Job key
    ``sha256`` of the part file's bytes, the command, the command's *parsed* parameters
    (defaults included, so ``--method exact`` and no ``--method`` are one job; files the
    command reads, such as ``--fingers``, enter through their bytes) and
    ``deformclosure.__version__``. Paths, outputs (``--plot``, ``--export-fields``) and
    display options (``--quiet``, ``--verbose``) are not in the key.
"""

from __future__ import annotations

import hashlib
import json
import os
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from ..errors import BatchError, DeformClosureError

__all__ = ["Job", "job_key", "job_ident", "list_identity", "MAX_FIELD", "check_field",
           "one_line"]

#: Longest field of a job list (a path, a command, the options), in characters.
MAX_FIELD = 4096
#: Options the runner sets itself.
_RESERVED = ("-o", "--output", "-h", "--help")
#: Parameter names in the key blob where they differ from the option table's: the CLI
#: called ``--fingers`` ``finger_file`` when the key was defined; keeping that name keeps
#: the keys, so results files of earlier runs resume.
_KEY_NAMES = {"fingers": "finger_file"}


def _version() -> str:
    from .. import __version__

    return __version__


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def one_line(text: Any) -> str:
    """``text`` on one line (whitespace runs collapsed)."""
    return " ".join(str(text).split()) or "(no message)"


@dataclass(frozen=True)
class Job:
    """One part or mesh file × one report command with its options.

    Build jobs with :meth:`Job.from_spec` or :func:`~deformclosure.batch.load_jobs`, which
    check the command and its options and compute the key.

    Attributes
    ----------
    part : str
        The part or mesh file as named in the job list (stored in the results file).
    command : str
        Report command, e.g. ``"plan"`` (see :data:`deformclosure.reports.JOB_COMMANDS`).
    options : tuple of str
        The command's options as given (without the part file).
    key : str
        Hex sha256 of the inputs, the parsed options and the package version.
    path : str
        Absolute path of the part file (symbolic links resolved).
    params : tuple of (str, object)
        The parsed parameters (defaults included) the worker runs with; paths of files
        read or written made absolute.
    inputs : tuple of (str, str, str)
        Files read besides the part (``--fingers``, a ``--material`` file): parameter
        name, absolute path and sha256 of the bytes used for the key.
    digest : str
        sha256 of the part file's bytes used for the key.
    ident : str
        The key without the package version: what identifies the job in a job list.
        Empty for a hand-made Job (then ``key``).
    """

    part: str
    command: str
    options: tuple[str, ...]
    key: str
    path: str
    params: tuple[tuple[str, Any], ...]
    inputs: tuple[tuple[str, str, str], ...]
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
            A report command that reads a part file (``plan``, ``optimize``, ``check``,
            ``mesh``, ``slice``).
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
        check_field(where, "part", part_str)
        if isinstance(command, str):
            check_field(where, "command", command)
        options = _split_options(options, where)
        _check_command(command, where)
        base = Path(base_dir) if base_dir is not None else Path.cwd()
        root_p = _resolve(Path(root), where, "job list folder") if root is not None else None
        opt_root = (_resolve(Path(options_root), where, "job list folder")
                    if options_root is not None else None)
        params, inputs = _parse_options(command, options, base, where, opt_root)
        path, real = _part_path(part_str, base, where, root_p)
        digest = _digest(path, where, f"part {part_str!r}")
        inputs += _sidecar(path, where)
        kparams = key_blob_params(command, params, inputs)
        shown = part_str if Path(part_str).is_absolute() or base_dir is None \
            else str(Path(base_dir) / part_str)
        return cls(part=shown, command=command, options=options,
                   key=job_key(digest, command, kparams), path=str(real),
                   params=tuple(params.items()), inputs=inputs, digest=digest,
                   ident=job_ident(digest, command, kparams))


def check_field(where: str, name: str, value: str) -> None:
    """Refuse a NUL character or an over-long field of a job (one line naming it)."""
    if "\x00" in value:
        raise BatchError(f"{where}{name}: contains a NUL character; a job list holds text "
                         "only (paths, a command, options) — fix or re-save the list")
    if len(value) > MAX_FIELD:
        raise BatchError(f"{where}{name}: {len(value)} characters, more than the {MAX_FIELD} "
                         "a job-list field may have; shorten it")


def _split_options(options: Sequence[str] | str, where: str) -> tuple[str, ...]:
    """The options as a tuple of strings, each checked as a field."""
    if isinstance(options, str):
        check_field(where, "options", options)
        try:
            options = shlex.split(options)
        except ValueError as err:
            raise BatchError(f"{where}options {options!r}: {err}") from None
    options = tuple(str(o) for o in options)
    for i, o in enumerate(options):
        check_field(where, f"options[{i}]", o)
    return options


def _check_command(name: Any, where: str) -> None:
    """Refuse what is not a job command (one line listing them)."""
    from ..reports import JOB_COMMANDS

    if not isinstance(name, str) or name not in JOB_COMMANDS:
        shown = repr(name) if not isinstance(name, str) or len(name) < 80 else repr(name[:80] + "...")
        raise BatchError(f"{where}command {shown}: not a job command; choose one of "
                         f"{', '.join(sorted(JOB_COMMANDS))}")


def _resolve(path: Path, where: str, what: str) -> Path:
    """``path`` with symbolic links resolved; one-line error for a loop or a bad name."""
    try:
        return path.resolve()
    except (OSError, RuntimeError) as err:
        reason = getattr(err, "strerror", None) or str(err)
        raise BatchError(f"{where}{what}: cannot resolve the path ({reason})") from None


def _inside(path: Path, root: Path) -> bool:
    return path == root or root in path.parents


def _is_file(path: Path) -> bool:
    try:
        return path.is_file()
    except OSError:
        return False


def _digest(path: Path, where: str, what: str) -> str:
    """sha256 of a regular input file of bounded size; one-line errors."""
    from ..jsonfile import check_input_file

    try:
        check_input_file(path, BatchError, "input file")
        return sha256(path.read_bytes())
    except BatchError as err:
        raise BatchError(f"{where}{what}: {err}") from None
    except OSError as err:
        raise BatchError(f"{where}{what}: cannot read ({err.strerror or err})") from None


def _part_path(part: str, base: Path, where: str, root: Path | None) -> tuple[Path, Path]:
    """The part file's path (relative to ``base``) and its resolved path, checked."""
    p = Path(part)
    path = p if p.is_absolute() else base / p
    real = _resolve(path, where, f"part {part!r}")
    if root is not None and not _inside(real, root):
        raise BatchError(f"{where}part {part!r}: outside the job list's folder "
                         f"{root}; move the file into it, or pass --allow-outside "
                         "(allow_outside=True) if you trust this job list")
    try:
        found = path.is_file()
    except OSError as err:
        raise BatchError(f"{where}part {part!r}: cannot read ({err.strerror or err})") from None
    if not found:
        raise BatchError(f"{where}part {part!r}: file not found "
                         f"(relative paths are relative to {base})")
    return path, real


def _parse_options(command: str, options: tuple[str, ...], base: Path, where: str,
                   root: Path | None) -> tuple[dict, tuple[tuple[str, str, str], ...]]:
    """Parse ``options`` as the CLI would; make file paths absolute and hash the inputs."""
    from ..reports import options_of, parse_argv

    bad = [o for o in options if o in _RESERVED or o.startswith("--output=")
           or (o.startswith("-o") and not o.startswith("--"))]
    if bad:
        raise BatchError(f"{where}options: {bad[0]} is set by the batch runner; remove it "
                         f"(each job's report goes to the results file)")
    try:
        params = parse_argv(command, options)
    except DeformClosureError as err:
        shown = shlex.join(options)
        shown = shown if len(shown) <= 200 else shown[:200] + "..."
        msg = one_line(str(err)).removeprefix(f"{command}: ")
        raise BatchError(f"{where}{command} {shown}: {msg}") from None
    inputs = []
    for opt in options_of(command):
        value = params.get(opt.name)
        if opt.role not in ("input", "file_or_json", "output") or not isinstance(value, str):
            continue
        if opt.role == "file_or_json" and value.lstrip().startswith("{"):
            continue                                # inline JSON: a value, in the key as is
        flag = opt.flags[-1]
        f = Path(value)
        f = _resolve(f if f.is_absolute() else base / f, where, flag)
        if root is not None and not _inside(f, root):
            raise BatchError(f"{where}{flag} {value!r}: outside the job list's folder "
                             f"{root}; keep the job's files in it, or pass --allow-outside "
                             "(allow_outside=True) if you trust this job list")
        params[opt.name] = str(f)
        if opt.role == "output":
            continue
        if not _is_file(f):
            raise BatchError(f"{where}{flag}: file not found ({f})")
        inputs.append((opt.name, str(f), _digest(f, where, flag)))
    return params, tuple(inputs)


#: Name of a drawing's material file (``<name>.material.json``) among a job's inputs; it
#: travels with the drawing (:attr:`deformclosure.jsonfile.Source.sidecar`).
SIDECAR = "sidecar"


def _sidecar(path: Path, where: str) -> tuple[tuple[str, str, str], ...]:
    """The material file beside a drawing, as an input of the job (none otherwise)."""
    from ..drawing import is_drawing_file, material_file_beside

    side = material_file_beside(path) if is_drawing_file(path) else None
    if side is None:
        return ()
    return ((SIDECAR, str(side), _digest(side, where, f"material file {side.name!r}")),)


def key_blob_params(command: str, params: dict, inputs: Sequence[tuple[str, str, str]]) -> dict:
    """The parameters that enter the key: outputs and display options left out, input
    files replaced by ``{"sha256": ...}`` of their bytes (a drawing's material file as
    ``sidecar``)."""
    from ..reports import key_params

    digests = {name: digest for name, _, digest in inputs}
    out = {SIDECAR: {"sha256": digests[SIDECAR]}} if SIDECAR in digests else {}
    for name, value in key_params(command, params).items():
        if name in digests:
            value = {"sha256": digests[name]}
        out[_KEY_NAMES.get(name, name)] = value
    return out


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
        Report command.
    params : dict
        The command's parameter values after parsing (defaults included, outputs left
        out), input files replaced by ``{"sha256": ...}`` of their bytes;
        JSON-serialisable.
    version : str, optional
        Package version (default: the installed ``deformclosure.__version__``).

    Returns
    -------
    str
        64 hex digits.

    Examples
    --------
    >>> len(job_key("0" * 64, "mesh", {"max_area": None}, "1.0"))
    64
    """
    return sha256(_key_blob(digest, command, params, version or _version()))


def job_ident(digest: str, command: str, params: dict) -> str:
    """The job's key without the version: the same job list keeps its identity across
    versions of the package."""
    return sha256(_key_blob(digest, command, params, None))


def list_identity(jobs: Sequence[Job]) -> str:
    """Identity of a job list: sha256 of its sorted, distinct job idents."""
    return sha256("\n".join(sorted({j.ident or j.key for j in jobs})).encode())
