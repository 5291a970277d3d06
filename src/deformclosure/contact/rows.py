"""Contact rows: the linearised non-penetration conditions between rigid bodies
(:mod:`.bodies`) and a part's boundary — one builder for every model (SPEC §3, §6, §7).

A *row* ``r`` is one condition ``g_r + Σ_j w_j d_rᵀ u_j ≥ 0``: a gap ``g_r`` (m, ≥ 0
when free) that involves up to two boundary nodes ``j`` with weights ``w`` (summing to
1) and a unit direction ``d_r`` — the outward normal of the body there, pointing from the
body into the part, which is the gap's gradient and the direction of the contact force
``λ_r d_r`` on the part (frictionless). The tangent ``t_r = (−d_y, d_x)``
(:meth:`ContactRows.tangents`) is what friction (SPEC §9) adds. Each row has an identity
``(finger, kind, corner, element)`` that survives re-linearisation (warm starts,
:func:`merge_rows`).

The rule per body kind
----------------------
The candidate contacts of each body, with their gap and direction, in the configuration
``x`` of the part (fingers fixed):

* **half-plane, convex polygon** (bodies with an interior) — ``NODE_BODY``: every boundary
  node whose signed distance to the body is below the search radius, however deep; gap =
  the signed distance, direction = the body's outward normal at the node (the radial
  direction from the nearest boundary point outside a polygon, its face normal inside).
* **point finger, polygon corners** (the body's corners) —

  - ``CORNER_EDGE`` on every boundary edge whose foot point the corner has (foot
    parameter ``s ∈ [0, 1]``) and whose line it is outside of (gap ≥ −1e-12 ℓ up to
    round-off, ℓ the edge length): gap = distance to the line, direction = the edge's
    inward normal, shared by the edge's end nodes with weights ``1 − s, s``;
  - ``CORNER_NODE`` on a boundary vertex whose normal cone holds the corner (beyond both
    adjacent edges, outside the part): gap = distance, direction = from the corner to the
    node;
  - a corner *inside* the part presses only on its nearest boundary (so a thin wall is
    not pushed from both sides) — :attr:`RowRule.inside_corner` says how.
* **disc** — :attr:`RowRule.disc` says how: by its radial distance and a row on every
  edge that passes it between two nodes (``"radial"``, SPEC §3), or as the round pad of
  SPEC §6 along its axis (``"pad"``, SPEC §7).

Two rules, two presets
----------------------
The §3 analysis of ``check`` (the contact equilibrium and the rigid closure test at rest,
:mod:`deformclosure.dspace.equilibrium`, :mod:`deformclosure.dspace.closure`) and the §7
placement landscape (:mod:`deformclosure.dspace.placement_energy`, whose compiled scan is
the fast path of :data:`PLACEMENT_RULE` and is tested against this module) differ by
design in three choices, the fields of :class:`RowRule`:

``disc``
    ``"radial"`` (§3): a disc is a circle; node rows by the radial signed distance, and
    ``DISC_EDGE`` rows on every edge whose foot point it faces from outside the edge's
    line (gap = the centre's distance to the line minus ``r``, within the search radius
    in absolute value). ``"pad"`` (§7): a disc presses like a round pad of SPEC §6 along
    its *axis* (given per finger): a node not behind it (axial coordinate ``s ≥ −r``)
    within the pad's reach (``|x| < r sin 75°``, :data:`.bodies.FLANK_ANGLE`) has the gap
    along the axis to :meth:`.bodies.Capsule.profile` at its cross coordinate ``x``,
    scaled to a unit gradient, and the disc's normal there; beyond the reach no row.
    Behind the disc the radial distance, except in material the disc is pressed into by
    more than its diameter (the node's boundary does not face the disc's back — inward
    normal within 45° of minus the axis — and the disc's back at the node's cross
    coordinate lies inside the part), where the pad's rule holds. While no node is inside
    the disc: a centre outside the part gives ``DISC_EDGE`` rows on edges whose foot point
    it faces from outside and whose end nodes are outside the disc; a centre inside the
    part presses on its nearest edge like a corner with offset ``r`` (``CENTRE_EDGE``) or
    its nearest vertex (``CORNER_NODE``), by the ``"least_deep"`` rule below whatever
    ``inside_corner`` says. Once a node is inside, the node rows alone see the disc (a
    round pad pressed past its centre).
``inside_corner``
    For point fingers and polygon corners. ``"nearest"`` (§3): a corner inside the part gives a ``CORNER_EDGE`` row on every edge
    whose line is within round-off (``1e-9 ℓ``) of the corner's distance to the boundary,
    and also the rows of the outside rule on edges whose line it is outside of.
    ``"least_deep"`` (§7): only one row — among the edges within twice that distance
    (foot on the edge, corner on their inner side) the one the finger crosses least deeply
    (for a polygon the depth of the whole polygon past the edge's line, so a finger
    corner passing a part's corner presses its side, not its end; ties to the edge whose
    line is nearer) — or, when there is none, ``CORNER_NODE`` rows pushing the nearest
    boundary vertex past the corner (gap = minus the distance minus the offset).
``cone``
    Which vertices take ``CORNER_NODE`` rows from a corner outside the part in their
    normal cone: ``"any"`` boundary node (§3) or only the ``"convex"`` ones at rest (§7).
``disc_depth``
    Whether a disc counts in the finger depth of :func:`contact_reach`: ``True`` at rest
    (``check`` refuses a disc deeper than half the inscribed radius,
    :func:`deformclosure.dspace.placement.check_finger_placement`), ``False`` for
    placements (a disc, like a pad, has no depth limit: its gap along the axis resists
    any depth).

Small-displacement theory (§3): with a reference configuration ``x_ref`` the directions,
the foot points carrying the forces on edges and the weights are taken on it (the
equilibrium equations on the undeformed geometry); the gaps are always measured in ``x``.

References
----------
K. Gopalakrishnan and K. Goldberg, IJRR 24(11), 2005, §3.2-3.3.
P. Wriggers, *Computational Contact Mechanics*, 2nd ed., Springer 2006 (node-to-surface
contact).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..choices import choose
from ..errors import DeformClosureError
from .bodies import Capsule, Finger, segment_distance

__all__ = [
    "BoundaryModel",
    "ContactRows",
    "RowRule",
    "EQUILIBRIUM_RULE",
    "PLACEMENT_RULE",
    "Reach",
    "contact_rows",
    "contact_reach",
    "refresh_rows",
    "merge_rows",
    "finger_gaps",
    "ray_crossings",
    "STRAIGHT", "CONVEX", "REFLEX", "FEATURE_NAMES", "STRAIGHT_SINE",
    "NODE_BODY", "CORNER_EDGE", "CORNER_NODE", "CENTRE_EDGE", "DISC_EDGE", "ROW_KINDS",
]

#: Part-feature codes of boundary nodes at rest.
STRAIGHT, CONVEX, REFLEX = 0, 1, 2
FEATURE_NAMES = {STRAIGHT: "edge", CONVEX: "convex_vertex", REFLEX: "concave_vertex"}

#: Sine of the turning angle below which a boundary node counts as straight (on an edge).
STRAIGHT_SINE = 1e-6

#: Kinds of contact rows (the same codes in the compiled placement kernel).
NODE_BODY, CORNER_EDGE, CORNER_NODE, CENTRE_EDGE, DISC_EDGE = 0, 1, 2, 3, 4
ROW_KINDS = {NODE_BODY: "node_body", CORNER_EDGE: "corner_edge", CORNER_NODE: "corner_node",
             CENTRE_EDGE: "centre_edge", DISC_EDGE: "disc_edge"}

#: A boundary faces a disc's back when its inward normal is within 45° of minus the axis.
_HALF_SQRT2 = 0.7071067811865476

#: The choices of :class:`RowRule`.
DISC_RULES = ("radial", "pad")
INSIDE_CORNER_RULES = ("nearest", "least_deep")
CONE_RULES = ("any", "convex")


@dataclass(frozen=True)
class RowRule:
    """How the contact rows treat discs, corners inside the part and vertex cones (see
    the module notes, "Two rules, two presets").

    Examples
    --------
    >>> RowRule(disc="pad", inside_corner="least_deep", cone="convex", disc_depth=False) == PLACEMENT_RULE
    True
    >>> RowRule(disc="round")
    Traceback (most recent call last):
    ...
    deformclosure.errors.DeformClosureError: disc = 'round': choose one of radial, pad
    """

    disc: str = "radial"
    inside_corner: str = "nearest"
    cone: str = "any"
    disc_depth: bool = True

    def __post_init__(self) -> None:
        choose(self.disc, DISC_RULES, "disc")
        choose(self.inside_corner, INSIDE_CORNER_RULES, "inside_corner")
        choose(self.cone, CONE_RULES, "cone")


#: The rule of ``check``'s contact equilibrium and rigid closure test (SPEC §3).
EQUILIBRIUM_RULE = RowRule("radial", "nearest", "any", True)
#: The rule of the placement landscape (SPEC §7; the compiled kernel of
#: :mod:`deformclosure.dspace.placement_energy`).
PLACEMENT_RULE = RowRule("pad", "least_deep", "convex", False)


def ray_crossings(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Even-odd rule: does the ray from ``p`` towards +x cross edge ``a-b``? (Arrays
    ``(..., 2)`` broadcast; bool ``(...)``.)"""
    ay, by, py = a[..., 1], b[..., 1], p[..., 1]
    straddle = (ay > py) != (by > py)
    dy = np.where(straddle, by - ay, 1.0)
    xint = a[..., 0] + (py - ay) * (b[..., 0] - a[..., 0]) / dy
    return straddle & (p[..., 0] < xint)


