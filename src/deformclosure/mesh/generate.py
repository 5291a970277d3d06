"""Quality triangulation of a part with Shewchuk's Triangle (via the ``triangle`` package).

Extra points (intended contact locations) become mesh nodes: points on the boundary
split the boundary segment they lie on, interior points are inserted as vertices.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import triangle as tr
import shapely
from shapely.geometry import Polygon

from .. import limits
from ..errors import MeshError, PartError
from ..geometry import touch_tolerance
from ..part import Part
from .core import Mesh

__all__ = ["mesh_part", "insert_points_in_ring", "default_max_area", "twin_mesh", "TWIN_ANGLE",
           "TWIN_AREA"]


def insert_points_in_ring(ring: np.ndarray, points: np.ndarray, tol: float
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Insert the ``points`` lying on ``ring``'s edges (within ``tol``) as ring vertices.

    Parameters
    ----------
    ring : ndarray, shape (k, 2)
        Closed ring without repeated first vertex (m).
    points : ndarray, shape (q, 2)
        Candidate points (m).
    tol : float
        Distance (m) within which a point counts as lying on an edge.

    Returns
    -------
    new_ring : ndarray
        Ring with the points inserted in order along each edge, at their feet on the edge
        (points that coincide with an existing vertex are snapped to it).
    on_ring : ndarray of bool, shape (q,)
        Which points were on the ring.

    Notes
    -----
    The edges near each point come from an R-tree of the edges (the nearest wins, the
    lowest edge index among equally near ones), so memory and time grow like
    ``(q + k) log k``, not with a ``q × k`` table (10 000 points on a 20 000-vertex ring
    took gigabytes).
    """
    points = np.asarray(points, float).reshape(-1, 2)
    q = len(points)
    if q == 0:
        return ring, np.zeros(0, bool)
    a = ring
    b = np.roll(ring, -1, axis=0)
    ab = b - a
    L2 = (ab**2).sum(1)
    tree = shapely.STRtree(shapely.linestrings(np.stack([a, b], axis=1)))
    # Only edges within (a little more than) tol can hold a point.
    pi, ei = tree.query(shapely.points(points), predicate="dwithin", distance=2.0 * tol)
    if not len(pi):
        return ring, np.zeros(q, bool)
    # Exact distances of the candidate (point, edge) pairs; keep the nearest, lowest index.
    t = ((points[pi] - a[ei]) * ab[ei]).sum(-1) / L2[ei]
    tc = np.clip(t, 0.0, 1.0)
    proj = a[ei] + tc[:, None] * ab[ei]
    dist = np.linalg.norm(points[pi] - proj, axis=-1)
    order = np.lexsort((ei, dist, pi))
    first = order[np.r_[True, pi[order][1:] != pi[order][:-1]]]
    edge = np.zeros(q, np.int64)
    dmin = np.full(q, np.inf)
    tt = np.zeros(q)
    foot = points.copy()
    edge[pi[first]] = ei[first]
    dmin[pi[first]] = dist[first]
    tt[pi[first]] = tc[first]
    foot[pi[first]] = proj[first]
    on = dmin <= tol
    # Points at an existing vertex need no insertion.
    Lk = np.sqrt(L2[edge])
    interior = on & (tt * Lk > tol) & ((1 - tt) * Lk > tol)
    if not interior.any():
        return ring, on
    # Sort key: edge index + parameter along the edge puts inserted points in order.
    keys = np.concatenate([np.arange(len(ring), dtype=float), edge[interior] + tt[interior]])
    # Insert the foot on the edge, not the point itself: a point up to tol off the edge
    # would make a boundary triangle of near-zero area with the edge's ends.
    coords = np.concatenate([ring, foot[interior]])
    order = np.argsort(keys, kind="stable")
    new = coords[order]
    keep = np.ones(len(new), bool)
    keep[1:] = np.linalg.norm(np.diff(new, axis=0), axis=1) > tol
    return new[keep], on


def _units_of(part: Part) -> tuple[str, float]:
    """The part's length unit and metres per unit, for messages (metres if unknown)."""
    from ..units import LENGTH_UNITS, length_scale

    if part.units in LENGTH_UNITS:
        return part.units, length_scale(part.units)
    return "m", 1.0


def default_max_area(part: Part) -> float:
    """The part's ``mesh.max_area`` (m²), else its area / 400."""
    opts = part.mesh_options
    return opts.max_area if opts.max_area is not None else part.area / 400.0


