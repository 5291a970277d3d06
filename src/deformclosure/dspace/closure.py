"""Deform closure of a contact set, decided on the part's rigid motions (paper §3.3-3.4,
Thm 1; SPEC §3).

``deform_closure(mesh, fingers)`` first finds the contact equilibrium
(:func:`.equilibrium.equilibrium`), then extracts the *active contacts* there and decides
whether the equilibrium is a strict local minimum of the energy (``U_A > 0``). Because the
null space of ``K`` is exactly the rigid modes, this is decided on the rigid motions
(twists) of the part under the active contacts (paper Thm 1: deform closure of the
deformable part ⇔ form closure of the rigid part).

Contacts
--------
Every active finger contributes one *group* of half-plane constraints on the velocity
``v_p`` of the part's material point at the contact, ``n . v_p >= 0`` (``n``: unit
normal pointing from the finger into the part):

* a finger on an edge (or on a node where the part is straight at rest): one
  half-plane, the edge's inward normal (feature ``"edge"``);
* a finger corner (point finger, polygon corner) at a concave (reflex) vertex: two
  half-planes, both edges' normals, *both* must hold (``"concave_vertex"``);
* a finger corner at a convex vertex: the part escapes the corner when *one* of the
  separating lines of the two wedges stays valid (the allowed set is a union of
  half-planes); the candidates are the two part edges and, for a polygon finger, its two
  edges at the corner (separating-axis test) (``"convex_vertex"``);
* a smooth finger (disc, polygon face, half-plane) on a convex vertex: one half-plane
  with the finger's normal (``"convex_vertex"``).

Each constraint also carries the radii of curvature of the finger (``0`` point/corner,
``r`` disc, ``inf`` flat face) and of the part (``inf`` on an edge, ``0`` at a vertex)
for the second-order test.

Decision
--------
For every choice of one candidate per "union" group (all choices are tried):

1. *First order* (an LP on the twist side): maximise ``sum_i s_i`` subject to
   ``A xi >= s``, ``0 <= s <= 1``, ``|xi| <= 1`` with rows ``A_i = (n_i, (p_i - c) x n_i)``
   and ``xi = (v_c, omega)``. A positive optimum is a twist that separates a contact:
   the part escapes. Otherwise every feasible twist keeps all gaps unchanged and the
   feasible set is the null space of ``A``: empty → held (order 1); containing a
   translation (sliding along parallel edges, gaps exactly unchanged) → escapes
   (order 1); else it is one rotation ``xi_0`` about the point ``c0`` where all contact
   normals meet and the decision is at second order.
2. *Second order* (Rimon-Burdick relative curvature): a rotation by ``theta`` about
   ``c0``, at signed distance ``t_i = n_i . (c0 - p_i)`` along contact ``i``'s inward
   normal, changes that gap by ``-h_i theta^2 / 2`` with
   ``h_i = (t_i + r_f)(r_p - t_i) / (r_p + r_f)``, i.e. ``t_i + r`` for a disc of radius
   ``r`` (``r = 0`` for a point) on a flat edge (SPEC §3) and ``-t_i`` for a flat face on
   a vertex. The part escapes iff some second-order twist ``a`` offsets all of them:
   the LP ``A_i a >= h_i`` is feasible (equality allowed). Otherwise it is held at order 2.

The certificate of an escape is the twist ``[vx, vy, omega]``: the velocity (m/s) of the
part's area centroid and its angular velocity (rad/s), normalised so that
``|(vx, vy, omega L)| = 1`` with ``L`` the part's diameter.

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.3-3.4 and Thm 1.
E. Rimon and J. W. Burdick, "Mobility of bodies in contact I/II", IEEE Trans. Robotics
and Automation 14(5), 1998 (first- and second-order form closure).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..errors import DeformClosureError
from .equilibrium import EquilibriumResult, area_centroid, equilibrium
from .fingers import Finger, as_fingers
from ..contact.rows import CORNER_NODE, FEATURE_NAMES, NODE_BODY, REFLEX, STRAIGHT, BoundaryModel, contact_rows
from .obstacles import resolve_tolerance

__all__ = [
    "ContactPrimitive",
    "ContactGroup",
    "RigidClosure",
    "ContactReport",
    "ClosureResult",
    "contact_groups",
    "relative_curvature",
    "rigid_closure",
    "deform_closure",
]

UNITS = {"length": "m", "energy": "J", "stiffness": "N/m", "strain_per_length": "1/m", "force": "N"}

#: Separation (in units of the part's diameter) that counts as a strictly separating twist:
#: the optimum of the first-order LP, a round-off threshold of that LP; not the SPEC §3
#: touching tolerance (:func:`deformclosure.geometry.touch_tolerance`), which decides
#: which contacts are active.
SEPARATION_TOL = 1e-9
#: Maximum number of choices enumerated for "union" (convex-vertex) contacts.
MAX_CHOICES = 4096


@dataclass(frozen=True)
class ContactPrimitive:
    """One first-order contact constraint ``normal . v_point >= 0``.

    Attributes
    ----------
    point : tuple (x, y)
        Contact point on the part (m).
    normal : tuple (nx, ny)
        Unit normal from the finger into the part.
    finger_radius : float
        Radius of curvature of the finger at the contact (m): 0 corner/point, r disc,
        inf flat face.
    part_radius : float
        Radius of curvature of the part at the contact (m): inf on an edge, 0 at a vertex.
    """

    point: tuple[float, float]
    normal: tuple[float, float]
    finger_radius: float = 0.0
    part_radius: float = math.inf


@dataclass(frozen=True)
class ContactGroup:
    """The constraints one finger puts on the part at one contact.

    ``mode`` is ``"all"`` (every primitive must hold: an edge contact or a corner in a
    concave vertex) or ``"any"`` (one suffices: a corner on a convex vertex).
    ``feature`` is ``"edge"``, ``"concave_vertex"`` or ``"convex_vertex"``.
    """

    finger: int
    mode: str
    primitives: tuple[ContactPrimitive, ...]
    feature: str


@dataclass(frozen=True)
class RigidClosure:
    """Result of the rigid-motion test (see module docstring).

    Attributes
    ----------
    closed : bool
    order : int
        1 or 2: the order that decided.
    twist : ndarray (3,) or None
        Escaping twist ``[vx, vy, omega]`` about ``centroid`` (m/s, m/s, rad/s), normalised.
    rotation_center : ndarray (2,) or None
        Point ``c0`` where the contact normals meet, when second order was needed (m).
    """

    closed: bool
    order: int
    twist: np.ndarray | None
    rotation_center: np.ndarray | None = None


@dataclass(frozen=True)
class ContactReport:
    """One finger's entry of the check report (SPEC §5)."""

    finger: int
    active: bool
    force: tuple[float, float]
    feature: str

    def to_dict(self) -> dict:
        return {"finger": self.finger, "active": self.active, "force": [float(self.force[0]), float(self.force[1])],
                "feature": self.feature}


