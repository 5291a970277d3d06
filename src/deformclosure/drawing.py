"""Parts from CAD drawings: DXF (ezdxf) and SVG (svgelements).

A drawing gives the part's outline; every curve is flattened to a polyline whose chords
stay within ``tolerance`` of it. Open pieces (LINE, ARC, open polylines and splines, SVG
sub-paths) are chained end to end into closed loops; the loop of largest area is the
outer ring and every other loop must lie inside it (a hole). Problems — an open chain,
a branch, a self-intersecting loop, a loop outside the outer one — are reported on one
line naming the entity (DXF handle and type) or the SVG element id.

Units: a DXF file's ``$INSUNITS`` header, an SVG file's physical ``width``/``height``
(CSS: 96 px per inch, so plain user units are CSS pixels); ``units=`` overrides both
(one drawing unit, or one SVG user unit, is then one ``units``).

A drawing holds no material: it comes from the caller, or from a small JSON file beside
the drawing, ``<name>.material.json`` (a material object, optionally with ``units`` and
a ``mesh`` block of part-file mesh options). The part itself is made by
:func:`deformclosure.part.part_from_drawing` (this module reads the geometry and knows
nothing of parts, so ``part`` can read a drawing wherever it reads a part file).

Every reader takes a path or a :class:`~deformclosure.jsonfile.Source` (a file's name and
bytes, read once); the file beside the drawing is looked up only for a path.

Hostile drawings (issue 23) are refused on one line before the work they would cause:
an SVG is first scanned by a bare expat parser (:func:`_svg_prescan`) that refuses XML
entity declarations (they expand without bound — "billion laughs" — or name files to
read; no file a drawing names is ever opened), nesting deeper than :data:`MAX_SVG_DEPTH`,
more than :data:`MAX_ENTITIES` elements once ``<use>`` references are expanded (and
``<use>`` cycles), more than :data:`MAX_PATH_NUMBERS` numbers of path data or
:data:`MAX_SUBPATHS` sub-paths, and numbers beyond :data:`MAX_DRAWING_NUMBER`; a DXF
file's entities are counted from its tags before it is loaded and again as its block
references are exploded (at most :data:`MAX_BLOCK_DEPTH` deep). Every coordinate must be
finite and at most :data:`~deformclosure.limits.MAX_COORDINATE` in magnitude, and
``tolerance`` within :data:`TOLERANCE_RANGE` times the drawing's size, so flattening
never makes more than :data:`MAX_VERTICES` vertices (counted before they are made).
"""

from __future__ import annotations

import io
import math
import os
import re
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from .errors import PartError
from .jsonfile import InputFile, Source, as_source
from .limits import MAX_COORDINATE
from .units import LENGTH_UNITS

__all__ = ["DRAWING_SUFFIXES", "MAX_VERTICES", "MAX_ENTITIES", "MAX_PATH_NUMBERS",
           "MAX_SUBPATHS", "MAX_SVG_DEPTH", "MAX_BLOCK_DEPTH", "MAX_DRAWING_NUMBER",
           "TOLERANCE_RANGE", "Drawing", "read_drawing", "drawing_source", "is_drawing_file",
           "material_file_beside", "material_path_beside"]

#: File suffixes read as drawings.
DRAWING_SUFFIXES = (".dxf", ".svg")

# DXF $INSUNITS codes we accept: the unit and the factor to it (feet → inches, µm → mm).
_DXF_UNITS = {1: ("in", 1.0), 2: ("in", 12.0), 4: ("mm", 1.0), 5: ("cm", 1.0), 6: ("m", 1.0),
              7: ("m", 1e3), 8: ("in", 1e-6), 9: ("in", 1e-3), 10: ("in", 36.0),
              13: ("mm", 1e-3), 14: ("mm", 100.0)}
_DXF_NAMES = {0: "unitless", 3: "miles", 11: "ångström",
              12: "nanometres", 15: "decametres", 16: "hectometres", 17: "gigametres",
              18: "astronomical units", 19: "light years", 20: "parsecs"}

#: Entities that carry no outline (annotations): skipped without a word.
_ANNOTATIONS = {"TEXT", "MTEXT", "DIMENSION", "LEADER", "MLEADER", "POINT", "HATCH", "SOLID",
                "ATTDEF", "ATTRIB", "VIEWPORT", "IMAGE", "WIPEOUT", "TOLERANCE", "XLINE", "RAY"}
_CURVES = {"LINE", "LWPOLYLINE", "POLYLINE", "ARC", "CIRCLE", "ELLIPSE", "SPLINE"}

#: Most vertices a flattened drawing may have (beyond it the chord tolerance is too fine).
MAX_VERTICES = 2_000_000

#: Most curve entities (DXF, after exploding block references) or SVG elements (after
#: expanding ``<use>``) a drawing may have. Protects the readers' time: ezdxf and
#: svgelements take about 0.1 ms per entity (measured: 200 000 DXF lines 15 s, 100 000
#: SVG elements 11 s), and no mesh within ``limits.MAX_TRIANGLES`` has more boundary
#: vertices than this.
MAX_ENTITIES = 50_000

#: Most numbers of SVG path data (``d``, ``points``) in a drawing (measured: 200 000
#: numbers read and flattened in 1.8 s).
MAX_PATH_NUMBERS = 500_000

#: Most SVG sub-paths (``M`` commands) in a drawing: svgelements is quadratic in them
#: (20 000 in one path: 0.4 s, 40 000: 1.3 s, a million would take minutes).
MAX_SUBPATHS = 10_000

#: Deepest nesting of SVG elements (svgelements recurses per level).
MAX_SVG_DEPTH = 200

