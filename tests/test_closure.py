"""Deform closure (paper §3.3-3.4) against an independent rigid form-closure test (Thm 1).

The library decides closure on the *twist* side (an LP over the part's velocities, then a
second-order LP) from contacts it extracts from the mesh at the contact equilibrium. The
reference here works on the *wrench* side from the construction data of each contact
set: first order = do the contact wrenches positively span R³ (origin strictly inside
their convex hull, qhull), or, when they span a plane, the plane around the origin; at
second order (normals meeting in one point ``c0``, found by intersecting the normal lines)
the Rimon-Burdick relative-curvature form: the part is held iff some equilibrium
combination ``lam >= 0`` of the wrenches has ``sum lam_i h_i > 0`` (Farkas dual of the
library's escape LP), with ``h_i`` computed here from the finger/part radii.
"""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
import shapely
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError

from deformclosure import Part, mesh_part
from deformclosure.dspace import (DiscFinger, HalfPlaneFinger, PointFinger, deform_closure,
                                  relative_curvature)
from deformclosure.dspace.closure import rigid_closure

MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 0.002, "elastic_limit_strain": 0.5}


def make_mesh(outer, points=(), divisions=40):
    outer = np.asarray(outer, float)
    area = shapely.Polygon(outer).area
    part = Part.from_dict({"name": "t", "units": "m", "outer": outer.tolist(), "material": MAT,
                           "mesh": {"max_area": area / divisions, "min_angle": 25,
                                    "points": [list(map(float, p)) for p in points]}})
    return mesh_part(part)


# ----------------------------------------------------------------------------- reference


def _rb_h(t, rf, rp):
    """Rimon-Burdick second-order coefficient, written out case by case (independent)."""
    if math.isinf(rp) and not math.isinf(rf):
        return t + rf  # finger of radius rf on a flat edge
    if math.isinf(rf) and not math.isinf(rp):
        return rp - t  # flat face on a part vertex (rp = 0)
    return (t + rf) * (rp - t) / (rp + rf)


def _strictly_inside_hull(P):
    """Is the origin strictly inside the convex hull of the rows of P (full dimension)?"""
    try:
        hull = ConvexHull(P)
    except QhullError:
        return False
    eq = hull.equations  # a . x + b <= 0 inside, |a| = 1
    return bool(np.all(eq[:, -1] < -1e-9))


def reference_closure(groups):
    """Wrench-side form closure: returns (closed, order).

    ``groups``: list of (mode, [(point, normal, rf, rp), ...]).
    """
    options = [[(p,) for p in prims] if mode == "any" else [tuple(prims)] for mode, prims in groups]
    second = []
    for choice in itertools.product(*options):
        prims = [p for g in choice for p in g]
        P = np.array([p[0] for p in prims], float)
        N = np.array([p[1] for p in prims], float)
        W = np.c_[N, P[:, 0] * N[:, 1] - P[:, 1] * N[:, 0]]  # wrenches about the origin
        rank = np.linalg.matrix_rank(W, tol=1e-9)
        if rank == 3:
            if not _strictly_inside_hull(W):
                return False, 1
            continue
        if rank <= 1:
            return False, 1
        # the wrenches span a plane: positive span of that plane?
        U, S, Vt = np.linalg.svd(W)
        basis = Vt[:2]
        if not _strictly_inside_hull(W @ basis.T):
            return False, 1
        xi0 = Vt[2]  # the only twist keeping every gap (normal of the wrench plane)
        if abs(xi0[2]) < 1e-9:
            return False, 1  # a translation slides with all gaps unchanged
        second.append((P, N, W, [p[2] for p in prims], [p[3] for p in prims]))
    if not second:
        return True, 1
    for P, N, W, rf, rp in second:
        # c0: least-squares intersection of the normal lines  (c0 - p_i) x n_i = 0
        A = np.c_[N[:, 1], -N[:, 0]]
        b = P[:, 0] * N[:, 1] - P[:, 1] * N[:, 0]
        c0 = np.linalg.lstsq(A, b, rcond=None)[0]
        h = np.array([_rb_h(float(n @ (c0 - p)), f, q) for p, n, f, q in zip(P, N, rf, rp)])
        # max sum lam h  s.t.  W^T lam = 0, sum lam = 1, lam >= 0
        k = len(h)
        res = linprog(-h, A_eq=np.vstack([W.T, np.ones(k)]), b_eq=np.r_[np.zeros(3), 1.0],
                      bounds=[(0, None)] * k, method="highs")
        assert res.status == 0
        if -res.fun <= 1e-9:
            return False, 2
    return True, 2