@dataclass(frozen=True)
class ClosureResult:
    """Deform-closure verdict of a contact set (paper §3.3-3.4).

    Attributes
    ----------
    deform_closure : bool
        The equilibrium is a strict local minimum: the fingers hold the part.
    order : int
        1 or 2, the order that decided.
    energy : float
        Linear elastic energy at the equilibrium (J).
    contacts : tuple of ContactReport
        One per finger, in input order.
    twist : ndarray (3,) or None
        Escaping twist ``[vx, vy, omega]`` (velocity of the area centroid in m/s and
        angular velocity in rad/s, ``|(vx, vy, omega L)| = 1``), ``None`` when closed.
    centroid : ndarray (2,)
        Area centroid of the equilibrium configuration (m), the twist's reference point.
    rotation_center : ndarray (2,) or None
        Where the contact normals meet when second order decided (m).
    groups : tuple of ContactGroup
        The active contact constraints.
    equilibrium : EquilibriumResult
    """

    deform_closure: bool
    order: int
    energy: float
    contacts: tuple[ContactReport, ...]
    twist: np.ndarray | None
    centroid: np.ndarray
    rotation_center: np.ndarray | None
    groups: tuple[ContactGroup, ...] = field(repr=False)
    equilibrium: EquilibriumResult = field(repr=False)

    def to_dict(self) -> dict:
        """The check report (SPEC §5), SI units."""
        return {
            "deform_closure": bool(self.deform_closure),
            "order": int(self.order),
            "energy": float(self.energy),
            "contacts": [c.to_dict() for c in self.contacts],
            "certificate": None if self.twist is None else {"twist": [float(v) for v in self.twist]},
            "units": dict(UNITS),
            # beyond the SPEC keys: where the twist is taken and how the equilibrium went
            "centroid": [float(v) for v in self.centroid],
            "equilibrium": {k: v for k, v in self.equilibrium.to_dict().items() if k != "units"},
        }


