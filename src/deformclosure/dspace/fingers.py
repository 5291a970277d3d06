"""The finger file (SPEC §5): reading and writing finger sets for ``check`` and ``slice``.

The finger bodies themselves are :mod:`deformclosure.contact.bodies` (one hierarchy for
every contact model); this module is their file format.

Finger file
-----------
A JSON object with the length ``units`` (``"m"``, ``"mm"``, ``"cm"`` or ``"in"``) and a
non-empty list ``fingers``; every entry has a ``type`` and that type's fields only::

    {"units": "mm",
     "fingers": [
        {"type": "point",     "at": [x, y]},
        {"type": "disc",      "center": [x, y], "radius": r},
        {"type": "polygon",   "vertices": [[x, y], [x, y], [x, y], ...]},
        {"type": "halfplane", "point": [x, y], "normal": [nx, ny]}]}

A half-plane finger occupies the side its normal points *away* from,
``{x : (x - point) . normal <= 0}``; the normal points towards the part. Polygon
vertices may be given in either orientation (they are stored counter-clockwise) and
must form a convex polygon of positive area. Unknown fields, unknown types, non-finite
numbers, a non-positive radius, a zero normal or a non-convex polygon raise
:class:`deformclosure.errors.FingerError` with a one-line message that names the field
and says how to fix it.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal, Sequence, Union

import numpy as np

from ..contact.bodies import (FINGER_TYPES, DiscFinger, Finger, HalfPlaneFinger, PointFinger,
                              PolygonFinger, as_fingers)
from ..errors import FingerError
from ..jsonfile import InputFile, as_source, read_json
from ..units import LENGTH_UNITS

__all__ = [
    "Finger",
    "PointFinger",
    "DiscFinger",
    "PolygonFinger",
    "HalfPlaneFinger",
    "FINGER_TYPES",
    "as_fingers",
    "load_fingers",
    "fingers_from_dict",
    "fingers_to_dict",
    "write_fingers",
]

# --------------------------------------------------------------------------- file format

try:  # pydantic is a core dependency; keep the import local to this module.
    from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError
except ImportError as err:  # pragma: no cover
    raise ImportError("deformclosure.dspace.fingers needs pydantic>=2") from err

#: Largest coordinate or length magnitude accepted in a finger file (file units).
_MAX_LENGTH = 1e12


def _real(v: Any) -> float:
    """A JSON number, not a boolean or a string (which pydantic's lax mode would coerce)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"must be a number, got {v!r:.40}")
    if not (math.isfinite(v) and abs(v) <= _MAX_LENGTH):
        raise ValueError(f"must be a finite number of at most {_MAX_LENGTH:g} in magnitude")
    return float(v)


_Num = Annotated[float, BeforeValidator(_real)]
_Pt = tuple[_Num, _Num]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, strict=False)


class _PointModel(_Model):
    type: Literal["point"]
    at: _Pt


class _DiscModel(_Model):
    type: Literal["disc"]
    center: _Pt
    radius: _Num


class _PolygonModel(_Model):
    type: Literal["polygon"]
    vertices: list[_Pt]


class _HalfPlaneModel(_Model):
    type: Literal["halfplane"]
    point: _Pt
    normal: _Pt


_FingerModel = Annotated[
    Union[_PointModel, _DiscModel, _PolygonModel, _HalfPlaneModel], Field(discriminator="type")
]


class _FingerFile(_Model):
    units: Literal["m", "mm", "cm", "in"]
    fingers: list[_FingerModel]


_FIELDS = {
    "point": "type, at",
    "disc": "type, center, radius",
    "polygon": "type, vertices",
    "halfplane": "type, point, normal",
}
_HINTS = {
    "units": 'give "units" as one of "m", "mm", "cm", "in"',
    "fingers": 'give "fingers" as a non-empty list of finger objects',
    "at": "give the point as [x, y]",
    "center": "give the centre as [x, y]",
    "radius": "give the radius as a positive number in the file's units",
    "vertices": "give the polygon as a list of [x, y] vertices",
    "point": "give a point on the boundary line as [x, y]",
    "normal": "give the normal as [nx, ny], pointing out of the finger towards the part",
    "type": "use one of point, disc, polygon, halfplane",
}