# ----------------------------------------------------------------------------- catalogue


def _star(rng, k):
    ang = np.sort(rng.uniform(0, 2 * np.pi, k))
    ang += np.linspace(0, 0.3, k)  # avoid near-equal angles
    rad = rng.uniform(0.55, 1.0, k)
    return np.c_[rad * np.cos(ang), rad * np.sin(ang)]


def _polygon_ok(outer):
    poly = shapely.Polygon(outer)
    if not poly.is_valid or poly.area < 0.3:
        return False
    e = np.roll(outer, -1, axis=0) - outer
    e2 = np.roll(e, -1, axis=0)
    ang = np.abs(np.arctan2(e[:, 0] * e2[:, 1] - e[:, 1] * e2[:, 0], np.einsum("ij,ij->i", e, e2)))
    return bool(np.all(ang > 0.15) and np.all(np.linalg.norm(e, axis=1) > 0.15))


def _inward(outer, i):
    e = outer[(i + 1) % len(outer)] - outer[i]
    e = e / np.linalg.norm(e)
    return np.array([-e[1], e[0]])


def _vertex_kind(outer, i):
    a, v, b = outer[i - 1], outer[i], outer[(i + 1) % len(outer)]
    cr = (v - a)[0] * (b - v)[1] - (v - a)[1] * (b - v)[0]
    return "convex" if cr > 0 else "reflex"


class Case:
    def __init__(self, name, outer, fingers, groups, points):
        self.name, self.outer, self.fingers, self.groups, self.points = name, outer, fingers, groups, points


def _edge_point(outer, i, s):
    return outer[i] + s * (outer[(i + 1) % len(outer)] - outer[i])


def _disc_ok(poly, center, r):
    return shapely.Point(center).distance(poly) >= r * (1 - 1e-9)