#: Deepest nesting of DXF block references (a block that holds itself would never end).
MAX_BLOCK_DEPTH = 32

#: Largest magnitude of a number in SVG geometry (beyond it svgelements' arc
#: parameterisation overflows and loops: an arc of radius 1e308 never returned).
MAX_DRAWING_NUMBER = 1e15

#: ``tolerance`` as a fraction of the drawing's bounding-box diagonal: below 1e-9 the
#: chords are finer than the coordinates' rounding (and a circle would need billions of
#: them), above 1 every curve is one chord.
TOLERANCE_RANGE = (1e-9, 1.0)


@dataclass(frozen=True)
class Drawing:
    """Closed loops of a drawing, in its units.

    Attributes
    ----------
    outer : ndarray, shape (n, 2)
        The outer ring (not closed).
    holes : tuple of ndarray
        The rings inside it.
    units : str
        Unit of the coordinates (one of ``m``, ``cm``, ``mm``, ``in``).
    """

    outer: np.ndarray
    holes: tuple[np.ndarray, ...]
    units: str


@dataclass
class _Piece:
    points: np.ndarray          # (k, 2), k >= 2
    closed: bool
    name: str                   # "LINE #2F" / "path 'slot'"


def is_drawing_file(path: InputFile) -> bool:
    """Whether ``path`` (a path or a :class:`~deformclosure.jsonfile.Source`) is read as a
    drawing (by its suffix)."""
    if isinstance(path, Source):
        return path.suffix in DRAWING_SUFFIXES
    return isinstance(path, (str, os.PathLike)) and Path(path).suffix.lower() in DRAWING_SUFFIXES


def read_drawing(path: InputFile, units: str | None = None, layer: str | None = None,
                 tolerance: float | None = None, default_units: str | None = None) -> Drawing:
    """Closed loops of a DXF or SVG drawing.

    Parameters
    ----------
    path : path-like or Source
        ``.dxf`` or ``.svg`` file, or its name and bytes
        (:class:`~deformclosure.jsonfile.Source`); messages name it.
    units : str, optional
        Unit of the drawing's coordinates, overriding its header.
    layer : str, optional
        DXF: read only this layer (SVG: only elements inside the group of this id).
    tolerance : float, optional
        Largest distance between a curve and its chords, in the drawing's units
        (default 0.1 % of the drawing's bounding-box diagonal).
    default_units : str, optional
        Unit of a DXF drawing whose header states none (``units`` overrides the header).

    Raises
    ------
    PartError
        One line naming the entity or element and what is wrong.

    Examples
    --------
    >>> from deformclosure.jsonfile import Source
    >>> svg = (b'<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="10mm" '
    ...        b'viewBox="0 0 20 10"><rect width="20" height="10"/>'
    ...        b'<circle cx="10" cy="5" r="2"/></svg>')
    >>> d = read_drawing(Source("plate.svg", svg))
    >>> d.units, len(d.outer), len(d.holes)
    ('mm', 4, 1)
    """
    src = drawing_source(path)
    _check_options(units, default_units, tolerance)
    if src.suffix == ".dxf":
        with _quiet_logger("ezdxf"):
            pieces, unit, scale = _dxf_pieces(src, units, layer, tolerance, default_units)
    elif src.suffix == ".svg":
        pieces, unit, scale = _svg_pieces(src, units, layer, tolerance)
    else:
        raise PartError(f"{src.name}: not a drawing; give a .dxf or .svg file")
    if not pieces:
        where = f" on layer {layer!r}" if layer is not None else ""
        raise PartError(f"{src.name}: no lines, arcs, polylines, circles, ellipses or splines"
                        f"{where}; draw the part's outline")
    loops = [(pts * scale, label) for pts, label in _chain(pieces, src.name)]
    return _assemble(loops, unit, src.name)


@contextmanager
def _quiet_logger(name: str):
    """Silence library logger ``name`` while reading, unless the caller configured logging:
    ezdxf logs damaged structure ("DXF Structure Warning: …") through Python's last-resort
    handler, which put a second line beside the CLI's one-line error."""
    import logging

    log = logging.getLogger(name)
    quiet = not log.hasHandlers() and not log.disabled
    if quiet:
        log.disabled = True
    try:
        yield
    finally:
        if quiet:
            log.disabled = False


def drawing_source(path: InputFile) -> Source:
    """The drawing as a Source (read once from a path)."""
    if not isinstance(path, (str, os.PathLike, Source)):
        raise PartError(f"drawing = {path!r}: give the path of a .dxf or .svg file")
    return as_source(path, PartError, "drawing")


def _check_options(units, default_units, tolerance) -> None:
    for given in (units, default_units):
        if given is not None and not (isinstance(given, str) and given in LENGTH_UNITS):
            raise PartError(f"--units = {given!r}: unknown length unit; use one of "
                            f"{', '.join(LENGTH_UNITS)}")
    if tolerance is not None and not (isinstance(tolerance, (int, float, np.number))
                                      and not isinstance(tolerance, bool)
                                      and math.isfinite(tolerance) and tolerance > 0):
        raise PartError(f"--tolerance = {tolerance!r}: must be a finite length > 0 in the "
                        "drawing's units")


def _detail(err: BaseException) -> str:
    """A reader's error message on one line, at most 200 characters."""
    return " ".join(str(err).split())[:200]


def _too_many_vertices(name: str) -> PartError:
    return PartError(f"{name}: flattening gives more than {MAX_VERTICES} vertices; "
                     "give a larger --tolerance")