class BoundaryModel:
    """Boundary loops of a mesh with rest-geometry feature classes (paper §3.3).

    Attributes
    ----------
    edges : ndarray (E, 2)
        Loop edges ``u -> w`` with the part's interior on the left (``mesh.boundary_edges``).
    nodes : ndarray (B,)
        Boundary node ids, ``nodes[k] = edges[k, 0]``.
    prev, next : ndarray (n,)
        Loop neighbours of every boundary node (``-1`` elsewhere).
    edge_of : ndarray (n,)
        The edge starting at every boundary node (``-1`` elsewhere).
    feature : ndarray (n,)
        ``STRAIGHT``, ``CONVEX`` or ``REFLEX`` at rest (``-1`` for interior nodes).
    """

    def __init__(self, mesh: Any):
        self.edges = np.asarray(mesh.boundary_edges, dtype=np.int64).reshape(-1, 2)
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
        return np.logical_xor.reduce(ray_crossings(a[None], b[None], points[:, None, :]), axis=-1)


@dataclass
class ContactRows:
    """Linearised contact conditions in one configuration (see module notes).

    All arrays have one row per condition: ``finger (r,)``, ``nodes (r, 2)``,
    ``weights (r, 2)``, ``direction (r, 2)`` (unit, from the finger into the part: the
    row's normal), ``gap (r,)`` (m), ``point (r, 2)`` (contact point on the part, m),
    ``kind (r,)`` (``NODE_BODY``, ``CORNER_EDGE``, ``CORNER_NODE``, ``CENTRE_EDGE``,
    ``DISC_EDGE``), ``corner (r,)`` (finger corner index or -1) and ``element (r,)`` (edge
    index for edge rows, node id otherwise).
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

    def tangents(self) -> np.ndarray:
        """Unit tangents ``(−d_y, d_x)`` of the rows, shape (r, 2) (for friction, SPEC §9;
        the convention of :meth:`deformclosure.contact.solve.ContactProblem.tangents`)."""
        d = np.asarray(self.direction, float)
        return np.column_stack([-d[:, 1], d[:, 0]])

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


@dataclass(frozen=True)
class Reach:
    """How far the fingers reach into the part in one configuration (m, per finger).

    Attributes
    ----------
    penetration : ndarray (n_fingers,)
        Deepest penetration of the finger's candidates — a node inside its body, a corner
        inside the part at its distance from the boundary (under the pad rule also a disc's
        centre, plus ``r``), an edge cutting a disc between its nodes — 0 when none
        penetrates. The search radius of the placement kernel is a multiple of the largest.
    depth : ndarray (n_fingers,)
        The finger's depth for the admissibility limit: nodes inside its body and its
        corners inside the part (discs only with :attr:`RowRule.disc_depth`).
    """

    penetration: np.ndarray
    depth: np.ndarray


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
    normals_ref: np.ndarray | None = None, feet_ref: np.ndarray | None = None, *,
    rule: RowRule = EQUILIBRIUM_RULE, axes: Any = None,
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
    rule : RowRule
        :data:`EQUILIBRIUM_RULE` (SPEC §3, default) or :data:`PLACEMENT_RULE` (SPEC §7).
    axes : array_like (n_fingers, 2), optional
        Pressing axis of every disc (unit, the frame of ``x``), needed by
        ``rule.disc == "pad"``.

    Returns
    -------
    ContactRows

    Notes
    -----
    The rule per body kind is in the module notes. A corner on the inner side of an edge
    line only counts as penetrating that edge when it is inside the part and that edge is
    (one of) the nearest, so thin walls are safe.

    Examples
    --------
    A 10 mm square with a node at (5, 0) mm; a point finger 1 mm below its bottom edge, and
    a disc pressed 0.1 mm into it at that node, pressing like a round pad along +y:

    >>> from deformclosure import Part, mesh_part
    >>> from deformclosure.contact.bodies import DiscFinger, PointFinger
    >>> square = mesh_part(Part.from_dict({"units": "mm", "outer": [[0, 0], [10, 0], [10, 10], [0, 10]],
    ...     "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "elastic_limit_strain": 0.5},
    ...     "mesh": {"points": [[5, 0]]}}))
    >>> bd = BoundaryModel(square)
    >>> rows = contact_rows(bd, square.nodes, [PointFinger((0.004, -0.001))], radius=0.002)
    >>> ROW_KINDS[int(rows.kind[0])], float(rows.gap[0]), rows.direction[0] + 0.0
    ('corner_edge', 0.001, array([0., 1.]))
    >>> disc = DiscFinger((0.005, -0.0009), 0.001)
    >>> rows = contact_rows(bd, square.nodes, [disc], radius=0.0, rule=PLACEMENT_RULE, axes=[[0.0, 1.0]])
    >>> ROW_KINDS[int(rows.kind[0])], round(float(rows.gap[0]), 12), square.nodes[rows.element[0]].tolist()
    ('node_body', -0.0001, [0.005, 0.0])
    """
    return _RowBuilder(bd, x, fingers, rule, axes, x_ref, normals_ref, feet_ref).rows(float(radius))