# ----------------------------------------------------------------------------- contacts


def _single(fi: int, point: Any, normal: Any, rf: float, rp: float, feature: str) -> ContactGroup:
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    prim = ContactPrimitive((float(point[0]), float(point[1])), (float(n[0]), float(n[1])), float(rf), float(rp))
    return ContactGroup(fi, "all", (prim,), feature)


def contact_groups(mesh: Any, q: Any, fingers: Sequence[Finger], tol: float | None = None) -> tuple[ContactGroup, ...]:
    """Active contacts of ``fingers`` with the part in configuration ``q``.

    Parameters
    ----------
    mesh : Mesh
        Gives the boundary loops and the rest geometry (contact features are classified
        at rest: a node on a straight edge at rest is an edge contact even when a finger
        dents it).
    q : array_like (n, 2)
        Configuration (m), usually the contact equilibrium.
    fingers : sequence of Finger
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter``.

    Returns
    -------
    tuple of ContactGroup
        In finger order; a finger may give several groups (e.g. a flat jaw on an edge
        gives one per touching node) or none (not touching).
    """
    x = np.asarray(q, dtype=float).reshape(-1, 2)
    tol = resolve_tolerance(mesh, tol)
    geo = _Boundary(BoundaryModel(mesh), x)
    out: list[ContactGroup] = []
    for fi, f in enumerate(fingers):
        at_corner = np.zeros(len(geo.nodes), dtype=bool)   # nodes touched by a finger corner
        for k in range(len(f.vertices)):
            out += _corner_groups(geo, fi, f, k, tol, at_corner)
        if f.has_interior:
            out += _body_groups(geo, fi, f, tol, at_corner)
            if (rc := f.round_centre()) is not None:
                out += _round_groups(geo, fi, *rc, tol)
    return tuple(out)