class _TooManyVertices(Exception):
    """Raised by the flatteners when a curve would exceed :data:`MAX_VERTICES`."""


def _too_many_entities(name: str, what: str) -> PartError:
    return PartError(f"{name}: more than {MAX_ENTITIES:,} {what}; a part's outline needs far "
                     "fewer (no mesh within the limits has that many boundary vertices): "
                     "simplify the drawing or choose one --layer")


def _check_tolerance(name: str, tolerance: float, diagonal: float) -> None:
    """Refuse a ``tolerance`` outside :data:`TOLERANCE_RANGE` times ``diagonal`` (both in
    the drawing's units)."""
    lo, hi = TOLERANCE_RANGE[0] * diagonal, TOLERANCE_RANGE[1] * diagonal
    if not lo <= tolerance <= hi:
        raise PartError(f"--tolerance = {tolerance:g}: give a chord tolerance from {lo:.3g} to "
                        f"{hi:.3g} in the drawing's units ({TOLERANCE_RANGE[0]:g} to "
                        f"{TOLERANCE_RANGE[1]:g} times the diagonal of {name}, {diagonal:.4g})")


def _check_extent(name: str, what: str, points: np.ndarray) -> None:
    """Refuse coordinates (drawing units) that are not finite or beyond MAX_COORDINATE."""
    if points.size and not np.all(np.isfinite(points)):
        raise PartError(f"{name}: {what} has non-finite coordinates (NaN, inf or an "
                        "overflow); fix it")
    if points.size and float(np.max(np.abs(points))) > MAX_COORDINATE:
        raise PartError(f"{name}: {what} has a coordinate larger than {MAX_COORDINATE:g} in "
                        "magnitude; check the drawing's scale and --units")


# --------------------------------------------------------------------------- DXF
_BINARY_DXF = b"AutoCAD Binary DXF\r\n\x1a\x00"


def _dxf_document(src: Source):
    """The DXF document of ``src``'s bytes, decoded as :func:`ezdxf.readfile` decodes a file:
    binary DXF as such; ASCII DXF in the encoding its header states (UTF-8 from R2007 on),
    with universal newlines, undecodable bytes kept (``surrogateescape``)."""
    import ezdxf
    from ezdxf.document import Drawing as DXFDocument
    from ezdxf.filemanagement import dxf_stream_info
    from ezdxf.lldxf.tagger import binary_tags_loader
    from ezdxf.lldxf.validator import is_dxf_stream

    data = src.data
    if data.startswith(_BINARY_DXF):
        return DXFDocument.load(binary_tags_loader(data, errors="surrogateescape"))
    # the entities are counted from the tags (group code 0 starts every structure)
    # before ezdxf spends ~0.1 ms on each
    codes = data.splitlines()[0::2]
    if sum(codes.count(c) for c in (b"0", b" 0", b"  0")) > 2 * MAX_ENTITIES + 20_000:
        raise _too_many_entities(src.name, "DXF entities")

    def text(encoding: str, errors: str) -> io.TextIOWrapper:
        return io.TextIOWrapper(io.BytesIO(data), encoding=encoding, errors=errors)

    if not is_dxf_stream(text("utf-8", "ignore")):
        raise OSError("not a DXF file")
    info = dxf_stream_info(text("utf-8", "ignore"))
    return ezdxf.read(text(info.encoding, "surrogateescape"))


def _dxf_pieces(src: Source, units: str | None, layer: str | None, tolerance: float | None,
                default_units: str | None) -> tuple[list[_Piece], str, float]:
    import ezdxf

    path = src.name
    try:
        doc = _dxf_document(src)
    except PartError:
        raise
    except Exception as err:  # noqa: BLE001 - ezdxf raises many types (a truncated file: StopIteration)
        raise PartError(f"{path}: not a readable DXF file ({_detail(err) or type(err).__name__})") from None
    try:
        msp = doc.modelspace()
        entities = []
        for e in msp:
            for sub in _expand(e, path):
                entities.append(sub)
                if len(entities) > MAX_ENTITIES:
                    raise _too_many_entities(path, "DXF entities (block references exploded)")
    except PartError:
        raise
    except Exception as err:  # noqa: BLE001 - a damaged block or entity
        raise PartError(f"{path}: not a readable DXF file ({_detail(err) or type(err).__name__})") from None
    if layer is not None:
        layers = sorted({e.dxf.layer for e in entities})
        entities = [e for e in entities if e.dxf.layer == layer]
        if not entities:
            raise PartError(f"--layer {layer!r}: no entities on it; layers in the drawing: "
                            f"{', '.join(layers) or 'none'}")
    curves = []
    for e in entities:
        kind = e.dxftype()
        if kind in _ANNOTATIONS:
            continue
        if kind not in _CURVES:
            raise PartError(f"{path}: {kind} #{e.dxf.handle} is not supported; draw the outline "
                            "with lines, arcs, polylines, circles, ellipses or splines")
        curves.append(e)
    for e in curves:
        _check_extent(path, f"{e.dxftype()} #{e.dxf.handle}", _dxf_defining_points(e))
        if e.dxftype() in ("ARC", "CIRCLE") and not float(e.dxf.radius) > 0:
            raise PartError(f"{path}: {e.dxftype()} #{e.dxf.handle} has radius "
                            f"{float(e.dxf.radius):g}; give a radius > 0 or delete it")
    default = tolerance is None
    diagonal = _dxf_diagonal(curves)
    if default:
        tolerance = 1e-3 * diagonal
    else:
        _check_tolerance(path, tolerance, diagonal)
    pieces = []
    total = 0
    for e in curves:
        name = f"{e.dxftype()} #{e.dxf.handle}"
        try:
            pts, closed = _dxf_flatten(e, min(tolerance, _own_tolerance(e)) if default
                                       else tolerance, 1e-2 if default else math.inf)
        except _TooManyVertices:
            raise _too_many_vertices(path) from None
        except Exception as err:  # noqa: BLE001 - ezdxf raises many types for bad geometry
            raise PartError(f"{path}: {name} cannot be flattened ({err}); fix or redraw it") from None
        if e.dxftype() in ("LWPOLYLINE", "POLYLINE") and _dxf_elevated(e):
            raise PartError(f"{path}: {name} is not in the XY plane; the part must be planar")
        total += len(pts)
        if total > MAX_VERTICES:
            raise _too_many_vertices(path)
        if len(pts) < 2 or not np.all(np.isfinite(pts)):
            raise PartError(f"{path}: {name} is degenerate (no length or non-finite "
                            "coordinates); delete it")
        pieces.append(_Piece(pts, closed, name))
    header = doc.header.get("$INSUNITS", 0)
    if units is not None:
        return pieces, units, 1.0
    if header in _DXF_UNITS:
        unit, factor = _DXF_UNITS[header]
        return pieces, unit, factor
    if default_units is not None:
        return pieces, default_units, 1.0
    what = _DXF_NAMES.get(header, f"code {header}")
    raise PartError(f"{path}: the drawing's units are {what} ($INSUNITS); give --units "
                    "(m, cm, mm or in) for its coordinates")