def contact_reach(bd: BoundaryModel, x: np.ndarray, fingers: Sequence[Finger], *,
                  rule: RowRule = EQUILIBRIUM_RULE, axes: Any = None) -> Reach:
    """How far each finger reaches into the part in configuration ``x`` under ``rule``
    (:class:`Reach`; the same candidates as :func:`contact_rows`)."""
    return _RowBuilder(bd, x, fingers, rule, axes, None, None, None).reach()


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
        self._node_inward: np.ndarray | None = None
        self._local: np.ndarray | None = None

    def rest_or_current(self, v: np.ndarray, current: np.ndarray) -> np.ndarray:
        """Positions of nodes ``v`` in the reference geometry, else ``current``."""
        return current if self.x_ref is None else self.x_ref[v]

    @property
    def node_inward(self) -> np.ndarray:
        """Inward normal (unnormalised) of the boundary at every boundary node: the sum of
        its two edges' inward unit normals, ``(B, 2)``."""
        if self._node_inward is None:
            bd = self.bd
            self._node_inward = self.n_in[bd.edge_of[bd.prev[self.nodes]]] + self.n_in[bd.edge_of[self.nodes]]
        return self._node_inward

    @property
    def local(self) -> np.ndarray:
        """Position in :attr:`nodes` of every node id (``-1`` off the boundary)."""
        if self._local is None:
            self._local = np.full(len(self.x), -1, np.int64)
            self._local[self.nodes] = np.arange(len(self.nodes))
        return self._local


