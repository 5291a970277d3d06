"""Writing output files so that a kill, a crash or a full disk never destroys a good one,
and a device or a FIFO given as the output is written to, never replaced.

Every writer of the package (JSON reports, meshes, plots, fields, slices, CSV) goes
through :func:`atomic_path`, the one output-opening rule (:func:`output_target`):

- a regular file, or a name that does not exist yet: the writer writes into a temporary
  file in the target's own folder, renamed onto the target only when the write has
  succeeded (``os.replace`` is atomic on POSIX and Windows, so the target is at any
  moment either the previous file or the complete new one);
- an existing character or block device or FIFO (``/dev/null``, ``/dev/stdout``, a named
  pipe): the finished content is written *into* it, in place, through a non-blocking
  open that waits at most :data:`STREAM_OPEN_WAIT` seconds for a FIFO's reader; a full
  device (``ENOSPC``) or a FIFO nobody reads is one line naming the target;
- a folder or a socket: refused with one line;
- a symbolic link: followed to what it names, which the same rule is applied to (the
  link itself is kept).

Nothing is ever renamed over a file that is not regular.
"""

from __future__ import annotations

import errno
import json
import math
import os
import stat
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

from .errors import DeformClosureError

__all__ = ["atomic_path", "write_text_atomic", "check_outputs", "json_safe", "json_text",
           "PLOT_FORMATS", "plot_target", "plot_file", "animation_file",
           "write_json", "output_target", "STREAM_OPEN_WAIT"]

#: Longest wait (s) for a process to open a FIFO output for reading.
STREAM_OPEN_WAIT = 1.5


def output_target(path: str | Path) -> tuple[str, Path]:
    """What writing to ``path`` means: the kind of target and the path to write.

    Parameters
    ----------
    path : str or Path
        The output as given (symbolic links are followed).

    Returns
    -------
    kind : {"file", "stream"}
        ``"file"``: a regular file or a missing one, replaced atomically; ``"stream"``: an
        existing character or block device or FIFO, written in place.
    where : Path
        ``"file"``: the real path (links resolved; a link to a missing file names the file
        to create); ``"stream"``: ``path`` itself (the kernel follows the links, which
        also keeps ``/dev/stdout`` meaning this process's standard output).

    Raises
    ------
    DeformClosureError
        A folder, a socket or another kind of file, or a path that cannot be examined
        (a loop of links, a file in its parent chain).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as d:
    ...     output_target(pathlib.Path(d) / "new.json")[0]
    'file'
    >>> output_target("/dev/null")
    ('stream', PosixPath('/dev/null'))
    """
    p = Path(path)
    try:
        mode = os.stat(p).st_mode
    except (FileNotFoundError, NotADirectoryError):   # to be created (or refused later)
        return "file", Path(os.path.realpath(p))
    except OSError as err:
        raise DeformClosureError(f"{path}: cannot write there "
                                 f"({err.strerror or err}); give another output file") from None
    if stat.S_ISREG(mode):
        return "file", Path(os.path.realpath(p))
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) or stat.S_ISFIFO(mode):
        return "stream", p
    if stat.S_ISDIR(mode):
        raise DeformClosureError(f"{path}: is a folder; give a file name for the output")
    kind = "a socket" if stat.S_ISSOCK(mode) else "not a regular file, device or FIFO"
    raise DeformClosureError(f"{path}: {kind}; cannot write an output there, give a file name")


@contextmanager
def atomic_path(path: str | Path, what: str = "output") -> Iterator[Path]:
    """A temporary path (same suffix, so format detection still works) for the writer to
    write ``path``'s content to; when the ``with`` block succeeds it is renamed onto a
    regular (or missing) target, or copied into a device or FIFO (:func:`output_target`);
    it is removed when the block fails.

    Raises
    ------
    DeformClosureError
        A target that cannot be written (see :func:`output_target`), and for a device or
        FIFO: no reader within :data:`STREAM_OPEN_WAIT` s, a full device, a write error.
    """
    kind, target = output_target(path)
    if kind == "stream":
        # The content is made in the temporary folder (never beside a device, e.g. in
        # /dev), then written into the target in one go.
        fd, tmp = tempfile.mkstemp(prefix="deformclosure-", suffix=Path(path).suffix or ".tmp")
        os.close(fd)
        try:
            yield Path(tmp)
            _write_stream(Path(tmp), Path(path), what)
        finally:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        return
    folder = target.parent
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=target.suffix or ".tmp",
                               dir=folder)
    os.close(fd)
    try:
        yield Path(tmp)
        with open(tmp, "rb+") as fh:       # durable before it replaces the old file
            os.fsync(fh.fileno())
        os.chmod(tmp, _mode_for(target))   # mkstemp makes 0600; keep the usual permissions
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _open_stream(path: Path, what: str) -> int:
    """A blocking write descriptor of the device or FIFO ``path``, opened without blocking:
    a FIFO without a reader is retried for :data:`STREAM_OPEN_WAIT` s, then refused."""
    nonblock = getattr(os, "O_NONBLOCK", 0)             # POSIX; Windows has no FIFOs
    flags = os.O_WRONLY | nonblock | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
    deadline = time.monotonic() + STREAM_OPEN_WAIT
    while True:
        try:
            fd = os.open(path, flags)
            break
        except OSError as err:
            # ENXIO on a FIFO: no process has it open for reading (yet)
            if err.errno != errno.ENXIO or not _is_fifo(path):
                raise DeformClosureError(f"{path}: cannot write {what} "
                                         f"({err.strerror or err})") from None
            if time.monotonic() >= deadline:
                raise DeformClosureError(
                    f"{path}: a FIFO that no process opened for reading within "
                    f"{STREAM_OPEN_WAIT:g} s; start the reader first, or give a file name "
                    f"for the {what}") from None
            time.sleep(0.02)
    if nonblock:
        os.set_blocking(fd, True)          # the reader sets the pace from now on
    return fd