def _own_tolerance(e) -> float:
    """1 % of a curve's own size (radius, minor semi-axis): the default tolerance never
    turns a small hole into a triangle."""
    kind = e.dxftype()
    if kind in ("ARC", "CIRCLE"):
        return 1e-2 * float(e.dxf.radius)
    if kind == "ELLIPSE":
        return 1e-2 * float(e.dxf.major_axis.magnitude) * float(e.dxf.ratio)
    if kind == "SPLINE":
        from ezdxf import bbox

        box = bbox.extents([e], fast=True)
        return 1e-2 * float(math.hypot(box.size.x, box.size.y)) if box.has_data else math.inf
    return math.inf


def _arc_points(cx: float, cy: float, r: float, a0: float, a1: float, tol: float) -> np.ndarray:
    """Points on the arc from angle ``a0`` to ``a1`` (rad, a1 > a0), both ends included,
    with chords whose sagitta ``r (1 − cos(Δ/2))`` is at most ``tol``."""
    step = 2 * math.acos(max(-1.0, 1.0 - tol / r)) if tol < 2 * r else math.pi
    n = (a1 - a0) / max(step, 1e-9)
    if not n <= MAX_VERTICES:          # counted before the points are made (NaN too)
        raise _TooManyVertices
    n = max(1, math.ceil(n))
    t = np.linspace(a0, a1, n + 1)
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


def _is_planar_xy(e) -> bool:
    """Whether an arc or circle lies in the XY plane, drawn counter-clockwise seen from +z."""
    n = e.dxf.extrusion
    return abs(n.x) < 1e-12 and abs(n.y) < 1e-12 and n.z > 0


def _dxf_flatten(e, tol: float, rel: float = math.inf) -> tuple[np.ndarray, bool]:
    """Vertices of a curve entity, chords within ``tol`` of it, and whether it is closed.

    Arcs (ARC, CIRCLE, polyline bulges) and ellipses are sampled on the exact curve, splines
    on the exact NURBS (ezdxf's generic paths would approximate arcs by Bézier curves,
    ~3e-4 r off, more than a fine tolerance). ``rel``: bulge arcs use at most ``rel × r``.
    """
    from ezdxf.math import bulge_to_arc

    kind = e.dxftype()
    if kind == "LINE":
        return np.array([[e.dxf.start.x, e.dxf.start.y], [e.dxf.end.x, e.dxf.end.y]]), False
    if kind in ("CIRCLE", "ARC") and _is_planar_xy(e):
        c, r = e.dxf.center, float(e.dxf.radius)
        if kind == "CIRCLE":
            return _arc_points(c.x, c.y, r, 0.0, 2 * math.pi, tol)[:-1], True
        a0 = math.radians(e.dxf.start_angle)
        a1 = math.radians(e.dxf.end_angle)
        a1 = a1 if a1 > a0 else a1 + 2 * math.pi
        return _arc_points(c.x, c.y, r, a0, a1, tol), False
    if kind in ("ARC", "ELLIPSE", "SPLINE", "CIRCLE"):
        pts = np.array([(v.x, v.y) for v in e.flattening(tol)], float)
        closed = kind == "ELLIPSE" and abs(abs(e.dxf.end_param - e.dxf.start_param)
                                           - 2 * math.pi) < 1e-12 or \
            (kind == "SPLINE" and bool(e.closed))
        if len(pts) > 2 and np.allclose(pts[0], pts[-1], rtol=0, atol=1e-12 * (tol + 1)):
            pts, closed = pts[:-1], True
        return pts, closed
    # LWPOLYLINE / 2-D POLYLINE: vertices with bulges (tan of a quarter of the arc angle)
    if kind == "LWPOLYLINE":
        verts = [(x, y, b) for x, y, b in e.get_points(format="xyb")]
        closed = bool(e.closed)
    else:
        if e.get_mode() != "AcDb2dPolyline":
            raise ValueError("only 2-D polylines are supported")
        verts = [(v.dxf.location.x, v.dxf.location.y, v.dxf.bulge) for v in e.vertices]
        closed = bool(e.is_closed)
    bulges = np.array([v[2] for v in verts], float)
    if not np.all(np.isfinite(bulges) & (np.abs(bulges) <= MAX_COORDINATE)):
        raise ValueError(f"a bulge is not finite or larger than {MAX_COORDINATE:g} in magnitude")
    out = []
    n = len(verts)
    for i in range(n if closed else n - 1):
        x0, y0, b = verts[i]
        x1, y1, _ = verts[(i + 1) % n]
        out.append((x0, y0))
        if b:
            c, a0, a1, r = bulge_to_arc((x0, y0), (x1, y1), b)
            a1 = a1 if a1 > a0 else a1 + 2 * math.pi
            inner = _arc_points(c.x, c.y, r, a0, a1, min(tol, rel * r))[1:-1]
            out.extend(inner if b > 0 else inner[::-1])
    if not closed:
        out.append(verts[-1][:2])
    return np.array(out, float), closed