class _RowBuilder:
    """The candidate rows of every finger in one configuration (module notes); the search
    radius only filters them."""

    def __init__(self, bd: BoundaryModel, x: np.ndarray, fingers: Sequence[Finger], rule: RowRule, axes: Any,
                 x_ref: np.ndarray | None, normals_ref: np.ndarray | None, feet_ref: np.ndarray | None):
        if not isinstance(rule, RowRule):
            raise DeformClosureError(f"rule: expected a RowRule, got {type(rule).__name__}")
        self.geo = _EdgeGeometry(bd, np.asarray(x, float), x_ref, normals_ref, feet_ref)
        self.fingers = list(fingers)
        self.rule = rule
        self.axes = None if axes is None else np.asarray(axes, float).reshape(len(self.fingers), 2)
        if rule.disc == "pad" and self.axes is None and any(f.round_centre() is not None for f in self.fingers):
            raise DeformClosureError("rule.disc = 'pad': give the discs' pressing axes (axes=)")

    def rows(self, radius: float) -> ContactRows:
        parts: list[ContactRows] = []
        for fi, f in enumerate(self.fingers):
            parts += self._finger(fi, f, radius, False)[0]
        return ContactRows.concat(parts)

    def reach(self) -> Reach:
        out = np.array([self._finger(fi, f, -np.inf, True)[1:] for fi, f in enumerate(self.fingers)]).reshape(-1, 2)
        return Reach(np.maximum(out[:, 0], 0.0), np.maximum(out[:, 1], 0.0))

    def _finger(self, fi: int, f: Finger, radius: float, reach: bool) -> tuple[list[ContactRows], float, float]:
        """Rows of finger ``fi`` with a gap below ``radius``; with ``reach`` also its
        penetration and depth (else ``-inf``)."""
        geo, rule = self.geo, self.rule
        rc = f.round_centre()
        pad = rc is not None and rule.disc == "pad"
        counts = rule.disc_depth or rc is None      # the finger's depth counts
        out: list[ContactRows] = []
        pen = depth = -np.inf
        anyin = False
        sd = np.zeros(0)
        if f.has_interior:
            sd, dirn = _pad_gaps(geo, f, rc, self.axes[fi]) if pad else (f.signed_distance(geo.xn), None)
            anyin = bool(np.any(sd < 0))
            pen = float(np.max(-sd, initial=-np.inf))
            depth = pen if counts else depth
            out += _body_rows(geo, fi, f, sd, dirn, radius)
        if pad or rule.inside_corner == "least_deep":
            corners = [(c, 0.0, k) for k, c in enumerate(np.asarray(f.vertices, float))]
            if pad:                  # the centre presses like a corner with offset r
                corners.append((np.asarray(rc[0], float), float(rc[1]), 0))
            for w, off, k in corners:
                rows, p, d = _corner_least_deep(geo, fi, f, k, w, off, radius, rule.cone, centre=off > 0,
                                                anyin=anyin, node_sd=sd)
                out += rows
                pen = max(pen, p)
                depth = max(depth, d) if counts else depth
        elif len(f.vertices):
            out += _corner_rows_nearest(geo, fi, f, radius, rule.cone)
            if reach:
                corners = np.asarray(f.vertices, float)
                for w, ins in zip(corners, geo.bd.inside(geo.x, corners)):
                    if ins:
                        d = float(segment_distance(geo.a, geo.b, w).min(initial=np.inf))
                        pen = max(pen, d)
                        depth = max(depth, d) if counts else depth
        if rc is not None and not pad:
            rows, p = _round_rows(geo, fi, f, radius)
            out += rows
            pen = max(pen, p)
        return out, pen, depth