def _mesher_settings(part: Part, max_area: float | None, min_angle: float | None,
                     points: np.ndarray | None) -> tuple[float, float, np.ndarray]:
    """Checked ``max_area`` (m²), ``min_angle`` (degrees) and the points to insert (m):
    the arguments, else the part's mesh options."""
    opts = part.mesh_options
    max_area = default_max_area(part) if max_area is None else float(max_area)
    if not (np.isfinite(max_area) and max_area > 0):
        raise PartError(f"max_area = {max_area!r}: must be a finite area > 0")
    min_angle = opts.min_angle if min_angle is None else float(min_angle)
    if not (0 < min_angle <= 34):
        raise PartError(f"min_angle = {min_angle!r}: use 0 < min_angle <= 34 degrees")
    pts = np.asarray(opts.points, float).reshape(-1, 2)
    if points is not None:
        pts = np.concatenate([pts, np.asarray(points, float).reshape(-1, 2)])
    limits.check_mesh_points(len(pts), "mesh.points" if points is None else "points")
    return max_area, min_angle, pts


def _check_points_inside(part: Part, pts: np.ndarray, tol: float) -> None:
    """Refuse points outside the part by more than ``tol`` (m)."""
    if len(pts):
        outside = ~limits.points_within(part.polygon, pts, tol)  # indexed: no points × edges
        if outside.any():
            bad = int(np.flatnonzero(outside)[0])
            raise PartError(f"points[{bad}]: point lies outside the part; move it onto or inside the part")


def _rings_with_points(part: Part, pts: np.ndarray, tol: float
                       ) -> tuple[list[np.ndarray], np.ndarray]:
    """The part's rings with the points on them (within ``tol``) inserted as vertices, and
    the points left for the interior."""
    remaining = np.ones(len(pts), bool)
    new_rings = []
    for ring in [part.outer] + list(part.holes):
        if len(pts):
            ring, on = insert_points_in_ring(ring, pts, tol)
            remaining &= ~on
        new_rings.append(ring)
    return new_rings, pts[remaining]