def _expand(entity, path: str, depth: int = 0) -> Iterable[Any]:
    """Block references exploded into their entities (recursively, lazily, at most
    :data:`MAX_BLOCK_DEPTH` deep); others as they are. An entity on layer "0" inside a
    block takes the reference's layer (DXF convention)."""
    if entity.dxftype() == "INSERT":
        if depth >= MAX_BLOCK_DEPTH:
            raise PartError(f"{path}: block references nest more than {MAX_BLOCK_DEPTH} deep at "
                            f"INSERT of block {entity.dxf.name!r} (does a block hold itself?); "
                            "fix the drawing")
        for sub in entity.virtual_entities():
            if sub.dxf.layer == "0":
                sub.dxf.layer = entity.dxf.layer
            yield from _expand(sub, path, depth + 1)
    else:
        yield entity


def _dxf_elevated(e) -> bool:
    try:
        return abs(float(e.dxf.elevation if e.dxftype() == "LWPOLYLINE"
                         else e.dxf.elevation.z)) > 0
    except (AttributeError, TypeError):
        return False


def _dxf_defining_points(e) -> np.ndarray:
    """The defining points (k, 2) of a curve entity: end points, centre ± radius, control
    points (a spline lies in their convex hull), vertices."""
    kind = e.dxftype()
    if kind == "LINE":
        pts = [(e.dxf.start.x, e.dxf.start.y), (e.dxf.end.x, e.dxf.end.y)]
    elif kind in ("ARC", "CIRCLE"):
        c, r = e.dxf.center, float(e.dxf.radius)
        pts = [(c.x - r, c.y - r), (c.x + r, c.y + r)]
    elif kind == "ELLIPSE":
        c, a = e.dxf.center, float(e.dxf.major_axis.magnitude)
        pts = [(c.x - a, c.y - a), (c.x + a, c.y + a)]
    elif kind == "SPLINE":
        pts = [(p[0], p[1]) for p in e.control_points] + [(p[0], p[1]) for p in e.fit_points]
    elif kind == "LWPOLYLINE":
        pts = [(x, y) for x, y in e.get_points(format="xy")]
    else:
        pts = [(v.dxf.location.x, v.dxf.location.y) for v in e.vertices]
    return np.asarray(pts, float).reshape(-1, 2)


def _dxf_diagonal(curves) -> float:
    """Diagonal of a box holding every curve, from its defining points: cheap, and never
    smaller than the drawing's own box."""
    if not curves:
        return 1.0
    arr = np.concatenate([_dxf_defining_points(e) for e in curves])
    if not len(arr):
        return 1.0
    d = float(np.hypot(*np.ptp(arr, axis=0)))
    return d if math.isfinite(d) and d > 0 else 1.0


# --------------------------------------------------------------------------- SVG
_SVG_PHYSICAL = {"mm": 1.0, "cm": 10.0, "in": 25.4, "pt": 25.4 / 72, "pc": 25.4 / 6}


def _svg_pieces(src: Source, units: str | None, layer: str | None,
                tolerance: float | None) -> tuple[list[_Piece], str, float]:
    import svgelements as se

    path = src.name
    _svg_prescan(src)
    try:
        svg = se.SVG.parse(io.BytesIO(src.data), reify=True, ppi=96.0)
    except Exception as err:  # noqa: BLE001 - the XML parser and svgelements raise many types
        raise PartError(f"{path}: not a readable SVG file ({_detail(err)})") from None
    if not isinstance(svg, se.SVG):
        raise PartError(f"{path}: not an SVG drawing (no <svg> root element in the SVG "
                        "namespace http://www.w3.org/2000/svg)")
    try:
        return _svg_shapes(svg, path, units, layer, tolerance)
    except (PartError, _TooManyVertices):
        raise
    except Exception as err:  # noqa: BLE001 - svgelements on damaged geometry raises many types
        raise PartError(f"{path}: not a readable SVG file ({_detail(err) or type(err).__name__})") from None