def _pad_gaps(geo: _EdgeGeometry, f: Finger, rc: tuple[np.ndarray, float], axis: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Gap and direction of boundary nodes against a disc that presses like a round pad
    along ``axis`` (module notes, ``disc = "pad"``): ``(B,)`` gaps (``inf`` beyond the
    reach) and ``(B, 2)`` unit directions."""
    P, n = geo.xn, geo.node_inward
    c, r = np.asarray(rc[0], float), float(rc[1])
    shape = Capsule(0.0, r)
    a = np.asarray(axis, float)
    perp = np.array([-a[1], a[0]])
    d = P - c
    s = d @ a                                  # along the axis, from the centre
    xc = d @ perp                              # across it
    front = s >= -r
    sd = f.signed_distance(P)                  # behind the disc: the radial distance
    dirn = f.outward_normal(P)
    back = ~front & (n @ a > -_HALF_SQRT2 * np.hypot(n[:, 0], n[:, 1]))
    if np.any(back):
        # the disc's back at the node's cross coordinate (at most the reach) inside the part
        xb = np.clip(xc[back], -shape.reach, shape.reach)
        depth_b, _ = shape.profile(xb, capped=False)
        pb = c + (-(r - depth_b))[:, None] * a + xb[:, None] * perp
        buried = np.zeros(len(P), bool)
        buried[np.flatnonzero(back)] = geo.bd.inside(geo.x, pb)
        front = front | buried
    idx = np.flatnonzero(front)
    if len(idx):
        h, slope = shape.profile(xc[idx])
        fin = np.isfinite(h)
        k = np.hypot(1.0, np.where(fin, slope, 0.0))
        # the surface at cross coordinate x lies r − h(x) ahead of the centre; the gap
        # along the axis scaled to a unit gradient, the disc's normal there
        sd[idx] = np.where(fin, (s[idx] - (r - np.where(fin, h, 0.0))) / k, np.inf)
        dirn[idx] = np.where(fin[:, None], (a + np.where(fin, slope, 0.0)[:, None] * perp) / k[:, None], a)
    return sd, dirn


def _body_rows(geo: _EdgeGeometry, fi: int, f: Finger, sd: np.ndarray, dirn: np.ndarray | None,
               radius: float) -> list[ContactRows]:
    """Boundary nodes against the finger body: every node with a gap ``sd`` below
    ``radius``, however deep (directions ``dirn``, else the body's outward normal)."""
    sel = sd < radius
    if not np.any(sel):
        return []
    v = geo.nodes[sel]
    if dirn is None:
        d = f.outward_normal(geo.rest_or_current(v, geo.xn[sel]))
    elif geo.x_ref is None:
        d = dirn[sel]
    else:
        raise DeformClosureError("rule.disc = 'pad': the rows are built at rest; give no x_ref")
    return [_rows(fi, NODE_BODY, -1, v, np.stack([v, v], 1), np.c_[np.ones(len(v)), np.zeros(len(v))], d,
                  sd[sel], geo.xn[sel])]


def _corner_rows_nearest(geo: _EdgeGeometry, fi: int, f: Finger, radius: float, cone: str) -> list[ContactRows]:
    """Finger corners against boundary edges, and against vertices whose normal cone
    holds them (``inside_corner = "nearest"``)."""
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
    # corners in the normal cone of a vertex (beyond both adjacent edges)
    e_next = bd.edge_of[nodes]
    e_prev = bd.edge_of[bd.prev[nodes]]
    beyond = (s_sel[:, e_next] < 0) & (s_sel[:, e_prev] > 1) & ~inside[:, None]
    if cone == "convex":
        beyond &= (bd.feature[nodes] == CONVEX)[None]
    dist = np.linalg.norm(corners[:, None, :] - xn[None], axis=-1)
    kk, vv = np.nonzero(beyond & (dist < radius) & (dist > 0))
    if len(kk):
        ref = geo.rest_or_current(nodes[vv], xn[vv])
        dirn = ref - corners[kk]
        dirn = dirn / np.linalg.norm(dirn, axis=1, keepdims=True)
        out.append(_rows(fi, CORNER_NODE, kk, nodes[vv], np.stack([nodes[vv], nodes[vv]], 1),
                         np.c_[np.ones(len(vv)), np.zeros(len(vv))], dirn, dist[kk, vv], xn[vv]))
    return out


def _edge_rows(geo: _EdgeGeometry, fi: int, kind: int, corner: int, ee: np.ndarray, s: np.ndarray,
               gap: np.ndarray) -> ContactRows:
    """Rows on edges ``ee`` at foot parameters ``s``: force along their inward normal,
    shared by their end nodes."""
    return _rows(fi, kind, corner, ee, geo.edges[ee], np.c_[1 - s, s], geo.n_dir[ee], gap,
                 geo.a[ee] + s[:, None] * geo.ab[ee])


def _node_rows(geo: _EdgeGeometry, fi: int, corner: int, j: np.ndarray, dirn: np.ndarray,
               gap: np.ndarray) -> ContactRows:
    """``CORNER_NODE`` rows on the boundary nodes at positions ``j`` of ``geo.nodes``."""
    v = geo.nodes[j]
    return _rows(fi, CORNER_NODE, corner, v, np.stack([v, v], 1), np.c_[np.ones(len(v)), np.zeros(len(v))], dirn,
                 gap, geo.xn[j])


def _corner_least_deep(geo: _EdgeGeometry, fi: int, f: Finger, k: int, w: np.ndarray, off: float,
                       radius: float, cone: str, *, centre: bool, anyin: bool,
                       node_sd: np.ndarray | None) -> tuple[list[ContactRows], float, float]:
    """Corner ``k`` at ``w`` (or a disc's centre, offset ``off`` = its radius) under
    ``inside_corner = "least_deep"``, the pad rule of discs. Returns the rows, the
    penetration and the depth (``-inf`` when none)."""
    if geo.x_ref is not None:
        raise DeformClosureError("rule.inside_corner = 'least_deep': the rows are built at rest; give no x_ref")
    bd = geo.bd
    inside = bool(bd.inside(geo.x, w[None])[0])
    dmin = float(segment_distance(geo.a, geo.b, w).min(initial=np.inf))
    pen = depth = -np.inf
    rel = w - geo.a
    s = np.einsum("ej,ej->e", rel, geo.ab) / geo.ell2
    gl = -np.einsum("ej,ej->e", rel, geo.n_in)
    if inside:
        pen = depth = dmin + off
    elif centre:
        if anyin:                 # once a node is inside, the node rows see the disc
            return [], pen, depth
        # a straight edge may cut the disc between two nodes outside it
        loc = geo.local
        ends_out = (node_sd[loc[geo.edges[:, 0]]] > 0) & (node_sd[loc[geo.edges[:, 1]]] > 0)
        cand = (s > 0) & (s < 1) & (gl >= 0) & ends_out
        gap = gl - off
        pen = float(np.max(-gap[cand], initial=-np.inf))
        ee = np.flatnonzero(cand & (gap < radius))
        return ([_edge_rows(geo, fi, DISC_EDGE, -1, ee, s[ee], gap[ee])] if len(ee) else []), pen, depth
    if centre and anyin:
        return [], pen, depth
    out: list[ContactRows] = []
    got = False
    if inside:
        best = _least_deep_edge(geo, f, s, gl, off, dmin)
        if best >= 0:
            out.append(_edge_rows(geo, fi, CENTRE_EDGE if centre else CORNER_EDGE, k, np.array([best]),
                                  s[[best]], gl[[best]] - off))
        got = best >= 0
    else:
        ee = np.flatnonzero((s >= 0) & (s <= 1) & (gl >= -1e-12 * np.sqrt(geo.ell2)) & (gl < radius))
        if len(ee):
            out.append(_edge_rows(geo, fi, CORNER_EDGE, k, ee, s[ee], gl[ee]))
    # vertices: inside, the nearest one when no edge row presses; outside, the cones
    r = geo.xn - w
    d = np.hypot(r[:, 0], r[:, 1])
    pos = d > 0
    if inside:
        j = np.flatnonzero(pos & (d <= dmin * (1 + 1e-9) + 1e-12 * d)) if not got else np.zeros(0, np.int64)
        if len(j):
            out.append(_node_rows(geo, fi, k, j, -r[j] / d[j, None], -d[j] - off))
    else:
        e1, e0 = bd.edge_of[geo.nodes], bd.edge_of[bd.prev[geo.nodes]]
        cone_ok = (bd.feature[geo.nodes] == CONVEX) if cone == "convex" else np.ones(len(d), bool)
        j = np.flatnonzero(pos & cone_ok & (d < radius) & (s[e1] < 0) & (s[e0] > 1))
        if len(j):
            out.append(_node_rows(geo, fi, k, j, r[j] / d[j, None], d[j]))
    return out, pen, depth


def _least_deep_edge(geo: _EdgeGeometry, f: Finger, s: np.ndarray, gl: np.ndarray, off: float,
                     dmin: float) -> int:
    """Among the edges within twice ``dmin`` of a point inside the part (foot on the edge,
    the point on their inner side) the one the finger crosses least deeply — for a
    polygon the depth of the whole polygon past the edge's line — ties to the edge whose
    line is nearer; ``-1`` when there is none. The point on an edge up to round-off counts
    as on its inner side."""
    # a corner on the boundary up to round-off (``dmin`` ~ 0: inside or not by a bit)
    # still presses the edges through it
    eps = 1e-12 * np.sqrt(geo.ell2)
    cand = np.flatnonzero((s >= 0) & (s <= 1) & (gl < eps) & (-gl <= 2.0 * dmin + eps))
    if not len(cand):
        return -1
    dep = -gl[cand] + off
    verts = np.asarray(f.vertices, float)
    if len(verts) > 1:      # a polygon: its deepest corner past the edge's line
        past = np.einsum("kej,ej->ke", verts[:, None, :] - geo.a[cand][None], geo.n_in[cand])
        dep = np.maximum(dep, past.max(axis=0))
    best, bdep, bgl = -1, np.inf, 0.0
    for e, de in zip(cand, dep):    # few candidates; the tie rule is sequential
        if de < bdep * (1 - 1e-12) or (de <= bdep * (1 + 1e-12) and gl[e] > bgl):
            best, bdep, bgl = int(e), float(de), float(gl[e])
    return best


def _round_rows(geo: _EdgeGeometry, fi: int, f: Finger, radius: float) -> tuple[list[ContactRows], float]:
    """A circular finger boundary against boundary edges whose foot point it faces
    (``disc = "radial"``); also the deepest cut of such an edge into the disc."""
    c, r = f.round_centre()
    a, ab = geo.a, geo.ab
    rel = c - a
    s = np.einsum("ej,ej->e", rel, ab) / geo.ell2
    s_ref = np.einsum("ej,ej->e", c - geo.a_ref, geo.ab_ref) / geo.ell2_ref
    s_w = np.clip(s_ref, 0, 1)
    gl = -np.einsum("ej,ej->e", rel, geo.n_in)
    gap = gl - r
    inner = (s > 0) & (s < 1) if geo.x_ref is None else (s_ref > 0) & (s_ref < 1)
    faces = inner & (gl >= 0)
    pen = float(np.max(-gap[faces], initial=-np.inf))
    ee = np.flatnonzero(faces & (np.abs(gap) < radius))
    if not len(ee):
        return [], pen
    ss = s_w[ee]
    return [_rows(fi, DISC_EDGE, -1, ee, geo.edges[ee], np.c_[1 - ss, ss], geo.n_dir[ee], gap[ee],
                  a[ee] + ss[:, None] * ab[ee])], pen


def refresh_rows(rows: ContactRows, bd: BoundaryModel, x: np.ndarray, fingers: Sequence[Finger]) -> ContactRows:
    """Re-measure the gaps and contact points of existing rows of :data:`EQUILIBRIUM_RULE`
    in configuration ``x`` (directions and weights are kept)."""
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
            else:                                   # DISC_EDGE, CENTRE_EDGE: the circular boundary
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


def finger_gaps(bd: BoundaryModel, x: np.ndarray, fingers: Sequence[Finger], *,
                rule: RowRule = EQUILIBRIUM_RULE, axes: Any = None) -> np.ndarray:
    """Smallest contact gap (m) of every finger in configuration ``x``; negative when
    the finger penetrates the part (``inf`` when no condition is within reach)."""
    L = float(np.ptp(x[bd.nodes], axis=0).max())
    rows = contact_rows(bd, x, fingers, radius=10.0 * L, rule=rule, axes=axes)
    out = np.full(len(fingers), np.inf)
    np.minimum.at(out, rows.finger, rows.gap)
    return out