def _is_fifo(path: Path) -> bool:
    try:
        return stat.S_ISFIFO(os.stat(path).st_mode)
    except OSError:
        return False


def _write_stream(src: Path, path: Path, what: str) -> None:
    """Write the whole of ``src`` into the device or FIFO ``path``; one-line errors."""
    fd = _open_stream(path, what)
    try:
        with open(src, "rb") as fh:
            while chunk := fh.read(1 << 16):
                view = memoryview(chunk)
                while view:
                    view = view[os.write(fd, view):]
    except OSError as err:                 # ENOSPC (a full device), EPIPE (reader gone), ...
        raise DeformClosureError(f"{path}: cannot write {what} "
                                 f"({err.strerror or err})") from None
    finally:
        os.close(fd)


def _mode_for(target: Path) -> int:
    """The target's current permissions, or those a new file gets under the umask."""
    try:
        return target.stat().st_mode & 0o777
    except OSError:
        mask = os.umask(0)
        os.umask(mask)
        return 0o666 & ~mask


def write_text_atomic(path: str | Path, text: str, what: str = "file") -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically; one-line error on failure."""
    try:
        with atomic_path(path, what) as tmp:
            tmp.write_text(text, encoding="utf-8")
    except OSError as err:
        raise DeformClosureError(f"{path}: cannot write {what} ({err.strerror or err})") from None


def json_safe(obj: Any) -> Any:
    """``obj`` with numpy scalars and arrays made Python, tuples made lists, keys made
    strings, and every non-finite float made ``None`` (SPEC §5: JSON has no infinity; a
    report says ``"U_A_infinite": true`` beside the ``null``).

    Examples
    --------
    >>> import numpy as np
    >>> json_safe({"U_A": np.inf, "k": np.float32(2.5), "jaws": (np.int64(3), 4)})
    {'U_A': None, 'k': 2.5, 'jaws': [3, 4]}
    """
    import numpy as np

    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    return obj


def json_text(obj: Any, indent: int | None = 2, compact: bool = False) -> str:
    """The package's one JSON encoding: :func:`json_safe`, then strict JSON (no ``NaN`` or
    ``Infinity`` can get through). ``compact``: no spaces and sorted keys (stored rows).

    Examples
    --------
    >>> json_text({"b": 1.0, "a": float("nan")}, compact=True)
    '{"a":null,"b":1.0}'
    """
    if compact:
        return json.dumps(json_safe(obj), sort_keys=True, separators=(",", ":"), allow_nan=False)
    return json.dumps(json_safe(obj), indent=indent, allow_nan=False)


def write_json(path: str | Path, obj: Any, what: str = "report", indent: int | None = 2) -> None:
    """Write ``obj`` as JSON (:func:`json_text`) to ``path`` atomically; one-line errors."""
    write_text_atomic(path, json_text(obj, indent=indent) + "\n", what)


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_outputs(files: list, folders: list = (), inputs: list = ()) -> None:
    """Refuse, before any work, outputs that cannot be written or would overwrite an input.

    Parameters
    ----------
    files : list of path or None
        Output files (``None`` and ``"-"``, stdout, are skipped).
    folders : list of path or None
        Output folders (``--plot``): created later; no part of them may be a file.
    inputs : list of path or None
        Input files that no output may replace.
    """
    ins = [Path(p) for p in inputs if p is not None]
    for f in files:
        if f is None or str(f) == "-":
            continue
        p = Path(f)
        kind, where = output_target(p)      # refuses a folder or a socket
        if any(_same_file(p, i) for i in ins):
            raise DeformClosureError(f"{f}: is an input of this command; write the output to "
                                     "another file")
        if kind == "stream":                # written in place: its folder is not written
            continue
        parent = where.parent
        if not parent.is_dir():
            raise DeformClosureError(f"{f}: folder {parent} does not exist; create it first")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise DeformClosureError(f"{f}: folder {parent} is not writable")
    for d in folders:
        if d is None:
            continue
        p = Path(d)
        for q in [p, *p.parents]:
            if q.exists():
                if not q.is_dir():
                    raise DeformClosureError(f"{d}: {q} is a file, not a folder; choose another "
                                             "--plot folder")
                if not os.access(q, os.W_OK | os.X_OK):
                    raise DeformClosureError(f"{d}: folder {q} is not writable")
                break


# ----------------------------------------------------------------------------- pictures

#: Picture formats ``--plot`` writes, by file suffix.
PLOT_FORMATS = ("png", "svg", "pdf")


def plot_target(value: str | Path, flag: str = "--plot") -> tuple[Path, str, str | None]:
    """Where and how ``--plot VALUE`` writes its figures: ``(folder, format, stem)``.

    A path whose suffix is one of :data:`PLOT_FORMATS` (any case) names a file: its
    suffix sets the format of every figure, and its stem prefixes their names (``stem``;
    a command drawing one figure writes that file itself, see :func:`plot_file`). A path
    without a suffix, or an existing folder, is a folder of PNG figures (``stem`` is
    ``None``) — unless it exists and is no folder (``/dev/stdout``, a FIFO): then PNG
    goes into it. Any other suffix is refused, before any work.

    Parameters
    ----------
    value : str or Path
        The option's value.
    flag : str
        The option's spelling, for the message.

    Returns
    -------
    folder : Path
        Where the figures go (created by the writer).
    format : str
        ``"png"``, ``"svg"`` or ``"pdf"``.
    stem : str or None
        The file name's stem, or ``None`` for a folder.

    Raises
    ------
    DeformClosureError
        An unknown suffix: one line listing the choices.

    Examples
    --------
    >>> plot_target("out/fig.SVG")
    (PosixPath('out'), 'svg', 'fig')
    >>> plot_target("out")
    (PosixPath('out'), 'png', None)
    >>> plot_target("out/fig.jpg")
    Traceback (most recent call last):
    ...
    deformclosure.errors.DeformClosureError: --plot out/fig.jpg: unknown picture format '.jpg'; choose .png, .svg or .pdf (or a folder)
    """
    p = Path(value)
    if str(value) == "":
        raise DeformClosureError(f"{flag}: empty path; give a folder or a .png, .svg or .pdf file")
    suffix = p.suffix.lower()
    if p.is_dir():
        return p, "png", None
    if not suffix:
        if p.exists():              # a device or a FIFO (/dev/stdout), a file: PNG into it
            return p.parent, "png", p.name
        return p, "png", None
    if suffix[1:] in PLOT_FORMATS:
        return p.parent, suffix[1:], p.stem
    choices = ", ".join(f".{f}" for f in PLOT_FORMATS[:-1]) + f" or .{PLOT_FORMATS[-1]}"
    raise DeformClosureError(f"{flag} {value}: unknown picture format '{p.suffix}'; choose "
                             f"{choices} (or a folder)")


def plot_file(value: str | Path, name: str, single: bool = False) -> Path:
    """The file of figure ``name`` (no suffix) for ``--plot VALUE`` (:func:`plot_target`).

    A folder gets ``<folder>/<name>.png``; a file ``dir/fig.svg`` gets
    ``dir/fig_<name>.svg`` — or, for a command drawing a single figure (``single``),
    ``dir/fig.svg`` itself.

    Examples
    --------
    >>> str(plot_file("out", "quality")), str(plot_file("out/fig.pdf", "quality"))
    ('out/quality.png', 'out/fig_quality.pdf')
    >>> str(plot_file("check.svg", "check", single=True))
    'check.svg'
    """
    folder, fmt, stem = plot_target(value)
    if stem is None:
        return folder / f"{name}.{fmt}"
    return Path(value) if single else folder / f"{stem}_{name}.{fmt}"


def animation_file(value: str | Path, name: str, flag: str = "--animate") -> Path:
    """The animated GIF of ``name`` (no suffix) beside the pictures of ``--plot VALUE``
    (:func:`plot_target`): ``<folder>/<name>.gif`` for a folder, ``dir/<stem>_<name>.gif``
    for a file ``dir/<stem>.<png|svg|pdf>`` — whatever the pictures' format.

    Raises
    ------
    DeformClosureError
        ``--plot`` naming a device or a FIFO (``/dev/null``): the GIF has nowhere beside
        it to go.

    Examples
    --------
    >>> str(animation_file("out", "escape")), str(animation_file("out/fig.pdf", "escape"))
    ('out/escape.gif', 'out/fig_escape.gif')
    """
    folder, _, stem = plot_target(value)
    p = Path(value)
    if p.exists() and not (p.is_dir() or p.is_file()):
        raise DeformClosureError(f"{flag}: --plot {value} is a device or a pipe, with no folder "
                                 "for the GIF beside it; give --plot a folder or a "
                                 ".png/.svg/.pdf file")
    return folder / (f"{name}.gif" if stem is None else f"{stem}_{name}.gif")
