"""Job lists: a folder of part or mesh files, or a list of jobs in JSON or CSV.

A job list is untrusted text: fields of at most :data:`~deformclosure.batch.jobs.MAX_FIELD`
characters, no NUL, and every file it names inside its own folder (symbolic links
resolved) unless ``allow_outside``. Every error is one line naming the file, the line
(CSV) or entry (JSON) and the field.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import Any, Sequence

from ..errors import BatchError
from .jobs import MAX_FIELD, Job, check_field

__all__ = ["load_jobs"]

#: Suffixes meshio knows that are too generic to mean "a mesh" in a folder of parts.
_AMBIGUOUS_SUFFIXES = frozenset({".dat", ".xml", ".svg", ".wkt", ".node", ".ele", ".txt"})


def _folder_files(folder: Path) -> list[Path]:
    """The part, mesh and drawing files of ``folder``; a drawing's material file
    (``<name>.material.json``) travels with its drawing and is no job of its own."""
    import meshio

    from ..drawing import DRAWING_SUFFIXES, material_path_beside

    suffixes = (tuple(sorted(set(meshio.extension_to_filetypes) - _AMBIGUOUS_SUFFIXES))
                + (".json",) + DRAWING_SUFFIXES)
    try:
        files = sorted(f for f in folder.iterdir()
                       if f.is_file() and not f.name.startswith(".")
                       and f.name.lower().endswith(suffixes))
    except OSError as err:
        raise BatchError(f"{folder}: cannot list the folder ({err.strerror or err})") from None
    sidecars = {material_path_beside(f) for f in files if f.suffix.lower() in DRAWING_SUFFIXES}
    return [f for f in files if f not in sidecars]


def load_jobs(path: str | os.PathLike, command: str = "plan",
              options: Sequence[str] | str = (), allow_outside: bool = False) -> list[Job]:
    """Read a batch: a folder of part or mesh files, or a job list (JSON or CSV).

    Parameters
    ----------
    path : path-like
        * a folder: one job per part, mesh or drawing file in it (``*.json``, the mesh
          formats meshio reads, ``.dxf`` and ``.svg`` with their ``<name>.material.json``;
          not recursive), each running ``command`` with ``options``;
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
                        check_field(f"{where}: ", name, value)
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
            check_field(f"{where}: ", field_name(col), cell)
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