class _Boundary:
    """Boundary nodes and edges of configuration ``x`` (ends, vectors, lengths, inward
    normals) with the rest-geometry features of :class:`deformclosure.contact.rows.BoundaryModel`."""

    def __init__(self, bd: BoundaryModel, x: np.ndarray):
        self.bd, self.x = bd, x
        self.nodes = bd.nodes
        self.P = x[self.nodes]
        edges = bd.edges
        self.a, self.b = x[edges[:, 0]], x[edges[:, 1]]
        self.ab = self.b - self.a
        self.ell = np.linalg.norm(self.ab, axis=1)
        self.n_in = bd.inward_normals(x)

    def edge_feet(self, p: np.ndarray, offset: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
        """Foot parameter ``s`` of point ``p`` on every edge and the edges it touches:
        foot inside the edge by more than ``tol`` and distance to the line minus
        ``offset`` within ``tol``. Returns ``(s, g, touching)``."""
        rel = p - self.a
        s = np.einsum("ej,ej->e", rel, self.ab) / self.ell**2
        g = -np.einsum("ej,ej->e", rel, self.n_in) - offset
        ok = (s * self.ell > tol) & ((1 - s) * self.ell > tol) & (np.abs(g) <= tol)
        return s, g, ok


def _corner_groups(geo: _Boundary, fi: int, f: Finger, k: int, tol: float,
                   at_corner: np.ndarray) -> list[ContactGroup]:
    """Finger corner ``k`` at a boundary node (marked in ``at_corner``) or on an edge."""
    bd, x = geo.bd, geo.x
    fv = f.vertices[k]
    dn = np.linalg.norm(geo.P - fv, axis=1)
    j = int(np.argmin(dn))
    if dn[j] <= tol:
        at_corner[j] = True
        v = int(geo.nodes[j])
        e_prev, e_next = int(bd.edge_of[bd.prev[v]]), int(bd.edge_of[v])
        feat = int(bd.feature[v])
        if feat == STRAIGHT:
            return [_single(fi, x[v], bd.node_normals(x, np.array([v]))[0], 0.0, math.inf, "edge")]
        if feat == REFLEX:
            prims = tuple(ContactPrimitive(tuple(x[v]), tuple(geo.n_in[e]), 0.0, math.inf) for e in (e_prev, e_next))
            return [ContactGroup(fi, "all", prims, "concave_vertex")]
        return [ContactGroup(fi, "any", _convex_axes(f, k, x, v, bd, geo.n_in, e_prev, e_next), "convex_vertex")]
    s, g, ok = geo.edge_feet(fv, 0.0, tol)
    if not np.any(ok):
        return []
    e = int(np.flatnonzero(ok)[np.argmin(np.abs(g[ok]))])
    return [_single(fi, geo.a[e] + s[e] * geo.ab[e], geo.n_in[e], 0.0, math.inf, "edge")]


def _body_groups(geo: _Boundary, fi: int, f: Finger, tol: float, at_corner: np.ndarray) -> list[ContactGroup]:
    """Boundary nodes touching the finger body (not at one of its corners). A curved
    body on a node of a straight edge is an edge contact; a flat face on any node has
    the node as a vertex (part radius 0)."""
    sd = f.signed_distance(geo.P)
    touch = (np.abs(sd) <= tol) & ~at_corner
    corners = f.vertices
    if len(corners):  # nodes at a polygon corner are corner contacts
        dc = np.linalg.norm(geo.P[:, None, :] - corners[None], axis=-1).min(axis=1)
        touch &= dc > tol
    rf = f.radius_of_curvature
    out = []
    for j in np.flatnonzero(touch):
        v = int(geo.nodes[j])
        feat = int(geo.bd.feature[v])
        rp = math.inf if (feat == STRAIGHT and math.isfinite(rf)) else 0.0
        out.append(_single(fi, geo.x[v], f.outward_normal(geo.x[v]), rf, rp, FEATURE_NAMES[feat]))
    return out


def _round_groups(geo: _Boundary, fi: int, c: np.ndarray, r: float, tol: float) -> list[ContactGroup]:
    """A circular finger boundary (centre ``c``, radius ``r``) touching edges between
    their nodes."""
    s, _, ok = geo.edge_feet(c, r, tol)
    return [_single(fi, geo.a[e] + s[e] * geo.ab[e], geo.n_in[e], r, math.inf, "edge") for e in np.flatnonzero(ok)]


def _convex_axes(f: Finger, k: int, x: np.ndarray, v: int, bd: BoundaryModel, n_in: np.ndarray,
                 e_prev: int, e_next: int) -> tuple[ContactPrimitive, ...]:
    """Separating-axis candidates of a finger corner on a convex part vertex."""
    xv = x[v]
    prims: list[ContactPrimitive] = []
    wf = f.corner_edges(k)
    for e in (e_prev, e_next):
        # valid when the finger's wedge lies on the outer side of the edge's line
        if all(float(n_in[e] @ w) <= 1e-9 * np.linalg.norm(w) for w in wf):
            prims.append(ContactPrimitive(tuple(xv), tuple(n_in[e]), 0.0, math.inf))
    wp = [x[bd.prev[v]] - xv, x[bd.next[v]] - xv]
    for m in f.corner_normals(k):  # the finger's two faces at corner k
        if all(float(m @ w) >= -1e-9 * np.linalg.norm(w) for w in wp):
            prims.append(ContactPrimitive(tuple(xv), tuple(m), math.inf, 0.0))
    if not prims:  # overlapping wedges (should not happen when touching): block both edges
        prims = [ContactPrimitive(tuple(xv), tuple(n_in[e]), 0.0, math.inf) for e in (e_prev, e_next)]
    return tuple(prims)


# ----------------------------------------------------------------------------- rigid test


def relative_curvature(t: np.ndarray, finger_radius: np.ndarray, part_radius: np.ndarray) -> np.ndarray:
    """Second-order gap coefficient ``h`` (m) of contacts under a rotation about ``c0``.

    A rotation by ``theta`` about the point at signed distance ``t`` along a contact's
    inward normal changes its gap by ``-h theta^2 / 2`` with
    ``h = (t + r_f)(r_p - t) / (r_p + r_f)`` (Rimon-Burdick; finger radius ``r_f``,
    part radius ``r_p``, either may be ``inf``). Special cases: ``t + r`` for a disc
    (or point, ``r = 0``) on a flat edge; ``-t`` for a flat face on a vertex.
    """
    t = np.asarray(t, float)
    rf = np.broadcast_to(np.asarray(finger_radius, float), t.shape)
    rp = np.broadcast_to(np.asarray(part_radius, float), t.shape)
    h = np.zeros_like(t)
    fin_f, fin_p = np.isfinite(rf), np.isfinite(rp)
    m = fin_f & ~fin_p
    h[m] = t[m] + rf[m]
    m = ~fin_f & fin_p
    h[m] = rp[m] - t[m]
    m = fin_f & fin_p & (rf + rp > 0)
    h[m] = (t[m] + rf[m]) * (rp[m] - t[m]) / (rp[m] + rf[m])
    # flat on flat (never a single-point contact) and corner on corner: no curvature term
    return h


def _linprog(c: np.ndarray, A_ub: np.ndarray, b_ub: np.ndarray, bounds: list) -> Any:
    from scipy.optimize import linprog

    res = linprog(c, A_ub=A_ub, b_ub=b_ub, bounds=bounds, method="highs")
    if res.status not in (0,):
        raise DeformClosureError(f"closure LP failed ({res.message})")
    return res


def _first_order(A: np.ndarray) -> tuple[str, np.ndarray]:
    """``("escape", xi)``, ``("closed", None)`` or ``("rotation", xi0)`` for scaled rows ``A``."""
    k = len(A)
    if k == 0:
        return "escape", np.array([1.0, 0.0, 0.0])
    # maximise sum s  s.t.  -A xi + s <= 0,  |xi| <= 1, 0 <= s <= 1
    c = np.r_[np.zeros(3), -np.ones(k)]
    A_ub = np.hstack([-A, np.eye(k)])
    res = _linprog(c, A_ub, np.zeros(k), [(-1, 1)] * 3 + [(0, 1)] * k)
    if -res.fun > SEPARATION_TOL:
        return "escape", np.asarray(res.x[:3])
    _, S, Vt = np.linalg.svd(A, full_matrices=True)
    rank = int(np.sum(S > 1e-9 * max(S.max(initial=0.0), 1.0)))
    N = Vt[rank:]  # rows span the null space
    if len(N) == 0:
        return "closed", np.zeros(3)
    if len(N) >= 2:  # contains a translation: the combination with zero rotation
        coef = np.linalg.svd(N[:, 2][None])[2][-1]
        xi = coef @ N
        return "escape", xi / np.linalg.norm(xi)
    xi0 = N[0]
    if abs(xi0[2]) <= 1e-9 * np.linalg.norm(xi0):
        return "escape", xi0 / np.linalg.norm(xi0)  # a pure translation keeps every gap
    return "rotation", xi0 / xi0[2]


def rigid_closure(groups: Sequence[ContactGroup], centroid: Any, length: float) -> RigidClosure:
    """Decide form closure of the rigid part under contact ``groups`` (module docstring).

    Parameters
    ----------
    groups : sequence of ContactGroup
    centroid : array_like (2,)
        Reference point of the twists (m), the part's area centroid.
    length : float
        Length scale ``L`` (m), the part's diameter (scales rotations in the LPs).

    Returns
    -------
    RigidClosure
    """
    c = np.asarray(centroid, float)
    L = float(length)
    options = []
    for g in groups:
        if g.mode == "any":
            options.append([(p,) for p in g.primitives])
        else:
            options.append([g.primitives])
    n_choices = int(np.prod([len(o) for o in options])) if options else 1
    if n_choices > MAX_CHOICES:
        raise DeformClosureError(
            f"{n_choices} combinations of convex-vertex contacts to enumerate (limit {MAX_CHOICES}); "
            "use fewer point fingers on convex vertices"
        )
    pending = []
    for choice in itertools.product(*options) if options else [()]:
        prims = [p for group in choice for p in group]
        P = np.array([p.point for p in prims], float).reshape(-1, 2)
        Nn = np.array([p.normal for p in prims], float).reshape(-1, 2)
        arm = (P - c) / L
        A = np.c_[Nn, arm[:, 0] * Nn[:, 1] - arm[:, 1] * Nn[:, 0]]
        status, xi = _first_order(A)
        if status == "escape":
            return RigidClosure(False, 1, _twist_si(xi, L))
        if status == "rotation":
            pending.append((prims, A, xi))
    if not pending:
        return RigidClosure(True, 1, None)
    center = None
    for prims, A, xi in pending:
        center = c + L * np.array([-xi[1], xi[0]]) / xi[2]  # c0 = c + J v / omega
        P = np.array([p.point for p in prims], float)
        Nn = np.array([p.normal for p in prims], float)
        t = np.einsum("ij,ij->i", Nn, center - P)
        h = relative_curvature(t, [p.finger_radius for p in prims], [p.part_radius for p in prims])
        # feasibility of A a >= h / L: maximise s with A a - s >= h / L
        k = len(A)
        cvec = np.r_[np.zeros(3), -1.0]
        A_ub = np.hstack([-A, np.ones((k, 1))])
        res = _linprog(cvec, A_ub, -h / L, [(-1e3, 1e3)] * 3 + [(None, 1.0)])
        if -res.fun >= -1e-9:
            return RigidClosure(False, 2, _twist_si(xi, L), center)
    return RigidClosure(True, 2, None, center)


def _twist_si(xi: np.ndarray, L: float) -> np.ndarray:
    """Scaled twist ``(v / L, omega)`` -> SI ``[vx, vy, omega]`` with ``|(v, omega L)| = 1``."""
    xi = np.asarray(xi, float)
    xi = xi / float(np.linalg.norm(xi))
    return np.array([xi[0], xi[1], xi[2] / L])


# ----------------------------------------------------------------------------- driver


def _nearest_feature(bd: BoundaryModel, x: np.ndarray, finger: Finger, L: float) -> str:
    rows = contact_rows(bd, x, [finger], radius=10.0 * L)
    if len(rows) == 0:
        return "edge"
    i = int(np.argmin(rows.gap))
    if rows.kind[i] in (NODE_BODY, CORNER_NODE):
        return FEATURE_NAMES[int(bd.feature[rows.element[i]])]
    w = rows.weights[i]
    if w[0] > 1 - 1e-12:
        return FEATURE_NAMES[int(bd.feature[rows.nodes[i, 0]])]
    if w[1] > 1 - 1e-12:
        return FEATURE_NAMES[int(bd.feature[rows.nodes[i, 1]])]
    return "edge"


def deform_closure(
    mesh: Any,
    fingers: Sequence[Finger],
    *,
    stiffness: Any = None,
    tol: float | None = None,
    equilibrium_result: EquilibriumResult | None = None,
) -> ClosureResult:
    """Is the part held by ``fingers``? Deform closure at the contact equilibrium.

    Parameters
    ----------
    mesh : Mesh
        The part (rest configuration, m) with its material.
    fingers : sequence of Finger
        Fixed fingers placed against the part at rest (touching or pre-squeezing), m.
    stiffness : sparse matrix (2n, 2n), optional
        ``K`` (N/m); assembled from the mesh when omitted.
    tol : float, optional
        Touching tolerance (m); default ``1e-9`` x ``mesh.diameter`` (SPEC §3).
    equilibrium_result : EquilibriumResult, optional
        Reuse an equilibrium computed before (:func:`.equilibrium.equilibrium`).

    Returns
    -------
    ClosureResult
        Verdict and deciding order (1 or 2), energy at the equilibrium (J, linear),
        contacts with forces (N) and features, escaping twist certificate
        ``[vx, vy, omega]`` (m/s, m/s, rad/s) about the area centroid (m).

    Raises
    ------
    FingerError, FingerPlacementError
        ``fingers`` is not a sequence of fingers, or one starts deep inside the part.
    DeformClosureError
        The contact problem or a closure LP cannot be solved.

    Examples
    --------
    A 40 mm x 20 mm rubber plate between four point fingers, one at the middle of each
    side: every twist keeps the gaps to first order (the contact normals meet at the
    centre), and the second order decides that it is held.

    >>> from deformclosure import Part, mesh_part
    >>> from deformclosure.dspace import PointFinger, deform_closure
    >>> part = Part.from_dict({"name": "plate", "units": "mm",
    ...     "outer": [[0, 0], [40, 0], [40, 20], [0, 20]],
    ...     "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 2,
    ...                  "elastic_limit_strain": 0.5},
    ...     "mesh": {"max_area": 40, "points": [[20, 0], [40, 10], [20, 20], [0, 10]]}})
    >>> fingers = [PointFinger((0.02, 0.0)), PointFinger((0.04, 0.01)),
    ...            PointFinger((0.02, 0.02)), PointFinger((0.0, 0.01))]
    >>> res = deform_closure(mesh_part(part), fingers)
    >>> res.deform_closure, res.order, res.twist is None
    (True, 2, True)

    References
    ----------
    Gopalakrishnan & Goldberg (2005), §3.3-3.4, Thm 1; Rimon & Burdick (1998).
    """
    fingers = list(as_fingers(fingers))
    tol = resolve_tolerance(mesh, tol)
    eq = equilibrium_result or equilibrium(mesh, fingers, stiffness=stiffness, tol=tol)
    x = eq.q
    L = float(mesh.diameter)
    bd = BoundaryModel(mesh)
    groups = contact_groups(mesh, x, fingers, tol=tol)
    groups = tuple(groups) + _unresolved_groups(eq, groups, fingers, bd, L)
    c = area_centroid(mesh.triangles, x)
    rc = rigid_closure(groups, c, L)
    contacts = _contact_reports(eq, groups, fingers, bd, L, tol)
    return ClosureResult(
        deform_closure=rc.closed, order=rc.order, energy=float(eq.energy), contacts=contacts,
        twist=rc.twist, centroid=c, rotation_center=rc.rotation_center, groups=groups, equilibrium=eq,
    )


def _unresolved_groups(eq: EquilibriumResult, groups: Sequence[ContactGroup], fingers: Sequence[Finger],
                       bd: BoundaryModel, L: float) -> tuple[ContactGroup, ...]:
    """Groups of the fingers that push but whose contact is not resolved within ``tol``
    (round-off of the contact solve): the solver's contact conditions instead."""
    have = {g.finger for g in groups}
    x = eq.q
    extra: list[ContactGroup] = []
    for i in range(len(fingers)):
        if i not in have and np.linalg.norm(eq.forces[i]) > 0:
            sel = np.flatnonzero((eq.rows.finger == i) & (eq.multipliers > 0))
            for r in sel:
                pt = (eq.rows.weights[r, :, None] * x[eq.rows.nodes[r]]).sum(axis=0)
                extra.append(_single(i, pt, eq.rows.direction[r], fingers[i].radius_of_curvature, 0.0,
                                     _nearest_feature(bd, x, fingers[i], L)))
    return tuple(extra)


def _contact_reports(eq: EquilibriumResult, groups: Sequence[ContactGroup], fingers: Sequence[Finger],
                     bd: BoundaryModel, L: float, tol: float) -> tuple[ContactReport, ...]:
    """One report per finger: active (touching or pushing), force (N), part feature."""
    out = []
    for i, f in enumerate(fingers):
        mine = [g for g in groups if g.finger == i]
        active = bool(mine) or bool(np.linalg.norm(eq.forces[i]) > 0)
        feature = _reported_feature(mine, bd, eq.q, f, L, tol)
        out.append(ContactReport(i, active, (float(eq.forces[i, 0]), float(eq.forces[i, 1])), feature))
    return tuple(out)


def _reported_feature(mine: list[ContactGroup], bd: BoundaryModel, x: np.ndarray, f: Finger, L: float,
                      tol: float) -> str:
    """The part feature reported for one finger from its contact groups ``mine``."""
    feats = {g.feature for g in mine}
    if "concave_vertex" in feats:
        return "concave_vertex"
    if "edge" in feats:
        return "edge"
    if mine:
        pts = {tuple(np.round(np.array(p.point) / max(tol, 1e-300))) for g in mine for p in g.primitives}
        return "edge" if len(pts) > 1 else "convex_vertex"
    return _nearest_feature(bd, x, f, L)
