"""Writing output files so that a kill, a crash or a full disk never destroys a good one.

Every writer of the package (JSON reports, meshes, plots, slices, CSV) writes into a
temporary file in the target's own folder and renames it onto the target only when the
write has succeeded: ``os.replace`` is atomic on POSIX and Windows, so the target is at
any moment either the previous file or the complete new one.
"""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

from .errors import DeformClosureError

__all__ = ["atomic_path", "write_text_atomic", "check_outputs"]


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