def _svg_shapes(svg, path: str, units: str | None, layer: str | None,
                tolerance: float | None) -> tuple[list[_Piece], str, float]:
    """The pieces of a parsed SVG (see :func:`_svg_pieces`)."""
    import svgelements as se

    root = svg
    if layer is not None:
        found = svg.get_element_by_id(layer)
        if found is None:
            raise PartError(f"--layer {layer!r}: no SVG element with this id")
        root = found
    shapes = [e for e in root.select() if isinstance(e, se.Shape)]
    # Scale from the parsed coordinates (CSS px at 96 ppi, after the viewBox) to the unit.
    px_per_user = _svg_px_per_user(svg)
    if units is not None:
        unit, scale = units, 1.0 / px_per_user
    else:
        unit, scale = "mm", _svg_mm_per_px(svg)
    pieces: list[_Piece] = []
    polylines = []
    for i, shape in enumerate(shapes):
        name = f"{type(shape).__name__.lower()} {shape.id!r}" if shape.id else \
            f"{type(shape).__name__.lower()} #{i + 1}"
        p = se.Path(shape)
        if len(p) == 0:
            continue
        polylines.append((name, p))
    if not polylines:
        return [], unit, scale
    boxes = []
    for name, p in polylines:
        box = p.bbox()
        if box is not None:
            # in the drawing's units: after transforms, an overflow shows here
            _check_extent(path, name, np.asarray(box, float) * scale)
            boxes.append(box)
    boxes = np.array(boxes, float).reshape(-1, 4)
    diag = math.hypot(boxes[:, 2].max() - boxes[:, 0].min(),
                      boxes[:, 3].max() - boxes[:, 1].min()) if len(boxes) else 0.0
    diag = diag if diag > 0 else 1.0
    if tolerance is None:
        tol_px = 1e-3 * diag
    else:
        _check_tolerance(path, tolerance, diag * scale)
        tol_px = tolerance / scale
    total = 0
    budget = [MAX_VERTICES]
    for name, p in polylines:
        for k, sub in enumerate(p.as_subpaths()):
            sub = se.Path(sub)
            try:
                pts, closed = _flatten_svg(sub, tol_px, budget)
            except _TooManyVertices:
                raise _too_many_vertices(path) from None
            if len(pts) < 2:
                continue
            total += len(pts)
            if total > MAX_VERTICES:
                raise _too_many_vertices(path)
            if not np.all(np.isfinite(pts)):
                raise PartError(f"{path}: {name} has non-finite coordinates; fix it")
            label = name if k == 0 else f"{name} (sub-path {k + 1})"
            # SVG's y axis points down: mirror it so that loops keep their orientation sense.
            pts = pts * np.array([1.0, -1.0])
            pieces.append(_Piece(pts, closed, label))
    return pieces, unit, scale


_SVG_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_SVG_NOT_FINITE = re.compile(r"(?i)nan|inf")
_SVG_PATH_ATTRS = ("d", "points")
_SVG_NUMERIC_ATTRS = ("x", "y", "x1", "y1", "x2", "y2", "cx", "cy", "r", "rx", "ry", "width",
                      "height", "transform", "viewBox")


class _Refused(Exception):
    """Raised inside the expat handlers of :func:`_svg_prescan` (a message)."""


def _svg_prescan(src: Source) -> None:
    """Refuse, before svgelements reads it, an SVG whose reading could expand without
    bound, read a file, or take unbounded time (module docstring).

    A bare expat parser (no ElementTree) sees every declaration: an ``<!ENTITY>`` of any
    kind is refused (defusedxml's ``forbid_entities`` rule: internal ones nest into
    "billion laughs", external ones name files or URLs), parameter entities are never
    parsed and no external DTD or entity is fetched. The elements' ids, ``<use>``
    references and children give the expanded element count without expanding anything.

    Raises
    ------
    PartError
    """
    from xml.parsers import expat

    name = src.name
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    children: list[list[int]] = [[]]        # element 0: the document
    use: dict[int, str] = {}
    ids: dict[str, int] = {}
    stack = [0]
    counts = {"numbers": 0, "subpaths": 0}

    def entity(ent, is_param, value, base, system_id, public_id, notation):
        raise _Refused(f"{name}: declares the XML entity {ent!r}; entities are refused (they "
                       "can expand without bound or name files to read): save the drawing as "
                       "plain SVG without a DOCTYPE")

    def external(context, base, system_id, public_id):
        raise _Refused(f"{name}: refers to the external entity {system_id!r}; no file a "
                       "drawing names is read: save it as plain SVG")

    def start(tag, attrs):
        if len(stack) > MAX_SVG_DEPTH:
            raise _Refused(f"{name}: elements nest more than {MAX_SVG_DEPTH} deep; flatten "
                           "the groups")
        i = len(children)
        children.append([])
        children[stack[-1]].append(i)
        stack.append(i)
        if len(children) > MAX_ENTITIES + 1:
            raise _Refused(_too_many_entities(name, "SVG elements").args[0])
        if "id" in attrs:
            ids.setdefault(attrs["id"], i)
        if tag.rpartition(":")[2] == "use":
            ref = attrs.get("xlink:href", attrs.get("href", ""))
            if ref.startswith("#"):
                use[i] = ref[1:]
        for key, value in attrs.items():
            local = key.rpartition(":")[2]
            if local in _SVG_PATH_ATTRS or local in _SVG_NUMERIC_ATTRS:
                if _SVG_NOT_FINITE.search(value):
                    # svgelements skips such a value silently (a NaN viewBox scaled the
                    # drawing by 96 ppi instead of its width)
                    raise _Refused(f"{name}: attribute {key!r} of element #{i} <{tag}> is not "
                                   "a finite number (NaN or inf); fix it")
                nums = _SVG_NUMBER.findall(value)
                if local in _SVG_PATH_ATTRS:
                    counts["numbers"] += len(nums)
                    if local == "d":
                        counts["subpaths"] += value.count("M") + value.count("m")
                    if counts["numbers"] > MAX_PATH_NUMBERS:
                        raise _Refused(f"{name}: more than {MAX_PATH_NUMBERS:,} numbers of path "
                                       "data; simplify the drawing")
                    if counts["subpaths"] > MAX_SUBPATHS:
                        raise _Refused(f"{name}: more than {MAX_SUBPATHS:,} sub-paths (M "
                                       "commands); simplify the drawing")
                if nums and float(np.max(np.abs(np.asarray(nums, float)))) > MAX_DRAWING_NUMBER:
                    raise _Refused(f"{name}: attribute {key!r} of element #{i} <{tag}> has a "
                                   f"number larger than {MAX_DRAWING_NUMBER:g} in magnitude; "
                                   "check the drawing's scale")

    def end(tag):
        stack.pop()

    parser.EntityDeclHandler = entity
    parser.ExternalEntityRefHandler = external
    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(src.data, True)
    except _Refused as err:
        raise PartError(str(err)) from None
    except (expat.ExpatError, ValueError, OverflowError, LookupError) as err:  # LookupError: an unknown encoding
        raise PartError(f"{name}: not a readable SVG file ({_detail(err)})") from None
    _svg_expanded_count(name, children, use, ids)