def build_catalogue(seed=20050101, n_random=72):
    rng = np.random.default_rng(seed)
    cases = []
    square = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
    # classic cases ----------------------------------------------------------------
    feet = [(0, 0.5), (1, 0.5), (2, 0.5), (3, 0.5)]
    pts = [_edge_point(square, i, s) for i, s in feet]
    cases.append(Case("square 4 points at midpoints (order 2, held)", square, [PointFinger(tuple(p)) for p in pts],
                      [("all", [(p, _inward(square, i), 0.0, math.inf)]) for p, (i, _) in zip(pts, feet)], pts))
    diag = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    cases.append(Case("square 4 flat faces on the corners (order 2, escapes)", square,
                      [HalfPlaneFinger(tuple(square[i]), tuple(-square[i] / np.sqrt(2))) for i in range(4)],
                      [("all", [(square[i], -square[i] / np.sqrt(2), math.inf, 0.0)]) for i in range(4)], []))
    cases.append(Case("square two jaws (slides)", square,
                      [HalfPlaneFinger((-1, 0), (1, 0)), HalfPlaneFinger((1, 0), (-1, 0))],
                      [("all", [(square[0], np.array([1.0, 0]), math.inf, 0.0), (square[3], np.array([1.0, 0]), math.inf, 0.0)]),
                       ("all", [(square[1], np.array([-1.0, 0]), math.inf, 0.0), (square[2], np.array([-1.0, 0]), math.inf, 0.0)])],
                      []))
    L = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    cases.append(Case("L with point in the concave corner + 2 points", L,
                      [PointFinger((1, 1)), PointFinger((0, 0.5)), PointFinger((0.5, 0))],
                      [("all", [(L[3], _inward(L, 2), 0.0, math.inf), (L[3], _inward(L, 3), 0.0, math.inf)]),
                       ("all", [(np.array([0, 0.5]), _inward(L, 5), 0.0, math.inf)]),
                       ("all", [(np.array([0.5, 0]), _inward(L, 0), 0.0, math.inf)])],
                      [(1, 1), (0, 0.5), (0.5, 0)]))
    cases.append(Case("square point fingers on two convex corners + edge", square,
                      [PointFinger((1, 1)), PointFinger((-1, -1)), PointFinger((-1, 0.3))],
                      [("any", [(square[2], _inward(square, 1), 0.0, math.inf), (square[2], _inward(square, 2), 0.0, math.inf)]),
                       ("any", [(square[0], _inward(square, 3), 0.0, math.inf), (square[0], _inward(square, 0), 0.0, math.inf)]),
                       ("all", [(np.array([-1, 0.3]), _inward(square, 3), 0.0, math.inf)])],
                      [(-1, 0.3)]))
    # random cases -----------------------------------------------------------------
    kinds = ["edges", "reflex", "concurrent", "concurrent_disc", "corner_flats", "mixed", "convex_points",
             "concurrent_flats"]
    while len(cases) < 5 + n_random:
        kind = kinds[len(cases) % len(kinds)]
        outer = _star(rng, int(rng.integers(5, 9)))
        if not _polygon_ok(outer):
            continue
        poly = shapely.Polygon(outer)
        n = len(outer)
        fingers, groups, points = [], [], []
        if kind in ("edges", "mixed"):
            for i in rng.choice(n, size=min(n, int(rng.integers(2, 6))), replace=False):
                p = _edge_point(outer, i, rng.uniform(0.2, 0.8))
                fingers.append(PointFinger(tuple(p)))
                groups.append(("all", [(p, _inward(outer, i), 0.0, math.inf)]))
                points.append(p)
        if kind in ("reflex", "mixed"):
            refl = [i for i in range(n) if _vertex_kind(outer, i) == "reflex"]
            if not refl:
                continue
            for i in refl[: int(rng.integers(1, 3))]:
                fingers.append(PointFinger(tuple(outer[i])))
                groups.append(("all", [(outer[i], _inward(outer, i - 1), 0.0, math.inf),
                                       (outer[i], _inward(outer, i), 0.0, math.inf)]))
            for i in rng.choice(n, size=int(rng.integers(1, 4)), replace=False):
                p = _edge_point(outer, i, rng.uniform(0.25, 0.75))
                fingers.append(PointFinger(tuple(p)))
                groups.append(("all", [(p, _inward(outer, i), 0.0, math.inf)]))
                points.append(p)
        if kind in ("concurrent", "concurrent_disc"):
            c0 = rng.uniform(-0.5, 0.5, 2) if rng.random() < 0.7 else rng.uniform(-2.0, 2.0, 2)
            cand = []
            for i in range(n):
                a, b = outer[i], outer[(i + 1) % n]
                s = float(np.dot(c0 - a, b - a) / np.dot(b - a, b - a))
                if 0.1 < s < 0.9:
                    cand.append((i, a + s * (b - a)))
            if len(cand) < 3:
                continue
            sel = rng.choice(len(cand), size=min(len(cand), int(rng.integers(3, 5))), replace=False)
            for j in sel:
                i, p = cand[j]
                nin = _inward(outer, i)
                r = float(rng.uniform(0.05, 0.6)) if kind == "concurrent_disc" and rng.random() < 0.7 else 0.0
                if r > 0 and _disc_ok(poly, p - r * nin, r):
                    fingers.append(DiscFinger(tuple(p - r * nin), r))
                    groups.append(("all", [(p, nin, r, math.inf)]))
                else:
                    fingers.append(PointFinger(tuple(p)))
                    groups.append(("all", [(p, nin, 0.0, math.inf)]))
                points.append(p)
        if kind == "concurrent_flats":
            # normals through c0: flat faces on convex corners (h = -t) and points on edges (h = t)
            c0 = rng.uniform(-0.4, 0.4, 2)
            cand = []
            for i in range(n):
                a, b = outer[i], outer[(i + 1) % n]
                s = float(np.dot(c0 - a, b - a) / np.dot(b - a, b - a))
                if 0.1 < s < 0.9:
                    cand.append(("edge", i, a + s * (b - a)))
                if _vertex_kind(outer, i) == "convex":
                    m = (c0 - outer[i]) / np.linalg.norm(c0 - outer[i])
                    if np.min((outer - outer[i]) @ m) >= -1e-12:
                        cand.append(("flat", i, m))
            if len(cand) < 3:
                continue
            # prefer flats; keep subsets whose normals positively span the plane
            wts = np.array([3.0 if c[0] == "flat" else 1.0 for c in cand])
            for _ in range(30):
                sel = rng.choice(len(cand), size=min(len(cand), int(rng.integers(3, 6))), replace=False,
                                 p=wts / wts.sum())
                nrm = np.array([_inward(outer, cand[j][1]) if cand[j][0] == "edge" else cand[j][2] for j in sel])
                if _strictly_inside_hull(nrm):
                    break
            else:
                continue
            for j in sel:
                what, i, data = cand[j]
                if what == "edge":
                    fingers.append(PointFinger(tuple(data)))
                    groups.append(("all", [(data, _inward(outer, i), 0.0, math.inf)]))
                    points.append(data)
                else:
                    fingers.append(HalfPlaneFinger(tuple(outer[i]), tuple(data)))
                    groups.append(("all", [(outer[i], data, math.inf, 0.0)]))
        if kind == "corner_flats":
            conv = [i for i in range(n) if _vertex_kind(outer, i) == "convex"]
            for i in rng.choice(conv, size=min(len(conv), int(rng.integers(3, 5))), replace=False):
                n1, n2 = _inward(outer, i - 1), _inward(outer, i)
                w = rng.uniform(0.2, 0.8)
                m = w * n1 + (1 - w) * n2
                m /= np.linalg.norm(m)
                # the face must only touch the corner: the whole part on its positive side
                if np.min((outer - outer[i]) @ m) < -1e-12:
                    continue
                fingers.append(HalfPlaneFinger(tuple(outer[i]), tuple(m)))
                groups.append(("all", [(outer[i], m, math.inf, 0.0)]))
            if rng.random() < 0.5:
                i = int(rng.integers(n))
                p = _edge_point(outer, i, 0.5)
                fingers.append(PointFinger(tuple(p)))
                groups.append(("all", [(p, _inward(outer, i), 0.0, math.inf)]))
                points.append(p)
        if kind == "convex_points":
            conv = [i for i in range(n) if _vertex_kind(outer, i) == "convex"]
            for i in rng.choice(conv, size=min(len(conv), 2), replace=False):
                fingers.append(PointFinger(tuple(outer[i])))
                groups.append(("any", [(outer[i], _inward(outer, i - 1), 0.0, math.inf),
                                       (outer[i], _inward(outer, i), 0.0, math.inf)]))
            for i in rng.choice(n, size=int(rng.integers(2, 4)), replace=False):
                p = _edge_point(outer, i, rng.uniform(0.25, 0.75))
                fingers.append(PointFinger(tuple(p)))
                groups.append(("all", [(p, _inward(outer, i), 0.0, math.inf)]))
                points.append(p)
        if len(fingers) < 2:
            continue
        # fingers must not overlap the part beyond touching
        if any(isinstance(f, DiscFinger) and not _disc_ok(poly, f.center, f.radius) for f in fingers):
            continue
        cases.append(Case(f"random {kind} #{len(cases)}", outer, fingers, groups, points))
    return cases