def _loc_str(loc: Sequence[Any]) -> tuple[str, str | None]:
    """Format a pydantic location like ``fingers[2].radius``; also return the field name."""
    parts = list(loc)
    # drop the discriminator tag pydantic inserts after the list index
    if len(parts) >= 3 and parts[0] == "fingers" and isinstance(parts[1], int) and parts[2] in _FIELDS:
        del parts[2]
    parts = [p for p in parts if p != "function-after"]
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else ("." if out else "") + str(p)
    field = next((str(p) for p in reversed(parts) if isinstance(p, str)), None)
    return out or "(top level)", field


def _message(err: ValidationError, source: str, raw: Any) -> str:
    errors = err.errors()
    rank = {"extra_forbidden": 0, "union_tag_invalid": 1, "union_tag_not_found": 1}
    e = min(errors, key=lambda x: rank.get(x["type"], 2))
    where, field = _loc_str(e["loc"])
    kind = e["type"]
    if kind in ("missing", "too_long", "too_short") and e["loc"] and isinstance(e["loc"][-1], int):
        where = where[: where.rfind("[")]
        return f"{source}: {where}: expected [x, y] with exactly 2 numbers"
    if kind in ("tuple_type", "list_type") and field in ("at", "center", "point", "normal", "vertices"):
        return f"{source}: {where}: expected a list; {_HINTS[field]}"
    if kind == "union_tag_invalid":
        tag = e.get("input", {}).get("type") if isinstance(e.get("input"), dict) else None
        return f"{source}: {where}.type: unknown finger type {tag!r}; use one of point, disc, polygon, halfplane"
    if kind == "union_tag_not_found":
        return f'{source}: {where}: missing "type"; use one of point, disc, polygon, halfplane'
    if kind == "extra_forbidden":
        ftype = _finger_type_at(raw, e["loc"])
        valid = _FIELDS.get(ftype, "units, fingers") if ftype else "units, fingers"
        what = f"a {ftype} finger" if ftype else "the finger file"
        return f"{source}: {where}: unknown field; valid fields for {what}: {valid}"
    if kind == "missing":
        ftype = _finger_type_at(raw, e["loc"])
        hint = _HINTS.get(field or "", "")
        if ftype:
            return f"{source}: {where}: missing; a {ftype} finger needs {_FIELDS[ftype]}"
        return f"{source}: {where}: missing; {hint}".rstrip("; ")
    if kind in ("model_type", "dict_type", "model_attributes_type"):
        hint = _HINTS.get(field or "", "see the finger file format in docs/dspace.md")
        return f"{source}: {where}: expected a JSON object; {hint}"
    if kind == "literal_error" and field == "units":
        return f"{source}: units: {e.get('input')!r} is not a length unit; {_HINTS['units']}"
    hint = _HINTS.get(field or "", "")
    msg = e["msg"].rstrip(".").removeprefix("Value error, ")
    return f"{source}: {where}: {msg}" + (f"; {hint}" if hint else "")


def _finger_type_at(raw: Any, loc: Sequence[Any]) -> str | None:
    if len(loc) >= 2 and loc[0] == "fingers" and isinstance(loc[1], int):
        try:
            t = raw["fingers"][loc[1]].get("type")
        except (KeyError, IndexError, TypeError, AttributeError):
            return None
        return t if t in _FIELDS else None
    return None


def _convex_ccw(vertices: np.ndarray, where: str) -> np.ndarray:
    """Validate a convex polygon, drop collinear vertices, return it counter-clockwise."""
    v = np.asarray(vertices, dtype=float)
    if len(v) < 3:
        raise FingerError(f"{where}.vertices: a polygon needs at least 3 vertices, got {len(v)}")
    scale = float(np.ptp(v, axis=0).max()) or 1.0
    e = np.roll(v, -1, axis=0) - v
    if np.any(np.linalg.norm(e, axis=1) <= 1e-12 * scale):
        raise FingerError(f"{where}.vertices: repeated vertex; list each corner once without closing the ring")
    area2 = float(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]))
    if abs(area2) <= 1e-12 * scale**2:
        raise FingerError(f"{where}.vertices: the polygon has zero area; give at least 3 non-collinear corners")
    if area2 < 0:
        v = v[::-1]
        e = np.roll(v, -1, axis=0) - v
    prev = np.roll(e, 1, axis=0)  # edge arriving at vertex i
    cross = prev[:, 0] * e[:, 1] - prev[:, 1] * e[:, 0]  # turn at vertex i
    lens = np.linalg.norm(e, axis=1) * np.linalg.norm(prev, axis=1)
    if np.any(cross < -1e-12 * lens):
        raise FingerError(
            f"{where}.vertices: the polygon is not convex; split it into convex fingers or use its convex hull"
        )
    # winding must be simple: total turning of a convex polygon is exactly 2*pi
    ang = np.arctan2(cross, np.einsum("ij,ij->i", prev, e))
    if abs(ang.sum() - 2 * np.pi) > 1e-6:
        raise FingerError(f"{where}.vertices: the polygon winds more than once; list the corners in order once")
    v = v[cross > 1e-12 * lens]  # drop collinear corners (they are face points)
    return v


