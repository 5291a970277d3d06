"""Contact graph of two-jaw grasps (SPEC §4; paper §4.3–4.4).

Hand-made shapes where the slide and swing edges are known in closed form, symmetry
(mirror, rotation, relabelling), and a slow independent reference for the swing rule
that intersects a finely sampled arc with the boundary using shapely.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Point, Polygon

from deformclosure.errors import GraspError
from deformclosure.grasp.contact_graph import (
    SLIDE,
    SWING,
    ContactGraph,
    contact_graph,
    part_diameter,
    pulling_pairs,
    swing_targets,
)

# --------------------------------------------------------------------------- shapes


def subdivide(corners: list[tuple[float, float]], counts: list[int] | int) -> np.ndarray:
    """Nodes along a closed polygon, edge i split into counts[i] equal parts."""
    corners_a = np.asarray(corners, dtype=float)
    k = len(corners_a)
    counts = [counts] * k if isinstance(counts, int) else counts
    pts = []
    for i in range(k):
        p, q = corners_a[i], corners_a[(i + 1) % k]
        for t in np.arange(counts[i]) / counts[i]:
            pts.append(p + t * (q - p))
    return np.array(pts)


def node_of(X: np.ndarray, xy: tuple[float, float]) -> int:
    d = np.hypot(*(X - np.asarray(xy)).T)
    i = int(np.argmin(d))
    assert d[i] < 1e-12
    return i


def c_shape() -> np.ndarray:
    """A C (mouth opening to +x between y = 1 and 2), unit spacing, CCW."""
    return subdivide([(0, 0), (3, 0), (3, 1), (1, 1), (1, 2), (3, 2), (3, 3), (0, 3)],
                     [3, 1, 2, 1, 2, 1, 3, 3])


def star(rng: np.random.Generator, n: int, r0: float, r1: float) -> np.ndarray:
    th = 2 * np.pi * (np.arange(n) + rng.uniform(-0.3, 0.3, n)) / n
    r = rng.uniform(r0, r1, n)
    return np.c_[r * np.cos(th), r * np.sin(th)]


def random_part(seed: int, hole: bool) -> tuple[np.ndarray, list[np.ndarray]]:
    rng = np.random.default_rng(seed)
    outer = star(rng, int(rng.integers(7, 11)), 0.7, 1.5)
    loops = [np.arange(len(outer))]
    X = outer
    if hole:
        h = star(rng, int(rng.integers(3, 6)), 0.15, 0.4)[::-1] + rng.uniform(-0.1, 0.1, 2)
        loops.append(len(X) + np.arange(len(h)))
        X = np.concatenate([X, h])
    poly = Polygon(X[loops[0]], [X[lp] for lp in loops[1:]])
    assert poly.is_valid
    return X, loops


def edge_dict(g: ContactGraph, relabel: np.ndarray | None = None) -> dict:
    """Edges in node terms: {frozenset({pair_u, pair_v}): kinds}."""
    out = {}
    for (u, v), k in zip(g.edges, g.kinds):
        pu, pv = g.pairs[u], g.pairs[v]
        if relabel is not None:
            pu, pv = relabel[pu], relabel[pv]
        out[frozenset((frozenset(pu.tolist()), frozenset(pv.tolist())))] = int(k)
    return out


def edges_of_kind(g: ContactGraph, bit: int) -> set:
    return {k for k, v in edge_dict(g).items() if v & bit}


def E(a: int, b: int, c: int) -> frozenset:
    """The edge {a, b} -- {a, c} in node terms."""
    return frozenset((frozenset((a, b)), frozenset((a, c))))


def brute_slide(loops: list[np.ndarray], vertex_loops: tuple[int, ...]) -> set:
    vnodes = sorted(int(x) for i in vertex_loops for x in loops[i])
    out = set()
    for i in vertex_loops:
        lp = [int(x) for x in loops[i]]
        for j, b in enumerate(lp):
            for c in (lp[j - 1], lp[(j + 1) % len(lp)]):
                for a in vnodes:
                    if a not in (b, c):
                        out.add(E(a, b, c))
    return out


def reference_swing(X: np.ndarray, loops: list[np.ndarray], vertex_loops: tuple[int, ...],
                    samples: int = 20000) -> tuple[set, int]:
    """Swing edges by sampling each arc as a fine polyline and intersecting with shapely.

    The direction test probes a point a tiny arc length after b; the first meeting is
    the intersection point closest to the arc's start (``line_locate_point``). Arcs whose
    first meeting is near a node are counted as ambiguous and not used.
    """
    poly = Polygon(X[loops[0]], [X[lp] for lp in loops[1:]])
    segs = [(int(p), int(q)) for lp in loops for p, q in zip(lp, np.roll(lp, -1))]
    lines = shapely.linestrings([X[[p, q]] for p, q in segs])
    bnd = shapely.union_all(lines)
    diam = part_diameter(X, loops)
    vn = sorted(int(x) for i in vertex_loops for x in loops[i])
    vset = set(vn)
    out, ambiguous = set(), 0
    for a in vn:
        for b in vn:
            if a == b:
                continue
            v = X[b] - X[a]
            r = float(np.hypot(*v))
            th0 = np.arctan2(v[1], v[0])
            delta = 1e-6 * diam / r
            for sgn in (1.0, -1.0):
                probe = X[a] + r * np.array([np.cos(th0 + sgn * delta),
                                             np.sin(th0 + sgn * delta)])
                if poly.contains(Point(probe)):
                    continue  # first motion enters the part
                t = th0 + sgn * np.linspace(delta, 2 * np.pi - delta, samples)
                arc = LineString(X[a] + r * np.c_[np.cos(t), np.sin(t)])
                pts = shapely.get_coordinates(arc.intersection(bnd))
                if len(pts) == 0:
                    continue
                pos = shapely.line_locate_point(arc, shapely.points(pts))
                hit = pts[np.argmin(pos)]
                if np.min(np.hypot(*(X - hit).T)) < 1e-5 * diam:
                    ambiguous += 1
                    continue
                dist = shapely.distance(lines, Point(hit))
                for j in np.flatnonzero(dist < 1e-6 * diam):
                    for c in segs[j]:
                        if c in vset and c not in (a, b):
                            out.add(E(a, b, c))
    return out, ambiguous


# --------------------------------------------------------------------------- basics


def test_square_vertices_slide_and_swing() -> None:
    sq = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    g = contact_graph(sq, [np.arange(4)])
    assert g.pairs.tolist() == [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]
    assert g.pairs.dtype == np.int64 and g.kinds.dtype == np.uint8
    assert np.all(g.edges[:, 0] < g.edges[:, 1])
    assert np.array_equal(g.edges, np.unique(g.edges, axis=0))
    assert edges_of_kind(g, SLIDE) == brute_slide([np.arange(4)], (0,))
    # Pivot 0, jaw at 1: CCW enters (the arc bends into the square along edge 1-2);
    # CW goes around the outside and arrives exactly at node 3 (node rule: 3 and its
    # neighbour 2; 0 is the pivot).
    t = swing_targets(sq, [np.arange(4)], 0, 1)
    assert t["ccw"] is None and t["cw"].tolist() == [2, 3]
    # The diagonal's far corner is the farthest point: the circle meets the square only
    # at the start, so neither exterior direction gives a target.
    t = swing_targets(sq, [np.arange(4)], 0, 2)
    assert t["ccw"].size == 0 and t["cw"].size == 0
    assert E(0, 1, 3) in edges_of_kind(g, SWING)
    assert g.vertex_index(3, 1) == g.vertex_index(1, 3) == 4
    assert g.neighbours(4).tolist() == sorted(g.neighbours(4).tolist())


def test_csr_is_symmetric_adjacency_of_edges() -> None:
    X, loops = random_part(3, hole=True)
    g = contact_graph(X, loops, (0, 1))
    V = g.n_vertices
    assert V == len(X) * (len(X) - 1) // 2
    rows = np.repeat(np.arange(V), np.diff(g.indptr))
    got = {(int(u), int(v)) for u, v in zip(rows, g.indices)}
    want = {(int(u), int(v)) for u, v in g.edges} | {(int(v), int(u)) for u, v in g.edges}
    assert got == want
    assert g.degrees().sum() == 2 * g.n_edges


def test_slide_edges_polygon_with_hole() -> None:
    outer = subdivide([(0, 0), (4, 0), (4, 3), (0, 3)], [2, 2, 2, 2])
    hole = np.array([[1.0, 1.0], [1.0, 2.0], [3.0, 2.0], [3.0, 1.0]])  # clockwise
    X = np.concatenate([outer, hole]) * 1e-2
    loops = [np.arange(8), 8 + np.arange(4)]
    gc = contact_graph(X, loops)  # contracting: outer nodes only
    assert gc.n_vertices == 28 and gc.vertex_nodes.tolist() == list(range(8))
    assert edges_of_kind(gc, SLIDE) == brute_slide(loops, (0,))
    ge = contact_graph(X, loops, vertex_loops=(0, 1))  # expanding: all loops
    assert ge.n_vertices == 66
    assert edges_of_kind(ge, SLIDE) == brute_slide(loops, (0, 1))
    # Expanding jaw on the hole corner (1,1) = 8, part rotating about the hole corner
    # (3,1) = 11, radius 2. CCW the jaw would move down into the part. CW it starts up
    # along the hole's edge 8-9 (tangent along an edge), bends right into the hole and
    # meets the hole's top edge y = 2 at x = 3 - sqrt(3), between hole nodes 9 and 10.
    t = swing_targets(X, loops, 11, 8, vertex_loops=(0, 1))
    assert t["ccw"] is None
    assert t["cw"].tolist() == [9, 10]
    assert E(11, 8, 9) in edges_of_kind(ge, SWING)


# --------------------------------------------------------------------------- swing


def test_c_shape_mouth_swing() -> None:
    X = c_shape() * 0.01  # metres
    loops = [np.arange(len(X))]
    a = node_of(X, (0.01, 0.01))  # inner corner
    b = node_of(X, (0.03, 0.01))  # tip of the lower prong
    t = swing_targets(X, loops, a, b)
    # Downwards (CW) the arc enters the lower prong; upwards it crosses the mouth and
    # lands on the upper prong's lower face y = 2 at x = 1 + sqrt(3) = 2.73.
    assert t["cw"] is None
    land = {node_of(X, (0.02, 0.02)), node_of(X, (0.03, 0.02))}
    assert set(t["ccw"].tolist()) == land
    g = contact_graph(X, loops)
    sw = edges_of_kind(g, SWING)
    for c in land:
        assert E(a, b, c) in sw
    # Jaw at the upper prong's tip (3,2), part rotating about the corner (3,0), radius 2.
    # CCW the jaw starts along the prong's lower face (tangent along an edge), bends down
    # into the mouth and lands on the lower prong's top face y = 1 at x = 3 - sqrt(3).
    # CW it heads out to +x, round below the part and up to the node (1,0) on the
    # bottom face (node rule: (1,0) and its neighbours (0,0), (2,0)).
    a2 = node_of(X, (0.03, 0.0))
    b2 = node_of(X, (0.03, 0.02))
    t2 = swing_targets(X, loops, a2, b2)
    assert set(t2["ccw"].tolist()) == {node_of(X, (0.01, 0.01)), node_of(X, (0.02, 0.01))}
    assert set(t2["cw"].tolist()) == {node_of(X, (x, 0.0)) for x in (0.0, 0.01, 0.02)}


def test_convex_rectangle_one_direction_and_node_hit() -> None:
    X = subdivide([(0, 0), (4, 0), (4, 2), (0, 2)], [4, 2, 4, 2]) * 1e-3
    loops = [np.arange(12)]
    a, b = node_of(X, (0, 0)), node_of(X, (0.002, 0))
    t = swing_targets(X, loops, a, b)
    # Straight boundary at b: upwards enters; downwards circles round and meets the part
    # exactly at the corner (0, 2): that node and both its neighbours (node rule).
    assert t["ccw"] is None
    want = {node_of(X, (0, 0.002)), node_of(X, (0.001, 0.002)), node_of(X, (0, 0.001))}
    assert set(t["cw"].tolist()) == want
    # Tangent along a boundary edge at the start (b a corner): the CCW arc bends into
    # the part (curvature towards the pivot) and is skipped; CW comes round and first
    # meets the top edge y = 2 from above at x = sqrt(12).
    b2 = node_of(X, (0.004, 0))
    t2 = swing_targets(X, loops, a, b2)
    assert t2["ccw"] is None
    assert set(t2["cw"].tolist()) == {node_of(X, (0.003, 0.002)), node_of(X, (0.004, 0.002))}


@pytest.mark.parametrize("offset", [0.0, 3e-10, -3e-10])
def test_tangential_touch(offset: float) -> None:
    """An arc touching an edge tangentially (within tol) stops there: both end nodes."""
    # C-shape: lower prong top face nodes at x = 3, 2.5, 2, 1.5, 1; upper prong bottom
    # face nodes at 1, 2, 3 only. Pivot (1.5, 1), jaw (2.5, 1), radius 1: the arc rises
    # and touches y = 2 at (1.5, 2), inside the edge (1,2)-(2,2).
    c = [(0, 0), (3, 0), (3, 1), (1, 1), (1, 2 + offset), (3, 2 + offset), (3, 3), (0, 3)]
    X = subdivide(c, [3, 1, 4, 1, 2, 1, 3, 3])
    loops = [np.arange(len(X))]
    a, b = node_of(X, (1.5, 1)), node_of(X, (2.5, 1))
    t = swing_targets(X, loops, a, b)
    assert t["cw"] is None
    assert set(t["ccw"].tolist()) == {node_of(X, (1, 2 + offset)), node_of(X, (2, 2 + offset))}


def test_tangential_touch_beyond_tol_is_not_a_touch() -> None:
    c = [(0, 0), (3, 0), (3, 1), (1, 1), (1, 2.001), (3, 2.001), (3, 3), (0, 3)]
    X = subdivide(c, [3, 1, 4, 1, 2, 1, 3, 3])
    a, b = node_of(X, (1.5, 1)), node_of(X, (2.5, 1))
    t = swing_targets(X, [np.arange(len(X))], a, b)
    # passes under the face and hits the spine x = 1 between (1,1) = pivot's neighbour
    # and (1, 2.001)
    assert set(t["ccw"].tolist()) == {node_of(X, (1, 1)), node_of(X, (1, 2.001))}


@pytest.mark.parametrize("N", [12, 16])
def test_regular_polygon_arcs_through_nodes(N: int) -> None:
    th = 2 * np.pi * np.arange(N) / N
    X = 0.05 * np.c_[np.cos(th), np.sin(th)]
    loops = [np.arange(N)]
    for j in range(1, N):
        t = swing_targets(X, loops, 0, j)
        if j == N // 2:  # farthest node: the circle meets the polygon only at b
            assert t["ccw"].size == 0 and t["cw"].size == 0
            continue
        assert (t["ccw"] is None) != (t["cw"] is None)
        got = t["cw"] if t["ccw"] is None else t["ccw"]
        # the exterior arc lands exactly on node -j: it and both its neighbours
        want = {(N - j - 1) % N, (N - j) % N, (N - j + 1) % N} - {0, j}
        assert set(got.tolist()) == want, j
    # cyclic symmetry: relabel i -> i + 1 (coordinates recomputed, not exactly equal)
    g = contact_graph(X, loops)
    shift = (np.arange(N) + 1) % N
    X2 = X[np.argsort(shift)]
    assert edge_dict(g, shift) == edge_dict(contact_graph(X2, loops))


def _mirror_relabel(X: np.ndarray, loops: list[np.ndarray], seed: int
                    ) -> tuple[np.ndarray, list[np.ndarray], np.ndarray]:
    perm = np.random.default_rng(seed).permutation(len(X))
    Xm = np.empty_like(X)
    Xm[perm] = X * np.array([-1.0, 1.0])
    return Xm, [perm[lp[::-1]] for lp in loops], perm


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_mirror_rotation_relabel_invariance(seed: int) -> None:
    X, loops = random_part(seed, hole=seed != 1)
    vl = tuple(range(len(loops)))
    g = edge_dict(contact_graph(X, loops, vl))
    # mirror image with shuffled node ids: same graph after relabelling
    Xm, lm, perm = _mirror_relabel(X, loops, seed)
    gm = contact_graph(Xm, lm, vl)
    assert edge_dict(contact_graph(X, loops, vl), perm) == edge_dict(gm)
    # rotated, translated, scaled to millimetres
    c, s = np.cos(0.7), np.sin(0.7)
    Xr = 1e-3 * (X @ np.array([[c, s], [-s, c]]) + [3.0, -2.0])
    assert edge_dict(contact_graph(Xr, loops, vl)) == g
    assert sum(1 for k in g.values() if k & SWING) > 20


@pytest.mark.parametrize("shape", ["rect", "c", "polygon12"])
def test_exact_symmetries_of_degenerate_shapes(shape: str) -> None:
    """Mirror and quarter turn of shapes full of exact node hits and tangencies."""
    if shape == "rect":
        X = subdivide([(0, 0), (4, 0), (4, 2), (0, 2)], [4, 2, 4, 2])
    elif shape == "c":
        X = c_shape()
    else:
        th = 2 * np.pi * np.arange(12) / 12
        X = np.c_[np.cos(th), np.sin(th)]
    loops = [np.arange(len(X))]
    g = contact_graph(X, loops)
    Xm, lm, perm = _mirror_relabel(X, loops, 5)
    assert edge_dict(g, perm) == edge_dict(contact_graph(Xm, lm))
    Xq = X @ np.array([[0.0, 1.0], [-1.0, 0.0]])
    assert edge_dict(contact_graph(Xq, loops)) == edge_dict(g)


@pytest.mark.parametrize("seed, hole", [(10, False), (11, False), (12, True), (13, True)])
def test_swing_edges_against_shapely_reference(seed: int, hole: bool) -> None:
    X, loops = random_part(seed, hole)
    vl = tuple(range(len(loops))) if hole else (0,)
    ref, ambiguous = reference_swing(X, loops, vl)
    assert ambiguous == 0
    got = edges_of_kind(contact_graph(X, loops, vl), SWING)
    assert got == ref
    assert len(ref) > 10


def test_large_perimeter_graph() -> None:
    p = 480
    th = np.linspace(0, 2 * np.pi, p, endpoint=False)
    rad = 1 + 0.3 * np.sin(3 * th) + 0.15 * np.cos(7 * th + 1)
    X = 0.05 * np.c_[rad * np.cos(th), rad * np.sin(th)]
    g = contact_graph(X, [np.arange(p)])
    assert g.n_vertices == p * (p - 1) // 2
    assert g.degrees().min() >= 2
    assert np.any(g.kinds == SWING) and np.any(g.kinds == SLIDE | SWING)


# --------------------------------------------------------------------------- exports


def test_to_dict_format() -> None:
    sq = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]) * 0.01
    g = contact_graph(sq, [np.arange(4)])
    s0 = np.hypot(*(sq[g.pairs[:, 0]] - sq[g.pairs[:, 1]]).T)
    k = np.full(g.n_vertices, 250.0)
    k[1] = np.inf
    d = g.to_dict(s0, k, pulls=np.zeros(g.n_vertices, bool))
    json.dumps(d)  # JSON-serialisable, no infinities
    assert d["vertices"][0] == {"a": 0, "b": 1, "sigma0": 0.01, "k": 250.0, "pulls": False}
    assert d["vertices"][1]["k"] is None
    assert len(d["edges"]) == g.n_edges
    for e in d["edges"]:
        assert e["u"][0] == e["v"][0]  # shared (fixed) jaw first
        assert set(e["kinds"]) <= {"slide", "swing"} and e["kinds"]
    kinds = {(tuple(e["u"]), tuple(e["v"])): e["kinds"] for e in d["edges"]}
    assert kinds[((0, 1), (0, 3))] == ["swing"]
    assert kinds[((0, 1), (0, 2))] == ["slide", "swing"]
    with pytest.raises(GraspError, match="sigma0 must have one value per vertex"):
        g.to_dict(s0[:-1], k)


def test_pulling_pairs() -> None:
    X = subdivide([(0, 0), (3, 0), (3, 1), (1, 1), (1, 2), (3, 2), (3, 3), (0, 3)], 1)
    loops = [np.arange(8)]
    # (3,1)-(3,3), (0,0)-(3,3), (0,0)-(3,0), (3,1)-(3,2)
    pairs = np.array([[2, 6], [0, 6], [0, 1], [2, 5]])
    # (3,1)->(3,3) leaves the lower prong upwards into the mouth: the jaw would pull.
    # (0,0)-(3,3) points into the part at both ends; (0,0)-(3,0) runs along an edge;
    # (3,2) pushed towards (3,1) is pushed down, out of the upper prong: pull.
    assert pulling_pairs(X, loops, pairs).tolist() == [True, False, False, True]
    # Expanding jaws push away from each other: (0,0) pushed away from (3,0) or (3,3)
    # would need a pull; (3,1)-(3,2) push along the edges at both ends.
    assert pulling_pairs(X, loops, pairs, expanding=True).tolist() == [True, True, True,
                                                                         False]


# --------------------------------------------------------------------------- errors


def test_vertex_index_errors() -> None:
    sq = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.5]])
    g = contact_graph(sq, [np.arange(4)])
    with pytest.raises(GraspError, match=r"\(1, 1\) are not a vertex"):
        g.vertex_index(1, 1)
    with pytest.raises(GraspError, match="not a vertex"):
        g.vertex_index(0, 4)  # interior node
    with pytest.raises(GraspError, match="not a vertex"):
        g.vertex_index(0, 99)
    with pytest.raises(GraspError, match="out of range"):
        g.neighbours(6)


@pytest.mark.parametrize("nodes, loops, kw, msg", [
    (np.zeros((4, 3)), [np.arange(4)], {}, r"shape \(n, 2\)"),
    ([[0, 0], [1, 0], [1, np.nan], [0, 1]], [np.arange(4)], {}, "NaN"),
    ([[0, 0], [1, 0], [1, 1], [0, 1]], [np.arange(4)[::-1]], {}, "counter-clockwise"),
    ([[0, 0], [1, 0], [1, 1], [0, 1]], [np.arange(5)], {}, "outside"),
    ([[0, 0], [1, 0], [1, 1], [0, 1]], [np.array([0, 1])], {}, ">= 3"),
    ([[0, 0], [1, 0], [1, 1], [0, 1]], [np.array([0, 1, 2, 3, 1])], {}, "more than once"),
    ([[0, 0], [1, 0], [1, 1], [0, 1]], [np.arange(4)], {"tol": -1.0}, "tol"),
    ([[0, 0], [1, 0], [1, 1], [0, 1]], [np.arange(4)], {"vertex_loops": (1,)},
     "vertex_loops"),
    ([[0, 0], [1, 0], [1, 0], [1, 1], [0, 1]], [np.arange(5)], {}, "zero length"),
    ([[0, 0], [1, 0], [1, 1], [0, 1]], [], {}, "no boundary loops"),
])
def test_bad_input(nodes, loops, kw, msg) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(GraspError, match=msg):
        contact_graph(np.asarray(nodes, dtype=float), loops, **kw)


def test_from_edges_validation() -> None:
    pairs = [[0, 1], [0, 2], [1, 2]]
    with pytest.raises(GraspError, match="self-loop"):
        ContactGraph.from_edges(pairs, [[1, 1]])
    with pytest.raises(GraspError, match="vertex indices"):
        ContactGraph.from_edges(pairs, [[0, 3]])
    with pytest.raises(GraspError, match="sorted"):
        ContactGraph.from_edges([[0, 2], [0, 1]], [])
    g = ContactGraph.from_edges(pairs, [[2, 0], [0, 2], [1, 0]], [SLIDE, SWING, SLIDE])
    assert g.edges.tolist() == [[0, 1], [0, 2]] and g.kinds.tolist() == [1, 3]
    with pytest.raises(ValueError):
        g.pairs[0, 0] = 5  # read-only arrays