CATALOGUE = build_catalogue()


def test_catalogue_is_rich():
    """≥ 50 random sets, with held and escaping verdicts at both orders."""
    assert len(CATALOGUE) >= 55
    assert sum(1 for v in (reference_closure(c.groups) for c in CATALOGUE) if v == (False, 2)) >= 3
    verdicts = [reference_closure(c.groups) for c in CATALOGUE]
    kinds = {v for v in verdicts}
    assert {(True, 1), (False, 1), (True, 2), (False, 2)} <= kinds, kinds
    assert sum(1 for c in CATALOGUE if "reflex" in c.name or "concave" in c.name) >= 5
    assert sum(1 for c in CATALOGUE if "concurrent" in c.name) >= 15


@pytest.mark.parametrize("case", CATALOGUE, ids=[c.name for c in CATALOGUE])
def test_theorem1_deform_closure_equals_rigid_form_closure(case):
    """Thm 1: deform closure (our test on the mesh) ⇔ form closure of the rigid part."""
    # insert the contact points on edges as nodes in half of the cases only, so contacts
    # inside an edge are exercised as well
    idx = CATALOGUE.index(case)
    mesh = make_mesh(case.outer, points=case.points if idx % 2 == 0 else ())
    res = deform_closure(mesh, case.fingers)
    expected = reference_closure(case.groups)
    assert (res.deform_closure, res.order) == expected
    # every finger touches: active, no force (no pre-squeeze), equilibrium at rest
    assert all(c.active for c in res.contacts)
    assert res.energy == pytest.approx(0.0, abs=1e-18)
    if not res.deform_closure:
        _check_certificate(res, case)


