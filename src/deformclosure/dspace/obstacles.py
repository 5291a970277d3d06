"""D-obstacles and the free D-space ``D_free`` (paper §3.2, SPEC §2).

Configuration ``q`` is in the D-obstacle ``DA_i`` of finger ``i`` when the interior of
the deformed part meets the interior of the finger; touching is free. With the
tolerance ``tol`` (default ``1e-9`` x the part's diameter, SPEC §3) the finger is
eroded by ``tol`` first, so contact with overlap up to ``tol`` counts as touching.
A point finger has no interior: it collides when the point lies inside the deformed
part farther than ``tol`` from its boundary. ``D_free = D_T ∩ complement(∪ DA_i)``.

Method
------
For ``q`` in ``D_T`` the deformed part is the polygon with holes bounded by the
deformed boundary rings, so everything is computed from boundary edges (vectorised over
edges and configurations):

* the open (eroded) finger meets the part's interior iff some boundary edge meets the
  open finger -- half-plane: an edge end strictly inside; disc: the edge passes closer
  than ``r - tol`` to the centre; convex polygon: Cyrus-Beck clipping of the edge
  against the open polygon -- **or** no edge does and an interior point of the finger
  (centre / centroid / the point itself) lies inside the part (even-odd crossing rule);
* the crossing parity, "some edge hits" and the nearest-edge distance are reductions
  over edges, so a slice that moves one node recomputes only the two edges at that
  node (:mod:`.slices`).

Outside ``D_T`` the rings may overlap themselves and the result refers to the even-odd
region of the rings; ``D_free`` does not depend on it.

This module also linearises the non-penetration conditions into *contact rows*
(gap, gradient, contact point, part feature) used by :mod:`.equilibrium` and
:mod:`.closure`.

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.2 (D-obstacles, ``D_free``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .energy import as_configurations
from .. import geometry
from ..errors import DeformClosureError
from ..geometry import TOUCH_TOLERANCE
from ..contact.bodies import Finger, segment_distance
from .topology import DEFAULT_MIN_AREA_RATIO, in_dt, loop_edges

__all__ = [
    "TOUCH_TOLERANCE",
    "touch_tolerance",
    "in_dobstacle",
    "dobstacle_mask",
    "in_dfree",
    "boundary_gaps",
]

def touch_tolerance(mesh: Any) -> float:
    """Touching tolerance (m) of a mesh: :func:`deformclosure.geometry.touch_tolerance` of
    its diameter, ``1e-9`` x ``mesh.diameter`` (SPEC §3)."""
    return geometry.touch_tolerance(mesh.diameter)


def resolve_tolerance(mesh: Any, tol: float | None) -> float:
    """``tol`` (m) as a float, or the mesh's touching tolerance when ``None``.

    Raises
    ------
    DeformClosureError
        ``tol`` is not a finite number >= 0.
    """
    if tol is None:
        return touch_tolerance(mesh)
    return nonnegative(tol, "tol", "the touching tolerance in m", "or None for 1e-9 x the part's diameter")


def nonnegative(value: Any, name: str, what: str, alternative: str = "") -> float:
    """``value`` as a finite float >= 0; :class:`DeformClosureError` naming ``name`` and
    asking for ``what`` (``alternative``: what else may be given) otherwise."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        out = math.nan
    if not (math.isfinite(out) and out >= 0.0):
        raise DeformClosureError(f"{name} = {value!r:.60}: give {what} as a finite number >= 0"
                                 + (f", {alternative}" if alternative else ""))
    return out


# ----------------------------------------------------------------------------- kernels


