"""Writing output files so that a kill, a crash or a full disk never destroys a good one.

Every writer of the package (JSON reports, meshes, plots, slices, CSV) writes into a
temporary file in the target's own folder and renames it onto the target only when the
write has succeeded: ``os.replace`` is atomic on POSIX and Windows, so the target is at
any moment either the previous file or the complete new one.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

from .errors import DeformClosureError

__all__ = ["atomic_path", "write_text_atomic", "check_outputs", "json_safe", "json_text",
           "write_json"]


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix, so format detection still works);
    renamed onto ``path`` when the ``with`` block succeeds, removed when it fails."""
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
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
        with atomic_path(path) as tmp:
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
        if p.is_dir():
            raise DeformClosureError(f"{f}: is a folder; give a file name for the output")
        if any(_same_file(p, i) for i in ins):
            raise DeformClosureError(f"{f}: is an input of this command; write the output to "
                                     "another file")
        parent = p.parent if str(p.parent) else Path(".")
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