def _check_certificate(res, case):
    """The escaping twist keeps every constraint of some choice non-penetrating
    (first order), recomputed from the construction data about the reported centroid."""
    tw = np.asarray(res.twist)
    L = shapely.Polygon(case.outer).length  # any scale: only signs matter
    assert np.linalg.norm(np.r_[tw[:2], tw[2] * 1.0]) > 0
    c = res.centroid
    ok_any = []
    options = [[(p,) for p in prims] if mode == "any" else [tuple(prims)] for mode, prims in case.groups]
    for choice in itertools.product(*options):
        rates = [np.dot(n, tw[:2] + tw[2] * np.array([-(p[1] - c[1]), p[0] - c[0]])) for g in choice
                 for (p, n, _, _) in g]
        ok_any.append(min(rates) >= -1e-9 * L)
    assert any(ok_any)


def test_relative_curvature_special_cases():
    t = np.array([0.3, -0.2])
    assert np.allclose(relative_curvature(t, 0.0, np.inf), t)  # point on an edge
    assert np.allclose(relative_curvature(t, 0.5, np.inf), t + 0.5)  # disc on an edge
    assert np.allclose(relative_curvature(t, np.inf, 0.0), -t)  # flat face on a vertex
    assert np.allclose(relative_curvature(t, 0.5, 0.0), (t + 0.5) * (-t) / 0.5)


def test_rigid_closure_without_contacts_escapes():
    r = rigid_closure([], [0, 0], 1.0)
    assert not r.closed and r.order == 1 and r.twist is not None


# ----------------------------------------------------------------------------- report / CLI


def _rect_mesh(W=0.04, H=0.02):
    return make_mesh([[0, 0], [W, 0], [W, H], [0, H]], divisions=80)