def _crosses(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Even-odd rule: does the ray from ``p`` towards +x cross edge ``a-b``?"""
    ay, by, py = a[..., 1], b[..., 1], p[..., 1]
    straddle = (ay > py) != (by > py)
    dy = np.where(straddle, by - ay, 1.0)
    xint = a[..., 0] + (py - ay) * (b[..., 0] - a[..., 0]) / dy
    return straddle & (p[..., 0] < xint)


@dataclass
class _Terms:
    """Per-configuration reductions over a set of boundary edges for one finger."""

    hit: np.ndarray  # bool: some edge meets the open (eroded) finger
    parity: np.ndarray  # bool: crossing parity of the finger's probe point
    mind: np.ndarray  # float: distance from the probe point to the nearest edge

    def combine(self, other: "_Terms") -> "_Terms":
        return _Terms(self.hit | other.hit, self.parity ^ other.parity, np.minimum(self.mind, other.mind))


def _edge_terms(finger: Finger, a: np.ndarray, b: np.ndarray, tol: float) -> _Terms:
    """Reductions over the edges axis (second to last) of segment arrays ``(..., E, 2)``.

    The crossing parity is that of the finger's probe point (none for a half-plane); the
    distance to the nearest edge matters only for a body without interior (a point)."""
    shape = a.shape[:-2]
    no = np.zeros(shape, dtype=bool)
    inf = np.full(shape, np.inf)
    if a.shape[-2] == 0:
        return _Terms(no, no.copy(), inf)
    hit = np.any(finger.segment_hits(a, b, tol), axis=-1)
    probe = finger.probe_point()
    if probe is None:
        return _Terms(hit, no, inf)
    parity = np.logical_xor.reduce(_crosses(a, b, probe), axis=-1)
    mind = inf if finger.has_interior else np.min(segment_distance(a, b, probe), axis=-1)
    return _Terms(hit, parity, mind)


def _collides(t: _Terms, tol: float) -> np.ndarray:
    """The open (eroded) finger meets the part's interior: some edge meets it, or its
    probe point is inside the part (for a point: farther than ``tol`` from the boundary;
    a body with interior has ``mind = inf``)."""
    return t.hit | (t.parity & (t.mind > tol))


def _obstacles(qb: np.ndarray, edges: np.ndarray, fingers: Sequence[Finger], tol: float) -> np.ndarray:
    a, b = qb[:, edges[:, 0]], qb[:, edges[:, 1]]
    out = np.zeros((len(qb), len(fingers)), dtype=bool)
    for i, f in enumerate(fingers):  # loop over the few fingers only
        out[:, i] = _collides(_edge_terms(f, a, b, tol), tol)
    return out


# ----------------------------------------------------------------------------- public API


def dobstacle_mask(mesh: Any, q: Any, fingers: Sequence[Finger], tol: float | None = None) -> np.ndarray:
    """Membership of ``q`` in every finger's D-obstacle ``DA_i``.

    Parameters
    ----------
    mesh : Mesh
    q : array_like
        Configuration(s) (m), see :func:`deformclosure.dspace.energy.as_configurations`.
    fingers : sequence of Finger
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter``.

    Returns
    -------
    ndarray of bool, shape (n_fingers,) or (b, n_fingers)
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    tol = resolve_tolerance(mesh, tol)
    out = _obstacles(qb, loop_edges(mesh.loops), list(fingers), tol)
    return out if batched else out[0]


def in_dobstacle(mesh: Any, q: Any, finger: Finger, tol: float | None = None) -> bool | np.ndarray:
    """Whether ``q`` lies in the D-obstacle of one ``finger`` (bool or ``(b,)`` bool)."""
    m = dobstacle_mask(mesh, q, [finger], tol)
    return bool(m[0]) if m.ndim == 1 else m[:, 0]


def in_dfree(
    mesh: Any,
    q: Any,
    fingers: Sequence[Finger],
    tol: float | None = None,
    min_area_ratio: float = DEFAULT_MIN_AREA_RATIO,
) -> bool | np.ndarray:
    """Membership of ``q`` in ``D_free = D_T ∩ complement(∪ DA_i)`` (paper §3.2).

    Parameters
    ----------
    mesh : Mesh
    q : array_like
        ``(n, 2)``/``(2n,)`` or a batch ``(b, n, 2)``/``(b, 2n)`` (m).
    fingers : sequence of Finger
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter``.
    min_area_ratio : float
        Minimum deformed/rest area of a triangle in ``D_T``.

    Returns
    -------
    bool or ndarray of bool, shape (b,)
    """
    qb, batched = as_configurations(q, len(mesh.nodes))
    ok = np.asarray(in_dt(mesh, qb, min_area_ratio=min_area_ratio))
    if len(fingers) and ok.any():
        idx = np.flatnonzero(ok)
        ok[idx] = ~np.any(dobstacle_mask(mesh, qb[idx], fingers, tol), axis=1)
    return ok if batched else bool(ok[0])


def boundary_gaps(mesh: Any, q: Any, finger: Finger) -> np.ndarray:
    """Signed distance (m) of every boundary node of configuration ``q`` from ``finger``
    (negative inside the finger; for a point finger the distance to the point)."""
    qb, _ = as_configurations(q, len(mesh.nodes))
    nodes = np.unique(loop_edges(mesh.loops)[:, 0])
    return finger.signed_distance(qb[0, nodes])


# ----------------------------------------------------------------------------- contact rows
# Linearised non-penetration conditions ("contact rows") between fingers and the deformed
# boundary. Row r has a gap g_r (m, >= 0 when free), involves up to two boundary nodes
# with weights w (summing to 1) and a unit direction d_r: moving node j by dx_j changes
# the gap by sum_j w_j d_r . dx_j. The force of the finger on the part is lambda_r d_r.

#: Part-feature codes of boundary nodes at rest.
STRAIGHT, CONVEX, REFLEX = 0, 1, 2
FEATURE_NAMES = {STRAIGHT: "edge", CONVEX: "convex_vertex", REFLEX: "concave_vertex"}

#: Sine of the turning angle below which a boundary node counts as straight (on an edge).
STRAIGHT_SINE = 1e-6


class BoundaryModel:
    """Boundary loops of a mesh with rest-geometry feature classes (paper §3.3).

    Attributes
    ----------
    edges : ndarray (E, 2)
        Loop edges ``u -> w`` with the part's interior on the left.
    nodes : ndarray (B,)
        Boundary node ids, ``nodes[k] = edges[k, 0]``.
    prev, next : ndarray (n,)
        Loop neighbours of every boundary node (``-1`` elsewhere).
    feature : ndarray (n,)
        ``STRAIGHT``, ``CONVEX`` or ``REFLEX`` at rest (``-1`` for interior nodes).
    """

    def __init__(self, mesh: Any):
        self.edges = loop_edges(mesh.loops)
        self.nodes = self.edges[:, 0].copy()
        n = len(mesh.nodes)
        self.prev = np.full(n, -1, dtype=np.int64)
        self.next = np.full(n, -1, dtype=np.int64)
        self.next[self.edges[:, 0]] = self.edges[:, 1]
        self.prev[self.edges[:, 1]] = self.edges[:, 0]
        self.edge_of = np.full(n, -1, dtype=np.int64)  # edge starting at node
        self.edge_of[self.edges[:, 0]] = np.arange(len(self.edges))
        x = np.asarray(mesh.nodes, dtype=float)
        v = self.nodes
        t1 = x[v] - x[self.prev[v]]
        t2 = x[self.next[v]] - x[v]
        t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
        t2 /= np.linalg.norm(t2, axis=1, keepdims=True)
        sin = t1[:, 0] * t2[:, 1] - t1[:, 1] * t2[:, 0]
        cos = np.einsum("ij,ij->i", t1, t2)
        feat = np.where(sin > 0, CONVEX, REFLEX)
        feat = np.where((np.abs(sin) <= STRAIGHT_SINE) & (cos > 0), STRAIGHT, feat)
        self.feature = np.full(n, -1, dtype=np.int64)
        self.feature[v] = feat

    def inward_normals(self, x: np.ndarray) -> np.ndarray:
        """Unit inward normals ``(E, 2)`` of the edges in configuration ``x (n, 2)``."""
        t = x[self.edges[:, 1]] - x[self.edges[:, 0]]
        t = t / np.linalg.norm(t, axis=1, keepdims=True)
        return np.stack([-t[:, 1], t[:, 0]], axis=1)

    def node_normals(self, x: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """Mean of the two adjacent edges' inward normals at ``nodes`` (normalised)."""
        en = self.inward_normals(x)
        m = en[self.edge_of[nodes]] + en[self.edge_of[self.prev[nodes]]]
        return m / np.linalg.norm(m, axis=1, keepdims=True)

    def inside(self, x: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Even-odd membership of ``points (k, 2)`` in the region bounded by the rings."""
        a, b = x[self.edges[:, 0]], x[self.edges[:, 1]]
        return np.logical_xor.reduce(_crosses(a[None], b[None], points[:, None, :]), axis=-1)


#: Kinds of contact rows.
NODE_BODY, CORNER_EDGE, DISC_EDGE, CORNER_NODE = 0, 1, 2, 3


@dataclass
class ContactRows:
    """Linearised contact conditions in one configuration (see module notes).

    All arrays have one row per condition: ``finger (r,)``, ``nodes (r, 2)``,
    ``weights (r, 2)``, ``direction (r, 2)`` (unit, from the finger into the part),
    ``gap (r,)`` (m), ``point (r, 2)`` (contact point on the part, m), ``kind (r,)``
    (``NODE_BODY``, ``CORNER_EDGE``, ``DISC_EDGE``, ``CORNER_NODE``), ``corner (r,)``
    (finger corner index or -1) and ``element (r,)`` (edge index for edge rows, node
    id otherwise).
    """

    finger: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    direction: np.ndarray
    gap: np.ndarray
    point: np.ndarray
    kind: np.ndarray
    corner: np.ndarray
    element: np.ndarray

    def __len__(self) -> int:
        return len(self.gap)

    def keys(self) -> np.ndarray:
        """Identity of each row: ``(finger, kind, corner, element)``, shape (r, 4)."""
        return np.stack([self.finger, self.kind, self.corner, self.element], axis=1)

    def take(self, idx: Any) -> "ContactRows":
        return ContactRows(*(getattr(self, k)[idx] for k in ContactRows.__dataclass_fields__))

    @staticmethod
    def concat(parts: list["ContactRows"]) -> "ContactRows":
        if not parts:
            z = np.zeros((0, 2))
            i = np.zeros(0, np.int64)
            return ContactRows(i, np.zeros((0, 2), np.int64), z, z.copy(), np.zeros(0), z.copy(),
                               i.copy(), i.copy(), i.copy())
        return ContactRows(*(np.concatenate([getattr(p, k) for p in parts]) for k in ContactRows.__dataclass_fields__))


def _rows(fi: int, kind: int, corner: Any, element: Any, nodes: Any, weights: Any, direction: Any,
          gap: Any, point: Any) -> ContactRows:
    gap = np.asarray(gap, dtype=float)
    r = len(gap)
    return ContactRows(
        np.full(r, fi, dtype=np.int64),
        np.asarray(nodes, dtype=np.int64).reshape(-1, 2),
        np.asarray(weights, dtype=float).reshape(-1, 2),
        np.asarray(direction, dtype=float).reshape(-1, 2),
        gap,
        np.asarray(point, dtype=float).reshape(-1, 2),
        np.full(r, kind, dtype=np.int64),
        np.broadcast_to(np.asarray(corner, dtype=np.int64), (r,)).copy(),
        np.broadcast_to(np.asarray(element, dtype=np.int64), (r,)).copy(),
    )


def contact_rows(
    bd: BoundaryModel, x: np.ndarray, fingers: Sequence[Finger], radius: float, x_ref: np.ndarray | None = None,
    normals_ref: np.ndarray | None = None, feet_ref: np.ndarray | None = None,
) -> ContactRows:
    """Linearised non-penetration conditions between ``fingers`` and the boundary.

    Parameters
    ----------
    bd : BoundaryModel
    x : ndarray (n, 2)
        Current configuration (m).
    fingers : sequence of Finger
    radius : float
        Search radius (m): conditions with ``gap < radius`` are returned (every
        penetrating node of a finger body, however deep).
    x_ref : ndarray (n, 2), optional
        Reference (rest) configuration: when given, the directions of all conditions
        and the material points carrying the forces on edges are taken at rest (edge
        normals at rest, the finger's foot point on the rest edge clamped to the edge,
        finger normals at the node's rest position): small-displacement theory,
        equilibrium equations on the undeformed geometry. The gaps are always
        measured in ``x``.
    normals_ref : ndarray (n, 2), optional
        Configuration whose edge normals are used with ``x_ref`` (default ``x_ref``).
    feet_ref : ndarray (n, 2), optional
        Configuration in which the foot points on edges are located (default ``x_ref``).

    Returns
    -------
    ContactRows

    Notes
    -----
    * boundary node vs finger body (disc, polygon, half-plane): gap = signed distance
      of the node, direction = the body's outward normal there;
    * finger corner (point finger, polygon corner) vs boundary edge whose foot point
      lies on the edge: gap = distance to the edge line, direction = the edge's inward
      normal, nodes = the edge ends with weights ``1 - s, s``. At a reflex vertex both
      edges give a row (the point blocks two half-planes); at a convex vertex too (the
      reaction may point anywhere in the normal cone). A corner beyond a convex vertex
      (in its normal cone) gives a node row along the line joining them;
    * disc vs boundary edge (foot point inside the edge): gap = distance to the line
      minus the radius.

    A corner on the inner side of an edge line only counts as penetrating that edge when
    it is inside the part and that edge is (one of) the nearest, so thin walls are safe.
    """
    geo = _EdgeGeometry(bd, x, x_ref, normals_ref, feet_ref)
    parts: list[ContactRows] = []
    for fi, f in enumerate(fingers):
        parts += _body_rows(geo, fi, f, radius)
        if len(f.vertices):
            parts += _corner_rows(geo, fi, f, radius)
        parts += _round_rows(geo, fi, f, radius)
    return ContactRows.concat(parts)


class _EdgeGeometry:
    """The boundary edges of configuration ``x`` for :func:`contact_rows`: ends ``a``,
    ``b``, vectors ``ab``, squared lengths, inward normals; with ``x_ref`` the reference
    geometry of the force directions and material points (see :func:`contact_rows`)."""

    def __init__(self, bd: BoundaryModel, x: np.ndarray, x_ref: np.ndarray | None,
                 normals_ref: np.ndarray | None, feet_ref: np.ndarray | None):
        self.bd, self.x = bd, x
        edges = self.edges = bd.edges
        self.a, self.b = x[edges[:, 0]], x[edges[:, 1]]
        self.ab = self.b - self.a
        self.ell2 = np.einsum("ij,ij->i", self.ab, self.ab)
        self.n_in = bd.inward_normals(x)
        self.nodes = bd.nodes
        self.xn = x[self.nodes]
        if x_ref is not None:
            x_ref = np.asarray(x_ref, dtype=float)
            xf = x_ref if feet_ref is None else np.asarray(feet_ref, dtype=float)
            self.a_ref, self.ab_ref = xf[edges[:, 0]], xf[edges[:, 1]] - xf[edges[:, 0]]
        else:
            self.a_ref, self.ab_ref = self.a, self.ab
        self.x_ref = x_ref
        self.ell2_ref = np.einsum("ij,ij->i", self.ab_ref, self.ab_ref)
        self.n_dir = self.n_in if x_ref is None else bd.inward_normals(x_ref if normals_ref is None else normals_ref)

    def rest_or_current(self, v: np.ndarray, current: np.ndarray) -> np.ndarray:
        """Positions of nodes ``v`` in the reference geometry, else ``current``."""
        return current if self.x_ref is None else self.x_ref[v]


def _body_rows(geo: _EdgeGeometry, fi: int, f: Finger, radius: float) -> list[ContactRows]:
    """Boundary nodes against the finger body: every penetrating node, however deep."""
    if not f.has_interior:
        return []
    sd = f.signed_distance(geo.xn)
    sel = sd < radius
    if not np.any(sel):
        return []
    v = geo.nodes[sel]
    dirn = f.outward_normal(geo.rest_or_current(v, geo.xn[sel]))
    return [_rows(fi, NODE_BODY, -1, v, np.stack([v, v], 1), np.c_[np.ones(len(v)), np.zeros(len(v))], dirn,
                  sd[sel], geo.xn[sel])]


def _corner_rows(geo: _EdgeGeometry, fi: int, f: Finger, radius: float) -> list[ContactRows]:
    """Finger corners against boundary edges, and against convex vertices whose normal
    cone holds them."""
    a, b, ab, n_in, xn, nodes, bd = geo.a, geo.b, geo.ab, geo.n_in, geo.xn, geo.nodes, geo.bd
    corners = f.vertices
    out: list[ContactRows] = []
    inside = bd.inside(geo.x, corners)
    rel = corners[:, None, :] - a[None]  # (k, E, 2)
    s = np.einsum("kej,ej->ke", rel, ab) / geo.ell2  # foot point in the current geometry
    # the material point carrying the force: foot point in the reference geometry
    s_ref = np.einsum("kej,ej->ke", corners[:, None, :] - geo.a_ref[None], geo.ab_ref) / geo.ell2_ref
    s_w = np.clip(s_ref, 0, 1)
    g = -np.einsum("kej,ej->ke", rel, n_in)  # outward distance to the edge line
    seg = segment_distance(a[None], b[None], corners[:, None, :])  # (k, E)
    dmin = seg.min(axis=1, keepdims=True)
    # small-displacement theory: the contact's material point is fixed at rest
    s_sel = s if geo.x_ref is None else s_ref
    on = (s_sel >= 0) & (s_sel <= 1)
    eps = 1e-12 * np.sqrt(geo.ell2)  # on the edge up to round-off: touching, inside or not
    ok = on & (((g >= -eps) & (g < radius)) | (inside[:, None] & (g < 0) & (-g <= dmin + 1e-9 * np.sqrt(geo.ell2))))
    kk, ee = np.nonzero(ok)
    if len(kk):
        ss = s_w[kk, ee]
        out.append(_rows(fi, CORNER_EDGE, kk, ee, geo.edges[ee], np.c_[1 - ss, ss], geo.n_dir[ee], g[kk, ee],
                         a[ee] + ss[:, None] * ab[ee]))
    # corners in the normal cone of a convex vertex (beyond both adjacent edges)
    e_next = bd.edge_of[nodes]
    e_prev = bd.edge_of[bd.prev[nodes]]
    beyond = (s_sel[:, e_next] < 0) & (s_sel[:, e_prev] > 1) & ~inside[:, None]
    dist = np.linalg.norm(corners[:, None, :] - xn[None], axis=-1)
    kk, vv = np.nonzero(beyond & (dist < radius) & (dist > 0))
    if len(kk):
        ref = geo.rest_or_current(nodes[vv], xn[vv])
        dirn = ref - corners[kk]
        dirn = dirn / np.linalg.norm(dirn, axis=1, keepdims=True)
        out.append(_rows(fi, CORNER_NODE, kk, nodes[vv], np.stack([nodes[vv], nodes[vv]], 1),
                         np.c_[np.ones(len(vv)), np.zeros(len(vv))], dirn, dist[kk, vv], xn[vv]))
    return out


def _round_rows(geo: _EdgeGeometry, fi: int, f: Finger, radius: float) -> list[ContactRows]:
    """A circular finger boundary against boundary edges whose foot point it faces."""
    rc = f.round_centre()
    if rc is None:
        return []
    c, r = rc
    a, ab = geo.a, geo.ab
    rel = c - a
    s = np.einsum("ej,ej->e", rel, ab) / geo.ell2
    s_ref = np.einsum("ej,ej->e", c - geo.a_ref, geo.ab_ref) / geo.ell2_ref
    s_w = np.clip(s_ref, 0, 1)
    gl = -np.einsum("ej,ej->e", rel, geo.n_in)
    gap = gl - r
    inner = (s > 0) & (s < 1) if geo.x_ref is None else (s_ref > 0) & (s_ref < 1)
    ok = inner & (gl >= 0) & (np.abs(gap) < radius)
    ee = np.flatnonzero(ok)
    if not len(ee):
        return []
    ss = s_w[ee]
    return [_rows(fi, DISC_EDGE, -1, ee, geo.edges[ee], np.c_[1 - ss, ss], geo.n_dir[ee], gap[ee],
                  a[ee] + ss[:, None] * ab[ee])]


def refresh_rows(rows: ContactRows, bd: BoundaryModel, x: np.ndarray, fingers: Sequence[Finger]) -> ContactRows:
    """Re-measure the gaps and contact points of existing rows in configuration ``x``
    (directions and weights are kept)."""
    out = rows.take(slice(None))
    out.gap = out.gap.copy()
    out.point = (out.weights[:, :, None] * x[out.nodes]).sum(axis=1)
    edges = bd.edges
    for i in range(len(out)):  # few rows; each is O(1)
        f = fingers[int(out.finger[i])]
        k = int(out.kind[i])
        if k == NODE_BODY:
            out.gap[i] = float(f.signed_distance(x[out.element[i]]))
        elif k == CORNER_NODE:
            out.gap[i] = float(np.linalg.norm(f.vertices[out.corner[i]] - x[out.element[i]]))
        else:
            u, w = edges[out.element[i]]
            t = x[w] - x[u]
            n_in = np.array([-t[1], t[0]]) / np.linalg.norm(t)
            if k == CORNER_EDGE:
                p, r = f.vertices[out.corner[i]], 0.0
            else:                                   # DISC_EDGE: the circular boundary
                p, r = f.round_centre()
            out.gap[i] = float(-n_in @ (p - x[u])) - r
    return out


def merge_rows(new: ContactRows, old: ContactRows) -> ContactRows:
    """``new`` plus the rows of ``old`` whose identity is not in ``new``."""
    if len(old) == 0:
        return new
    seen = {tuple(k) for k in new.keys().tolist()}
    keep = [i for i, k in enumerate(old.keys().tolist()) if tuple(k) not in seen]
    return ContactRows.concat([new, old.take(np.asarray(keep, dtype=np.int64))]) if keep else new


def finger_gaps(bd: BoundaryModel, x: np.ndarray, fingers: Sequence[Finger]) -> np.ndarray:
    """Smallest contact gap (m) of every finger in configuration ``x``; negative when
    the finger penetrates the part (``inf`` when no condition is within reach)."""
    L = float(np.ptp(x[bd.nodes], axis=0).max())
    rows = contact_rows(bd, x, fingers, radius=10.0 * L)
    out = np.full(len(fingers), np.inf)
    np.minimum.at(out, rows.finger, rows.gap)
    return out