def fingers_from_dict(data: Any, source: str = "fingers") -> tuple[Finger, ...]:
    """Build fingers from a finger-file dictionary (lengths converted to metres).

    Parameters
    ----------
    data : dict
        ``{"units": ..., "fingers": [...]}`` as described in the module docstring.
    source : str
        Name used at the start of error messages (usually the file name).

    Returns
    -------
    tuple of Finger
        In file order, SI units (m).

    Raises
    ------
    FingerError
        One-line message naming the offending field and the fix.

    Examples
    --------
    >>> fingers_from_dict({"units": "mm", "fingers": [{"type": "disc", "center": [0, 0], "radius": 2}]})
    (DiscFinger(center=(0.0, 0.0), radius=0.002),)
    """
    if not isinstance(data, dict):
        raise FingerError(f'{source}: expected a JSON object {{"units": ..., "fingers": [...]}}')
    try:
        model = _FingerFile.model_validate(data)
    except ValidationError as err:
        raise FingerError(_message(err, source, data)) from None
    if not model.fingers:
        raise FingerError(f"{source}: fingers: the list is empty; {_HINTS['fingers']}")
    f = LENGTH_UNITS[model.units]
    out: list[Finger] = []
    for i, m in enumerate(model.fingers):
        where = f"{source}: fingers[{i}]"
        if isinstance(m, _PointModel):
            out.append(PointFinger(at=(m.at[0] * f, m.at[1] * f)))
        elif isinstance(m, _DiscModel):
            if not m.radius > 0:
                raise FingerError(f"{where}.radius: must be > 0, got {m.radius:g}; {_HINTS['radius']}")
            out.append(DiscFinger(center=(m.center[0] * f, m.center[1] * f), radius=m.radius * f))
        elif isinstance(m, _PolygonModel):
            v = _convex_ccw(np.asarray(m.vertices, dtype=float) * f, where)
            out.append(PolygonFinger(corners=tuple((float(x), float(y)) for x, y in v)))
        else:
            n = np.asarray(m.normal, dtype=float)
            n = n / max(float(np.abs(n).max()), 1e-300)   # scale first: no overflow in the norm
            norm = float(np.linalg.norm(n))
            if not norm > 0 or not np.any(np.asarray(m.normal) != 0):
                raise FingerError(f"{where}.normal: must be non-zero; {_HINTS['normal']}")
            n = n / norm
            out.append(
                HalfPlaneFinger(point=(m.point[0] * f, m.point[1] * f), normal=(float(n[0]), float(n[1])))
            )
    return tuple(out)


def load_fingers(path: InputFile) -> tuple[Finger, ...]:
    """Read and validate a finger file (JSON); see the module docstring for the format.

    Parameters
    ----------
    path : str, Path or Source
        The finger file, or its bytes already read (:class:`deformclosure.jsonfile.Source`;
        messages then name ``Source.name``).

    Returns
    -------
    tuple of Finger
        SI units (m).

    Raises
    ------
    FingerError
        Unreadable file, invalid JSON or invalid content (one-line message).

    Examples
    --------
    >>> from deformclosure.jsonfile import Source
    >>> load_fingers(Source("f.json", b'{"units": "mm", "fingers": [{"type": "point", "at": [1, 2]}]}'))
    (PointFinger(at=(0.001, 0.002)),)
    """
    src = as_source(path, FingerError, "finger file")
    return fingers_from_dict(read_json(src, FingerError, "finger file"), source=src.name)


def fingers_to_dict(fingers: Sequence[Finger], units: str = "m") -> dict:
    """Inverse of :func:`fingers_from_dict`: a finger-file dictionary in ``units``."""
    if units not in LENGTH_UNITS:
        raise FingerError(f"units: {units!r} is not a length unit; {_HINTS['units']}")
    s = LENGTH_UNITS[units]
    return {"units": units, "fingers": [f.to_dict(s) for f in fingers]}


def write_fingers(fingers: Sequence[Finger], path: str | Path, units: str = "m") -> None:
    """Write a finger file (JSON) in ``units``, atomically."""
    from ..outputs import write_json

    write_json(path, fingers_to_dict(fingers, units), "finger file")