def test_report_keys_and_prequeeze():
    """Check report (SPEC §5): exact keys, SI, forces balance; held by 4 pre-squeezing jaws."""
    W, H, d = 0.04, 0.02, 1e-5
    mesh = _rect_mesh(W, H)
    fingers = [HalfPlaneFinger((d, 0), (1, 0)), HalfPlaneFinger((W - d, 0), (-1, 0)),
               HalfPlaneFinger((0, d), (0, 1)), HalfPlaneFinger((0, H - d), (0, -1))]
    res = deform_closure(mesh, fingers)
    rep = json.loads(json.dumps(res.to_dict()))
    assert set(rep) >= {"deform_closure", "order", "energy", "contacts", "certificate", "units"}
    assert rep["equilibrium"]["converged"] and rep["equilibrium"]["energy"] == rep["energy"]
    assert rep["deform_closure"] is True and rep["order"] == 1 and rep["certificate"] is None
    assert rep["energy"] > 0
    assert rep["units"]["length"] == "m" and rep["units"]["energy"] == "J"
    for i, c in enumerate(rep["contacts"]):
        assert set(c) == {"finger", "active", "force", "feature"}
        assert c["finger"] == i and c["active"] is True and c["feature"] == "edge"
    F = np.array([c["force"] for c in rep["contacts"]])
    assert np.allclose(F.sum(axis=0), 0, atol=1e-9 * np.abs(F).max())
    assert F[0, 0] > 0 and F[1, 0] < 0 and F[2, 1] > 0 and F[3, 1] < 0


def test_escape_certificate_for_two_jaws():
    """Two parallel jaws squeezing a rectangle: held in x, slides along the jaws (order 1)."""
    W, H, d = 0.04, 0.02, 1e-5
    mesh = _rect_mesh(W, H)
    res = deform_closure(mesh, [HalfPlaneFinger((d, 0), (1, 0)), HalfPlaneFinger((W - d, 0), (-1, 0))])
    assert not res.deform_closure and res.order == 1
    tw = res.twist
    assert abs(tw[0]) < 1e-9 and abs(tw[2]) < 1e-9 and abs(abs(tw[1]) - 1) < 1e-9
    assert [c.feature for c in res.contacts] == ["edge", "edge"]


def test_inactive_finger_and_features():
    mesh = make_mesh([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], points=[(1, 1)])
    res = deform_closure(mesh, [PointFinger((1, 1)), DiscFinger((3.5, 0.5), 0.2), PointFinger((2, 1))])
    feats = [c.feature for c in res.contacts]
    assert feats[0] == "concave_vertex" and feats[2] == "convex_vertex"
    assert [c.active for c in res.contacts] == [True, False, True]


def _run_cli(argv):
    from deformclosure.cli.main import main

    return main(argv)


@pytest.mark.slow
def test_cli_check_report_and_plot(tmp_path, capsys):
    part = tmp_path / "part.json"
    part.write_text(json.dumps({"name": "sq", "units": "mm", "outer": [[0, 0], [20, 0], [20, 20], [0, 20]],
                                "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 1,
                                             "elastic_limit_strain": 0.5}, "mesh": {"max_area": 8}}))
    fing = tmp_path / "f.json"
    fing.write_text(json.dumps({"units": "mm", "fingers": [
        {"type": "point", "at": [10, 0]}, {"type": "point", "at": [20, 10]},
        {"type": "point", "at": [10, 20]}, {"type": "point", "at": [0, 10]}]}))
    out, png = tmp_path / "r.json", tmp_path / "c.png"
    assert _run_cli(["check", str(part), "--fingers", str(fing), "-o", str(out), "--plot", str(png)]) == 0
    rep = json.loads(out.read_text())
    assert rep["deform_closure"] is True and rep["order"] == 2
    assert png.stat().st_size > 1000
    assert "HELD" in capsys.readouterr().out
    # escaping set: three fingers -> certificate in SI
    fing.write_text(json.dumps({"units": "mm", "fingers": [
        {"type": "point", "at": [10, 0]}, {"type": "point", "at": [20, 10]}, {"type": "point", "at": [0, 10]}]}))
    assert _run_cli(["check", str(part), "--fingers", str(fing), "-o", str(out), "--plot", str(png)]) == 0
    rep = json.loads(out.read_text())
    assert rep["deform_closure"] is False and len(rep["certificate"]["twist"]) == 3