def _svg_expanded_count(name: str, children: list[list[int]], use: dict[int, str],
                        ids: dict[str, int]) -> int:
    """Elements of an SVG once every ``<use>`` is replaced by what it references
    (recursively), without expanding: ``size(e) = 1 + Σ size(child) + size(target)``,
    memoised over the reference graph (iteratively; a cycle is refused)."""
    size: dict[int, int] = {}
    top = MAX_ENTITIES + 1

    def deps(i: int) -> list[int]:
        t = ids.get(use[i]) if i in use else None
        return children[i] + ([t] if t is not None else [])

    on_path: set[int] = set()
    todo: list[tuple[int, bool]] = [(0, False)]
    while todo:
        i, done = todo.pop()
        if done:
            on_path.discard(i)
            size[i] = min(top, 1 + sum(size[j] for j in deps(i)))
            continue
        if i in size:
            continue
        on_path.add(i)
        todo.append((i, True))
        for j in deps(i):
            if j in on_path:
                raise PartError(f"{name}: <use> of #{use.get(i, '?') if i in use else use.get(j, '?')} "
                                "refers back to itself; fix the drawing")
            if j not in size:
                todo.append((j, False))
    if size[0] > top - 1:
        raise _too_many_entities(name, "SVG elements (<use> references expanded)")
    return size[0]


def _svg_mm_per_px(svg) -> float:
    """Millimetres per parsed coordinate. With a physical root width and a viewBox, exact
    from the width as written: svgelements converts mm and cm to px with a 7-digit
    factor (3.7795296 px/mm), which would make a 20 mm drawing 20.0000108 mm. Otherwise
    CSS pixels, 25.4/96 mm each."""
    import re

    vb = getattr(svg, "viewbox", None)
    raw = str(svg.values.get("width") or "")
    m = re.fullmatch(r"\s*([0-9.]+(?:[eE][+-]?[0-9]+)?)\s*(mm|cm|in|pt|pc)\s*", raw)
    if vb is not None and getattr(vb, "width", None) and m and svg.width:
        return float(m.group(1)) * _SVG_PHYSICAL[m.group(2)] / float(svg.width)
    return 25.4 / 96.0


def _svg_px_per_user(svg) -> float:
    """CSS pixels per SVG user unit (from the root's width and viewBox; 1 without)."""
    vb = getattr(svg, "viewbox", None)
    if vb is None or not getattr(vb, "width", None):
        return 1.0
    return float(svg.width) / float(vb.width) if svg.width else 1.0


def _flatten_svg(path, tol: float, budget: list[int] | None = None) -> tuple[np.ndarray, bool]:
    """Vertices of one SVG sub-path with chords within ``tol`` (px) of the curves;
    ``budget``: ``[points left]``, shared by the sub-paths of a drawing (at most
    :data:`MAX_VERTICES`; :class:`_TooManyVertices` beyond it)."""
    budget = [MAX_VERTICES] if budget is None else budget
    import svgelements as se

    pts: list[complex] = []
    closed = False
    for seg in path:
        if isinstance(seg, se.Move):
            pts.append(_z(seg.end))
        elif isinstance(seg, se.Close):
            closed = True
        elif isinstance(seg, se.Line):
            pts.append(_z(seg.end))
        else:      # Arc, CubicBezier, QuadraticBezier: adaptive subdivision
            pts.extend(_subdivide(seg, 0.0, 1.0, _z(seg.start), _z(seg.end), tol, 0, budget))
    arr = np.array([[z.real, z.imag] for z in pts], float)
    if len(arr) > 2 and np.allclose(arr[0], arr[-1], rtol=0, atol=tol * 1e-3):
        arr = arr[:-1]
        closed = True
    return arr, closed


def _z(point) -> complex:
    """An svgelements point as a Python complex number."""
    return complex(float(point.x), float(point.y))


def _subdivide(seg, t0: float, t1: float, p0: complex, p1: complex, tol: float,
               depth: int, budget: list[int]) -> list[complex]:
    """Points (after ``p0``, ending with ``p1``) of ``seg`` on [t0, t1] within ``tol``;
    each evaluation of the curve counts against ``budget``."""
    budget[0] -= 3
    if budget[0] < 0:
        raise _TooManyVertices
    tm = 0.5 * (t0 + t1)
    pm = _z(seg.point(tm))
    q1, q3 = _z(seg.point(0.5 * (t0 + tm))), _z(seg.point(0.5 * (tm + t1)))
    chord = p1 - p0
    L = abs(chord)

    def dev(q: complex) -> float:
        if L == 0:
            return abs(q - p0)
        return abs(((q - p0) * chord.conjugate()).imag) / L

    if depth >= 18 or (depth >= 2 and max(dev(pm), dev(q1), dev(q3)) <= tol):
        return [p1]
    return (_subdivide(seg, t0, tm, p0, pm, tol, depth + 1, budget)
            + _subdivide(seg, tm, t1, pm, p1, tol, depth + 1, budget))