def _triangulate(rings: list[np.ndarray], interior_pts: np.ndarray, holes: tuple,
                 min_angle: float, max_area: float, sizing=None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Triangle's constrained quality triangulation of the rings (as segments) and the
    interior points: node coordinates (m) and triangles, unused input vertices dropped.
    With ``sizing`` (a :class:`~deformclosure.mesh.sizing.Sizing`, in the frame of the
    rings) the triangulation is refined until each triangle meets it at its centroid."""
    verts = np.concatenate(rings + [interior_pts])
    segs = []
    off = 0
    for ring in rings:
        idx = np.arange(off, off + len(ring))
        segs.append(np.column_stack([idx, np.roll(idx, -1)]))
        off += len(ring)
    geom: dict = {"vertices": verts, "segments": np.concatenate(segs)}
    if holes:
        geom["holes"] = np.array([Polygon(h).representative_point().coords[0] for h in holes])
    # Triangle's switch parser does not read exponents: write plain decimals.
    flags = (f"pq{np.format_float_positional(min_angle, trim='-')}"
             f"a{np.format_float_positional(max_area, trim='-')}Q"
             f"S{limits.steiner_cap()}")  # a backstop: a wrong estimate cannot run away
    try:
        out = tr.triangulate(geom, flags)
        if sizing is not None:
            out = _refine_to(out, geom.get("holes"), sizing, min_angle)
    except Exception as err:  # the C library reports failures as generic errors
        raise MeshError(f"the mesher failed ({err}); check the part geometry and mesh options") from None
    return np.asarray(out["vertices"], float), np.asarray(out["triangles"], np.int64)


def _refine_to(out: dict, holes, sizing, min_angle: float, passes: int = 12) -> dict:
    """Refine Triangle's output ``out`` (quality ``min_angle``, segments kept) until every
    triangle's area is within ``sizing`` at its centroid: Triangle's ``r`` + per-triangle
    ``a`` switch, repeated because the new triangles' centroids move into finer regions."""
    flags = f"rpq{np.format_float_positional(min_angle, trim='-')}aQS{limits.steiner_cap()}"
    for _ in range(passes):
        V, T = np.asarray(out["vertices"], float), np.asarray(out["triangles"])
        P = V[T]
        e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
        area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        want = sizing(P.mean(axis=1))
        if np.all(area <= want * (1 + 1e-9)) or len(T) > limits.MAX_TRIANGLES:
            break
        geom = {"vertices": V, "triangles": T, "segments": out["segments"],
                "triangle_max_area": want}
        if holes is not None:
            geom["holes"] = holes
        out = tr.triangulate(geom, flags)
    return out


def _drop_unused(nodes: np.ndarray, tris: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangle may leave unused input vertices (duplicates); drop them, keeping order."""
    used = np.zeros(len(nodes), bool)
    used[tris.ravel()] = True
    if used.all():
        return nodes, tris
    return nodes[used], (np.cumsum(used) - 1)[tris]


def mesh_part(part: Part, max_area: float | None = None, min_angle: float | None = None,
              points: np.ndarray | None = None, sizing=None) -> Mesh:
    """Quality-mesh a part with linear triangles.

    Parameters
    ----------
    part : Part
    max_area : float, optional
        Largest triangle area (m²). Default: the part's ``mesh.max_area``, else area/400.
    min_angle : float, optional
        Smallest angle (degrees, ≤ 34). Default: the part's ``mesh.min_angle``.
    points : ndarray, shape (k, 2), optional
        Extra points (m) to insert as nodes, in addition to the part's ``mesh.points``.
        Points on the boundary (within the SPEC's touching tolerance, ``1e-9 ×`` the
        part's diameter) split the boundary edge they lie on.
    sizing : Sizing, optional
        Local areas (m², :class:`~deformclosure.mesh.sizing.Sizing`) below ``max_area``:
        the mesh is refined until each triangle meets it (adaptive refinement, SPEC §6).

    Returns
    -------
    Mesh
        Counter-clockwise triangles, outer loop CCW, holes CW, ``material`` set.

    Raises
    ------
    PartError
        Bad mesh options or points outside the part.
    MeshError
        If the mesher fails.

    Examples
    --------
    A 12 × 20 mm block with nodes forced at the middle of its long sides:

    >>> from deformclosure import demo_part
    >>> mesh = mesh_part(demo_part(max_area_mm2=20.0))
    >>> mesh.n_triangles > 12, mesh.find_node([0.0, 0.01]) in mesh.outer_loop
    (True, True)
    """
    opts = part.mesh_options
    from_file = max_area is None and opts.max_area is not None
    max_area, min_angle, pts = _mesher_settings(part, max_area, min_angle, points)
    units, scale = _units_of(part)
    diam = part.diameter
    tol = touch_tolerance(diam)
    _check_points_inside(part, pts, tol)
    limits.check_ring_gaps(part.outer, part.holes, diam, units=units, scale=scale)
    new_rings, interior_pts = _rings_with_points(part, pts, tol)
    # Refuse, from an estimate, a mesh too large to analyse or too slow to make.
    field = "mesh.max_area" if from_file else "max_area"
    limits.check_mesh_size(new_rings, max_area, min_angle, interior_pts, units=units,
                           scale=scale, field=field)
    nodes, tris = _triangulate(new_rings, interior_pts, part.holes, min_angle, max_area, sizing)
    limits.check_mesh_result(len(tris), max_area, units=units, scale=scale, field=field)
    nodes, tris = _drop_unused(nodes, tris)
    mesh = Mesh.from_arrays(nodes, tris, material=part.material, name=part.name)
    if len(pts):
        from scipy.spatial import cKDTree  # lazy: scipy.spatial is slow to import

        d, _ = cKDTree(mesh.nodes).query(pts)
        if np.any(d > tol * 10):
            raise MeshError("an inserted point did not become a mesh node; report this as a bug")
    return mesh


# ----------------------------------------------------------------------------- twin

#: Rotation (rad) of the frame in which the twin realisation is meshed.
TWIN_ANGLE = 1.0

#: Triangle-area ratio of the twin realisation: boundary nodes at other positions, and a
#: coarser mesh, so the noise it shows errs on the large (cautious) side and costs less.
TWIN_AREA = 1.3


def _rot(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def twin_mesh(part, max_area: float | None = None, angle: float = TWIN_ANGLE,
              area_ratio: float = TWIN_AREA, sizing=None):
    """A second realisation of the part's mesh, returned in the part frame: the
    discretisation-noise measurement of every model (SPEC §6 "Noise floor").

    Meshed in a frame rotated by ``angle`` (rad) with ``area_ratio`` × the triangle area
    ``max_area`` (m², default the part's), so every node, boundary nodes included, sits
    elsewhere (Triangle splits a straight edge evenly, so a rotation alone would reproduce
    the boundary nodes). ``sizing`` (part frame) refines it locally as the main mesh, its
    areas times ``area_ratio`` too.
    """
    c = part.outer.mean(axis=0)
    R = _rot(angle)
    rot = lambda P: (np.asarray(P, float) - c) @ R.T + c  # noqa: E731
    opts = part.mesh_options
    pts = np.asarray(opts.points, float).reshape(-1, 2)
    rpart = replace(part, outer=rot(part.outer), holes=tuple(rot(h) for h in part.holes),
                    mesh_options=replace(opts, points=rot(pts) if len(pts) else opts.points))
    area = default_max_area(part) if max_area is None else max_area
    local = None
    if sizing is not None:
        back = _rot(-angle)
        local = lambda P: area_ratio * sizing((np.asarray(P, float) - c) @ back.T + c)  # noqa: E731
    return mesh_part(rpart, max_area=area * area_ratio, sizing=local).rotated(-angle, c)
