"""Reading the package's input files (JSON and text) safely, with one-line errors.

Every input file goes through :func:`read_text_file` (a regular file of bounded size, in
UTF-8 — or UTF-16 with a byte-order mark) and JSON through :func:`parse_json`, which
refuses what the standard parser lets through or dies on: duplicate keys (``"units"``
twice would silently keep the last), integers too long to be a length or a count, and
nesting deeper than any input of ours needs. (``NaN``/``Infinity`` parse, so that the
readers' field checks name the field.)
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Union

from .errors import DeformClosureError

__all__ = ["read_json", "read_text_file", "parse_json", "check_input_file", "MAX_INPUT_BYTES",
           "Source", "InputFile", "as_source"]

#: Largest input file read (bytes): far above any part, mesh or job list we write.
MAX_INPUT_BYTES = 256 * 2**20
#: Deepest JSON nesting accepted (a mesh JSON needs 4).
MAX_DEPTH = 64
#: Longest integer literal accepted (digits); longer ones cannot be meant.
MAX_INT_DIGITS = 30


def check_input_file(path: str | Path, error: type[DeformClosureError], what: str) -> None:
    """Refuse what is not a regular file of bounded size (a FIFO or ``/dev/zero`` would
    hang or exhaust memory)."""
    path = Path(path)
    try:
        st = path.stat()
    except OSError as err:
        raise error(f"{path}: cannot read the {what} ({err.strerror})") from None
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{path}: not a regular file; give the {what} as a file")
    if st.st_size > MAX_INPUT_BYTES:
        raise error(f"{path}: {st.st_size / 2**20:.0f} MiB is too large for a {what} "
                    f"(limit {MAX_INPUT_BYTES // 2**20} MiB)")


@dataclass(frozen=True)
class Source:
    """An input file read once: the name it is shown by and its bytes.

    Every reader of the package accepts a :class:`Source` wherever it accepts a path, so
    a batch worker parses exactly the bytes its job key was computed from, and a worker
    on another machine needs no file system shared with the batch process.

    Attributes
    ----------
    name : str
        How the file is named in messages (the path the user gave); its suffix selects
        the format.
    data : bytes
        The file's content.
    sidecar : Source, optional
        A file that belongs to this one and travels with it: the material file
        ``<name>.material.json`` beside a drawing (:func:`deformclosure.drawing.material_file_beside`).

    Examples
    --------
    >>> src = Source("part.json", b'{"units": "mm"}')
    >>> src.suffix, len(src.sha256)
    ('.json', 64)
    """

    name: str
    data: bytes
    sidecar: "Source | None" = None

    @property
    def suffix(self) -> str:
        """The name's last suffix in lower case (``".json"``)."""
        return Path(self.name).suffix.lower()

    @property
    def sha256(self) -> str:
        """Hex SHA-256 of the bytes."""
        return hashlib.sha256(self.data).hexdigest()

    def __str__(self) -> str:
        return self.name

    @classmethod
    def read(cls, path: str | os.PathLike, error: type[DeformClosureError] = DeformClosureError,
             what: str = "input file", name: str | None = None) -> "Source":
        """Read a regular input file of bounded size (:func:`check_input_file`)."""
        p = Path(path)
        check_input_file(p, error, what)
        try:
            data = p.read_bytes()
        except OSError as err:
            raise error(f"{p}: cannot read the {what} ({err.strerror})") from None
        return cls(str(p) if name is None else name, data)


#: What the readers accept: a path or a :class:`Source`.
InputFile = Union[str, os.PathLike, Source]


def as_source(file: InputFile, error: type[DeformClosureError] = DeformClosureError,
              what: str = "input file") -> Source:
    """``file`` as a :class:`Source` (read from disk when it is a path)."""
    return file if isinstance(file, Source) else Source.read(file, error, what)


def read_text_file(path: InputFile, error: type[DeformClosureError], what: str) -> str:
    """The text of a regular input file (or a :class:`Source`): UTF-8 (BOM allowed) or
    UTF-16 with a BOM."""
    src = as_source(path, error, what)
    path, raw = src.name, src.data
    try:
        if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
            return raw.decode("utf-16")
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise error(f"{path}: the {what} is not UTF-8 text (byte {err.start}); save it as UTF-8") from None


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict:
    out: dict = {}
    for k, v in pairs:
        if k in out:
            raise ValueError(f"key {k!r} appears twice in one object; keep one")
        out[k] = v
    return out


def _int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise ValueError(f"integer with {len(text)} digits; no value here needs more than "
                         f"{MAX_INT_DIGITS}")
    return int(text)


def _depth_ok(text: str) -> bool:
    """Whether brackets nest at most MAX_DEPTH deep (strings skipped), in linear time."""
    depth = 0
    for m in re.finditer(r'"(?:\\.|[^"\\])*"|[\[\]{}]', text):
        t = m.group()
        if t in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                return False
        elif t in "]}":
            depth -= 1
    return True


def parse_json(text: str, source: str, error: type[DeformClosureError], what: str) -> Any:
    """Parse JSON ``text`` from ``source`` strictly (module docstring); one-line errors."""
    if not _depth_ok(text):
        raise error(f"{source}: JSON nested more than {MAX_DEPTH} deep; not a {what}")
    try:
        # NaN/Infinity parse: the field validators then name the offending field.
        return json.loads(text, object_pairs_hook=_no_duplicates, parse_int=_int)
    except json.JSONDecodeError as err:
        raise error(f"{source}: not valid JSON (line {err.lineno} column {err.colno}: {err.msg}); "
                    f"fix the {what}'s syntax") from None
    except (ValueError, RecursionError) as err:
        raise error(f"{source}: {err}") from None


def read_json(path: InputFile, error: type[DeformClosureError], what: str) -> Any:
    """Parse the JSON file ``path`` (see :func:`read_text_file` and :func:`parse_json`).

    Parameters
    ----------
    path : str, Path or Source
    error : DeformClosureError subclass
        Raised, with a one-line message naming the file, when the file cannot be read or
        is not valid JSON.
    what : str
        What the file is, for the message (``"part file"``, ``"finger file"``).
    """
    return parse_json(read_text_file(path, error, what), str(path), error, what)