# --------------------------------------------------------------------------- loops
def _chain(pieces: list[_Piece], path: str) -> list[tuple[np.ndarray, str]]:
    """Closed loops: closed pieces as they are, open pieces joined end to end (end points
    within 1e-6 of the drawing's span of each other are the same point)."""
    loops = [(p.points, p.name) for p in pieces if p.closed]
    open_ = [p for p in pieces if not p.closed]
    if not open_:
        return loops
    lo = np.min([p.points.min(axis=0) for p in open_], axis=0)
    hi = np.max([p.points.max(axis=0) for p in open_], axis=0)
    snap = 1e-6 * (float(np.max(hi - lo)) or 1.0)
    ends = [(tuple(p.points[0]), tuple(p.points[-1])) for p in open_]
    cells: dict[tuple[int, int], list[tuple[int, int]]] = {}   # grid cell -> (piece, end)

    def cell(pt) -> tuple[int, int]:
        return (math.floor(pt[0] / snap), math.floor(pt[1] / snap))

    def same(a, b) -> bool:
        return math.hypot(a[0] - b[0], a[1] - b[1]) <= snap

    used = [False] * len(open_)
    for i, (a, b) in enumerate(ends):
        if same(a, b) and len(open_[i].points) > 2:
            loops.append((open_[i].points[:-1], open_[i].name))
            used[i] = True
            continue
        for end, pt in enumerate((a, b)):
            cells.setdefault(cell(pt), []).append((i, end))

    def near(pt) -> list[tuple[int, int]]:
        cx, cy = cell(pt)
        return [m for dx in (-1, 0, 1) for dy in (-1, 0, 1) for m in cells.get((cx + dx, cy + dy), ())
                if not used[m[0]] and same(ends[m[0]][m[1]], pt)]

    for i in range(len(open_)):
        if used[i]:
            continue
        used[i] = True
        chain = [open_[i].points]
        names = [open_[i].name]
        start, tip = ends[i]
        while not same(tip, start):
            nxt = near(tip)
            if not nxt:
                raise PartError(f"{path}: open outline: {names[-1]} ends at "
                                f"({tip[0]:.6g}, {tip[1]:.6g}) and nothing continues it; "
                                "close the outline")
            if len(nxt) > 1:
                others = ", ".join(open_[j].name for j, _ in nxt)
                raise PartError(f"{path}: the outline branches at ({tip[0]:.6g}, {tip[1]:.6g}) "
                                f"after {names[-1]} ({others}); remove the extra entity")
            j, end = nxt[0]
            used[j] = True
            pts = open_[j].points if end == 0 else open_[j].points[::-1]
            chain.append(pts[1:])
            names.append(open_[j].name)
            tip = ends[j][1 - end]
        loop = np.concatenate(chain)[:-1]
        loops.append((loop, names[0] if len(names) == 1 else f"{names[0]} … {names[-1]}"))
    return loops


def _assemble(loops: list[tuple[np.ndarray, str]], unit: str, path: str) -> Drawing:
    import shapely

    rings = []
    for pts, name in loops:
        pts = _dedupe(pts)
        if len(pts) < 3:
            raise PartError(f"{path}: {name} closes with fewer than 3 distinct points; delete it")
        ring = shapely.LinearRing(pts)
        if not ring.is_simple:
            raise PartError(f"{path}: {name} crosses itself; redraw it without a "
                            "self-intersection")
        area = abs(shapely.Polygon(pts).area)
        if area <= 0:
            raise PartError(f"{path}: {name} encloses no area; delete it")
        rings.append((area, pts, name))
    rings.sort(key=lambda r: -r[0])
    _, outer, outer_name = rings[0]
    shell = shapely.Polygon(outer)
    shapely.prepare(shell)
    holes = []
    for _, pts, name in rings[1:]:
        poly = shapely.Polygon(pts)
        if not shell.contains(poly):
            if shell.intersects(poly):
                raise PartError(f"{path}: {name} crosses the outer outline {outer_name}; "
                                "fix the drawing")
            raise PartError(f"{path}: two outer outlines, {outer_name} and {name}; a part is "
                            "one piece: delete one, or choose one with --layer")
        holes.append(pts)
    return Drawing(outer, tuple(holes), unit)


def _dedupe(pts: np.ndarray) -> np.ndarray:
    """Consecutive repeated vertices removed (a loop is not closed in the array)."""
    if len(pts) == 0:
        return pts
    span = float(np.ptp(pts, axis=0).max()) or 1.0
    keep = np.ones(len(pts), bool)
    keep[1:] = np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-12 * span
    pts = pts[keep]
    if len(pts) > 1 and np.linalg.norm(pts[0] - pts[-1]) <= 1e-12 * span:
        pts = pts[:-1]
    return pts


# --------------------------------------------------------------------------- parts
def material_file_beside(path: InputFile) -> Path | None:
    """The material file ``<name>.material.json`` beside a drawing given by its path, if it
    exists; for a drawing given as a :class:`~deformclosure.jsonfile.Source`, the Source's
    ``sidecar`` (the material file's bytes read with the drawing's, or ``None``)."""
    if isinstance(path, Source):
        return path.sidecar
    side = material_path_beside(Path(path))
    return side if side.is_file() else None


def material_path_beside(path: Path) -> Path:
    """Where the material file of the drawing at ``path`` is: ``<name>.material.json``."""
    return path.with_name(path.stem + ".material.json")
