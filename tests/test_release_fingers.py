"""Release energy ``U_A`` of any finger set from the energy landscape over the part's
placement (SPEC §7, issue 14).

* Thm 1 at rest: ``deform_closure`` of ``check`` equals the rigid form-closure test of
  :mod:`deformclosure.dspace.closure` on a catalogue of contact sets (first and second
  order), and the energy kernel agrees on its own: zero along the escaping motion, positive
  around a held part.
* Two pads: ``check`` (disc fingers at the pads' places at σ) and ``optimize --model pads``
  agree on the verdict and on ``U_A`` within the stated errors, held and not held.
* A cage whose fingers do not touch the part: ``U_A`` is the barrier of squeezing through
  the narrowest gap (hand calculation), or infinite for a closed box.
* Invariance under a rigid motion of part and fingers (Thm 2); convergence under mesh and
  lattice refinement.
* The escape path is continuous, starts at the equilibrium, ends released, and its highest
  energy above the start is ``U_A``.
"""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest
import shapely

from deformclosure import Part, mesh_part
from deformclosure.dspace import (DiscFinger, HalfPlaneFinger, PlacementEnergy, PointFinger, PolygonFinger,
                                  deform_closure, release_energy_fingers)

MAT_M = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 0.002, "elastic_limit_strain": 0.5}
RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0, "elastic_limit_strain": 0.8,
          "plane": "stress"}
MM = 1e-3


def part_m(outer, points=(), divisions=40, material=MAT_M):
    outer = np.asarray(outer, float)
    area = shapely.Polygon(outer).area
    return Part.from_dict({"name": "t", "units": "m", "outer": outer.tolist(), "material": material,
                           "mesh": {"max_area": area / divisions, "min_angle": 25,
                                    "points": [list(map(float, p)) for p in points]}})


def part_mm(outer, max_area, material=RUBBER, name="p"):
    return Part.from_dict({"name": name, "units": "mm", "outer": [list(map(float, p)) for p in outer],
                           "material": material, "mesh": {"max_area": max_area, "min_angle": 30}})


# ============================================================================ Thm 1 at rest

def _inward(outer, i):
    e = outer[(i + 1) % len(outer)] - outer[i]
    e = e / np.linalg.norm(e)
    return np.array([-e[1], e[0]])


def _kind(outer, i):
    a, v, b = outer[i - 1], outer[i], outer[(i + 1) % len(outer)]
    cr = (v - a)[0] * (b - v)[1] - (v - a)[1] * (b - v)[0]
    return "convex" if cr > 0 else "reflex"


SHAPES = {
    "rectangle": np.array([[-1.0, -0.6], [1.0, -0.6], [1.0, 0.6], [-1.0, 0.6]]),
    "L": np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float) - 0.7,
    "decagon": np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, 11)[:-1] + 0.1]),
}


def _candidates(rng, outer):
    """Fingers touching the part at rest: (finger, point to insert as a node or None)."""
    poly = shapely.Polygon(outer)
    n = len(outer)
    out = []
    for i in range(n):
        a, b = outer[i], outer[(i + 1) % n]
        nin = _inward(outer, i)
        p = a + rng.uniform(0.2, 0.8) * (b - a)
        out.append((PointFinger(tuple(p)), p))
        r = float(rng.uniform(0.1, 0.5))
        q = a + rng.uniform(0.25, 0.75) * (b - a)
        c = q - r * nin
        if shapely.Point(c).distance(poly) >= r * (1 - 1e-9):
            out.append((DiscFinger(tuple(c), r), None))
        if np.min((outer - a) @ nin) >= -1e-12:                    # a flat face on the edge
            out.append((HalfPlaneFinger(tuple(a), tuple(nin)), None))
        if _kind(outer, i) == "reflex":
            out.append((PointFinger(tuple(outer[i])), None))
        else:
            if rng.random() < 0.5:
                out.append((PointFinger(tuple(outer[i])), None))
            w = rng.uniform(0.2, 0.8)
            m = w * _inward(outer, i - 1) + (1 - w) * nin
            m /= np.linalg.norm(m)
            if np.min((outer - outer[i]) @ m) >= -1e-12:           # a flat face on the corner
                out.append((HalfPlaneFinger(tuple(outer[i]), tuple(m)), None))
    return out


def _classic():
    """Hand-made sets, so both orders and both verdicts occur."""
    R, D = SHAPES["rectangle"], SHAPES["decagon"]
    mids = [0.5 * (R[i] + R[(i + 1) % 4]) for i in range(4)]
    cases = [
        ("rectangle: 4 points at the mid-sides (order 2, held)", R, [PointFinger(tuple(p)) for p in mids], mids),
        ("rectangle: 2 discs + 2 points at the mid-sides (order 2, held)", R,
         [DiscFinger((-1.3, 0.0), 0.3), DiscFinger((1.3, 0.0), 0.3), PointFinger(tuple(mids[0])),
          PointFinger(tuple(mids[2]))], [mids[0], mids[2]]),
        ("rectangle: 4 flat faces on the corners (order 2, escapes)", R,
         [HalfPlaneFinger(tuple(v), tuple(-v / np.linalg.norm(v))) for v in R], []),
        ("rectangle: 3 mid-side points (order 1, escapes)", R, [PointFinger(tuple(p)) for p in mids[:3]],
         mids[:3]),
        ("rectangle: flat faces on 3 sides + a point (order 1, held)", R,
         [HalfPlaneFinger(tuple(R[i]), tuple(_inward(R, i))) for i in range(3)] + [PointFinger(tuple(mids[3]))],
         [mids[3]]),
        ("decagon: 3 mid-edge points 120° apart (order 2, held)", D,
         [PointFinger(tuple(0.5 * (D[i] + D[(i + 1) % 10]))) for i in (0, 3, 6)],
         [0.5 * (D[i] + D[(i + 1) % 10]) for i in (0, 3, 6)]),
        ("decagon: 2 flat faces on opposite edges (order 1, escapes)", D,
         [HalfPlaneFinger(tuple(D[i]), tuple(_inward(D, i))) for i in (0, 5)], []),
    ]
    return cases


def build_catalogue(seed=14, n_random=54):
    rng = np.random.default_rng(seed)
    cases = list(_classic())
    names = list(SHAPES)
    while len(cases) < len(_classic()) + n_random:
        shape = names[len(cases) % len(names)]
        outer = SHAPES[shape]
        pool = _candidates(rng, outer)
        k = int(rng.integers(2, 6))
        sel = rng.choice(len(pool), size=min(k, len(pool)), replace=False)
        fingers = [pool[j][0] for j in sel]
        points = [pool[j][1] for j in sel if pool[j][1] is not None]
        cases.append((f"{shape} #{len(cases)}: " + ", ".join(f.type for f in fingers), outer, fingers, points))
    return cases


CATALOGUE = build_catalogue()


@functools.lru_cache(maxsize=None)
def _rigid(idx):
    name, outer, fingers, points = CATALOGUE[idx]
    mesh = mesh_part(part_m(outer, points=points if idx % 2 == 0 else ()))
    return mesh, deform_closure(mesh, fingers)


def test_catalogue_has_both_orders_and_verdicts():
    assert len(CATALOGUE) >= 50
    kinds = {(res.deform_closure, res.order) for res in (_rigid(i)[1] for i in range(len(CATALOGUE)))}
    assert {(True, 1), (False, 1), (True, 2), (False, 2)} <= kinds, kinds


def _twist_placement(twist, centroid, eps):
    """Placement after moving the part along ``twist`` (about ``centroid``) for time ``eps``."""
    v, w = np.asarray(twist[:2], float), float(twist[2])
    if abs(w) < 1e-12:
        return np.r_[eps * v, 0.0]
    c0 = centroid + np.array([-v[1], v[0]]) / w          # instantaneous centre
    th = eps * w
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    return np.r_[c0 + R @ (centroid - c0) - centroid, th]


@pytest.mark.parametrize("idx", range(len(CATALOGUE)), ids=[c[0] for c in CATALOGUE])
@pytest.mark.slow
def test_theorem1_at_rest(idx):
    """Thm 1: deform closure (the release energy at rest) ⇔ rigid form closure, and the
    energy landscape agrees: E = 0 along the escaping motion, E > 0 around a held part."""
    mesh, res = _rigid(idx)
    fingers = CATALOGUE[idx][2]
    rel = release_energy_fingers(mesh, fingers, start=res.equilibrium, stop_above=0.0, levels=0)
    assert rel.energy == 0.0
    assert rel.deform_closure == res.deform_closure
    if res.deform_closure:
        assert rel.strict and rel.U_A > rel.U_A_error
    # the energy kernel on its own
    pe = PlacementEnergy(mesh, fingers)
    L = float(mesh.diameter)
    E_scale = MAT_M["youngs_modulus"] * MAT_M["thickness"] * (1e-4 * L) ** 2
    if res.deform_closure:
        for d in np.eye(3) * np.array([1e-3 * L, 1e-3 * L, 1e-3]):
            for sgn in (1, -1):
                assert pe.energy(sgn * d).energy > 0, (d, sgn)
        if res.order == 2:                               # the critical rotation about c0
            c0 = res.rotation_center
            for th in (1e-3, -1e-3):
                R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
                g = np.r_[c0 + R @ (pe.centroid - c0) - pe.centroid, th]
                assert pe.energy(g).energy > 0
    else:
        g = _twist_placement(res.twist, pe.centroid, 1e-4 * L)
        assert pe.energy(g).energy <= 1e-6 * E_scale


# ============================================================================ two pads

def taper(depth=1.5):
    """A 30 × 12 mm bar tapering to 6 mm at its ends, with a V-notch of ``depth`` mm in the
    middle of each long side: round pads seated in the notches hold it, and the way out
    (sliding past a notch shoulder, then down the taper) stays within the model."""
    return [[0, 3], [12, 0], [15, depth], [18, 0], [30, 3], [30, 9], [18, 12], [15, 12 - depth],
            [12, 12], [0, 9]]


def pad_fingers(result, sigma):
    """Disc fingers of the pads' radius at their places at separation ``sigma`` (W = 0),
    each pad pressed half the squeeze past its first touch (the part floats between them,
    so only their separation matters)."""
    rho = result.pad.radius
    ca, cb = np.asarray(result.contacts, float)
    a = (cb - ca) / np.linalg.norm(cb - ca)
    za = ca + 0.5 * (result.sigma0 - sigma) * a           # pad A's face
    return [DiscFinger(tuple(za - rho * a), rho), DiscFinger(tuple(za + (sigma + rho) * a), rho)]


PAD_GRASPS = {
    # name: (outer (mm), max_area (mm²), axis through two points (mm), pad radius (mm), held)
    "tapered bar, pads in the notches (held)": (taper(1.5), 0.4, ([15, 0], [15, 12]), 2.0, True),
    "tapered bar, shallow notches (held)": (taper(1.0), 0.4, ([15, 0], [15, 12]), 2.0, True),
    "12 x 20 mm block across its width (not held)": ([[0, 0], [12, 0], [12, 20], [0, 20]], 1.0,
                                                     ([0, 10], [12, 10]), 1.0, False),
    "16-gon of radius 8 mm (not held)": ([[8 * np.cos(t), 8 * np.sin(t)] for t in
                                          np.linspace(0, 2 * np.pi, 17)[:-1] + 0.1], 0.3,
                                         ([-8, 0.5], [8, 0.5]), 1.5, False),
}


@pytest.mark.parametrize("name", list(PAD_GRASPS))
@pytest.mark.slow
def test_check_agrees_with_optimize_for_two_pads(name):
    """SPEC §7: for two pads, check (disc fingers at the pads' places at σ) and optimize
    (pads model) agree on the verdict and on U_A within the stated errors."""
    from deformclosure.pads import GraspAxis, Pad, PadContact, optimize_pads
    from deformclosure.mesh.generate import twin_mesh

    outer, area, (p, q), rho, held = PAD_GRASPS[name]
    part = part_mm(outer, area)
    mesh = mesh_part(part)
    axis = GraspAxis.through(np.asarray(p) * MM, np.asarray(q) * MM)
    pads = optimize_pads(mesh, axis, Pad(0.0, rho * MM), twin=PadContact(twin_mesh(part)))
    # one mesh: "undecided" where it does not resolve the contacts, never "held" for a
    # part that is not held
    assert (pads.verdict != "not held") == held
    if held:
        sigma, U_pads = pads.sigma_star, pads.U_A
    else:                     # no σ* when nothing holds: the middle of the squeeze range
        sigma, U_pads = 0.5 * (pads.sigma0 + pads.sigma_L), 0.0
    fingers = pad_fingers(pads, sigma)
    rel = release_energy_fingers(mesh, fingers, part=part)
    assert rel.deform_closure == held
    # the same contact energy as the pads at their axis (SPEC §6): the part floats along it
    from scipy.optimize import minimize_scalar

    pe = PlacementEnergy(mesh, fingers)
    a = axis.direction
    h = 0.25 * (pads.sigma0 - sigma)
    E_axis = minimize_scalar(lambda t: pe.energy(np.r_[t * a, 0.0]).energy, bounds=(-h, h),
                             method="bounded", options={"xatol": 1e-9}).fun
    assert E_axis == pytest.approx(float(pads.start_curve.energy_at(sigma)), rel=0.02)
    assert abs(rel.U_A - U_pads) <= rel.U_A_error + pads.noise, (rel.U_A, U_pads, rel.U_A_error)
    if held:
        assert rel.target == "released" and rel.U_A > 0


# ============================================================================ cages

def _slot_cage(max_area):
    """An 8 × 12 mm rubber rectangle in a chamber 0.3 mm wider all round (half-planes left,
    right and below), whose lid (two polygon fingers) has a 7.6 mm wide, 14 mm long slot
    above the part. No finger touches the part."""
    W, H, gap, w, Ls = 8.0, 12.0, 0.3, 7.6, 14.0
    part = part_mm([[-W / 2, -H / 2], [W / 2, -H / 2], [W / 2, H / 2], [-W / 2, H / 2]], max_area,
                   material={**RUBBER, "poisson_ratio": 0.3})
    yl = H / 2 + gap
    box = lambda x0, x1: PolygonFinger(tuple(map(tuple, np.array(   # noqa: E731
        [[x0, yl], [x1, yl], [x1, yl + Ls], [x0, yl + Ls]]) * MM)))
    fingers = [HalfPlaneFinger((-(W / 2 + gap) * MM, 0.0), (1.0, 0.0)),
               HalfPlaneFinger(((W / 2 + gap) * MM, 0.0), (-1.0, 0.0)),
               HalfPlaneFinger((0.0, -(H / 2 + gap) * MM), (0.0, 1.0)),
               box(-20.0, -w / 2), box(w / 2, 20.0)]
    return part, fingers, (W * MM, H * MM, (W - w) * MM)


@pytest.mark.slow
def test_cage_barrier_is_squeezing_through_the_slot():
    """Caged, untouched: the way out is through the slot, and the barrier is the part
    squeezed across its width over its whole length between the slot's flat faces — the
    uniaxial energy ½ E t H δ² / W (plane stress, frictionless faces): 0.24 mJ."""
    part, fingers, (W, H, delta) = _slot_cage(0.15)
    mesh = mesh_part(part)
    rel = release_energy_fingers(mesh, fingers, part=part)
    hand = 0.5 * RUBBER["youngs_modulus"] * RUBBER["thickness"] * MM * H * delta**2 / W
    assert rel.energy == 0.0 and not rel.strict
    assert rel.target == "released" and rel.caged and not rel.deform_closure
    assert abs(rel.U_A - hand) <= rel.U_A_error and abs(rel.U_A - hand) <= 0.05 * hand, (rel.U_A, hand)
    # the saddle has the part inside the slot, centred and upright
    g = rel.path[rel.saddle]
    assert abs(g[0]) < 1e-9 and abs(g[2]) < 0.05
    assert rel.path[-1][1] > H + 14 * MM - H / 2           # released above the lid


@pytest.mark.slow
def test_closed_box_is_an_infinite_cage():
    """Four walls around the part, none touching it: it rattles but nothing lets it out
    without pushing a wall deeper than the model allows — U_A is infinite."""
    W, H, gap = 8.0, 12.0, 0.3
    part = part_mm([[-W / 2, -H / 2], [W / 2, -H / 2], [W / 2, H / 2], [-W / 2, H / 2]], 2.0)
    fingers = [HalfPlaneFinger((-(W / 2 + gap) * MM, 0.0), (1.0, 0.0)),
               HalfPlaneFinger(((W / 2 + gap) * MM, 0.0), (-1.0, 0.0)),
               HalfPlaneFinger((0.0, -(H / 2 + gap) * MM), (0.0, 1.0)),
               HalfPlaneFinger((0.0, (H / 2 + gap) * MM), (0.0, -1.0))]
    rel = release_energy_fingers(mesh_part(part), fingers)
    assert rel.U_A_infinite and rel.caged and not rel.deform_closure
    d = rel.to_dict()
    assert d["U_A"] is None and d["U_A_infinite"] is True and d["escape_path"]["placements"] == []


# ============================================================================ invariance, convergence, path

def taper_grasp(area, sigma=7.09e-3, rho=2e-3, depth=1.5):
    """The tapered bar held by two round pads (discs) in its notches at separation σ."""
    from deformclosure.pads.geometry import GraspAxis, Pad, first_touch

    part = part_mm(taper(depth), area)
    mesh = mesh_part(part)
    axis = GraspAxis.through(np.array([15, 0]) * MM, np.array([15, 12]) * MM)
    t = first_touch(mesh.nodes[mesh.outer_loop], axis, Pad(0.0, rho))
    a = axis.direction
    za = t.contact_a + 0.5 * (t.sigma0 - sigma) * a
    return part, mesh, [DiscFinger(tuple(za - rho * a), rho), DiscFinger(tuple(za + (sigma + rho) * a), rho)]


def _moved(f, R, c, t):
    move = lambda p: tuple(R @ (np.asarray(p, float) - c) + c + t)   # noqa: E731
    if isinstance(f, DiscFinger):
        return DiscFinger(move(f.center), f.radius)
    if isinstance(f, PointFinger):
        return PointFinger(move(f.at))
    if isinstance(f, HalfPlaneFinger):
        return HalfPlaneFinger(move(f.point), tuple(R @ np.asarray(f.normal)))
    return PolygonFinger(tuple(move(v) for v in f.vertices))


@pytest.mark.slow
def test_invariant_under_a_rigid_motion_of_part_and_fingers():
    """Thm 2: moving part and fingers together changes neither U_A, its error, the energy
    nor the escape path (relative to the part)."""
    part, mesh, fingers = taper_grasp(0.4)
    ang, c, t = 0.7, np.array([0.01, 0.02]), np.array([0.3, -0.2])
    R = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
    mesh2 = mesh.rotated(ang, c).translated(t)
    fingers2 = [_moved(f, R, c, t) for f in fingers]
    r1 = release_energy_fingers(mesh, fingers, levels=1)
    r2 = release_energy_fingers(mesh2, fingers2, levels=1)
    assert r1.deform_closure and r2.deform_closure
    assert r2.U_A == pytest.approx(r1.U_A, rel=1e-6)
    assert r2.U_A_error == pytest.approx(r1.U_A_error, rel=1e-6, abs=1e-9 * r1.U_A)
    assert r2.energy == pytest.approx(r1.energy, rel=1e-6)
    assert len(r2.path) == len(r1.path)
    assert np.allclose(r2.path_energy, r1.path_energy, rtol=1e-6)
    # the same motion of the part: the escape paths' rotations agree, translations turn with R
    assert np.allclose(r2.path[:, 2] - r2.path[0, 2], r1.path[:, 2] - r1.path[0, 2], atol=1e-9)
    d1, d2 = r1.path[:, :2] - r1.path[0, :2], r2.path[:, :2] - r2.path[0, :2]
    assert np.allclose(d2, d1 @ R.T, atol=1e-9)


@pytest.mark.slow
def test_converges_under_mesh_and_lattice_refinement():
    """U_A of the tapered bar: successive meshes (h halving) agree within their stated
    errors and the two finest within 3 %, and lattices of 32 to 72 steps per diameter agree
    within the stated errors. (The changes need not shrink on these unstructured meshes:
    the pads model's U_A on the same meshes goes 4.17 → 4.24 mJ between the two finest.)"""
    U, err = [], []
    for area in (0.4, 0.2, 0.1):
        part, mesh, fingers = taper_grasp(area)
        rel = release_energy_fingers(mesh, fingers, part=part)
        assert rel.deform_closure and rel.target == "released"
        U.append(rel.U_A)
        err.append(rel.U_A_error)
    for k in range(2):
        assert abs(U[k + 1] - U[k]) <= err[k] + err[k + 1]
    assert abs(U[2] - U[1]) < 0.03 * U[2]
    part, mesh, fingers = taper_grasp(0.2)
    rels = [release_energy_fingers(mesh, fingers, part=part, n_translation=n) for n in (32, 48, 72)]
    for a in rels:
        for b in rels:
            assert abs(a.U_A - b.U_A) <= a.U_A_error + b.U_A_error
    assert max(r.U_A for r in rels) - min(r.U_A for r in rels) < 0.02 * rels[-1].U_A


@pytest.mark.slow
def test_escape_path_is_continuous_and_ends_released():
    part, mesh, fingers = taper_grasp(0.2)
    rel = release_energy_fingers(mesh, fingers, part=part)
    P, E, grid = rel.path, rel.path_energy, rel.grid
    assert len(P) > 2
    assert np.allclose(P[0], rel.equilibrium)                   # starts at the equilibrium
    assert E[0] == pytest.approx(rel.energy)
    d = np.diff(P, axis=0)
    d[:, 2] = (d[:, 2] + np.pi) % (2 * np.pi) - np.pi
    moves = np.c_[np.hypot(d[:, 0], d[:, 1]) / grid.h, np.abs(d[:, 2]) / grid.h_phi]
    assert np.all(moves <= 1 + 1e-9)                            # at most one lattice step
    assert np.all((moves > 1e-12).sum(axis=1) == 1)             # along one axis at a time
    pe = PlacementEnergy(mesh, fingers)
    assert rel.target == "released"
    assert pe.energy(P[-1]).energy == 0.0 and pe.escapable(P[-1], angle0=grid.angle)
    assert np.allclose([pe.energy(g).energy for g in P], E, rtol=1e-9)
    assert E.max() - rel.energy == pytest.approx(rel.U_A, rel=1e-12)
    assert rel.saddle == int(np.argmax(E))
    assert rel.U_L > 0 and rel.quality == pytest.approx(min(rel.U_A, rel.U_L))


# ============================================================================ the kernel

@pytest.mark.slow
def test_kernel_uniaxial_energy_and_force():
    """Two flat jaws squeezing a rectangle: E = ½ E t H (2d)² / W (plane stress), and the
    generalised force dE/dg matches finite differences."""
    W, H, d = 0.04, 0.02, 1e-5
    part = part_m([[0, 0], [W, 0], [W, H], [0, H]], divisions=200)
    mesh = mesh_part(part)
    pe = PlacementEnergy(mesh, [HalfPlaneFinger((d, 0), (1, 0)), HalfPlaneFinger((W - d, 0), (-1, 0))])
    hand = 0.5 * MAT_M["youngs_modulus"] * MAT_M["thickness"] * H * (2 * d) ** 2 / W
    assert pe.energy(np.zeros(3)).energy == pytest.approx(hand, rel=1e-4)
    g = np.array([3e-6, 1e-4, 0.0])
    st = pe.energy(g)
    eps = 1e-9
    fd = (pe.energy(g + [eps, 0, 0]).energy - pe.energy(g - [eps, 0, 0]).energy) / (2 * eps)
    assert st.gradient[0] == pytest.approx(fd, rel=1e-5)
    assert abs(st.gradient[1]) <= 1e-9 * abs(fd)                # sliding along the jaws is free
    assert np.allclose(st.forces.sum(axis=0), -st.gradient[:2], rtol=1e-9, atol=1e-12)


@pytest.mark.slow
def test_kernel_inadmissible_and_free():
    part, mesh, fingers = taper_grasp(0.4)
    pe = PlacementEnergy(mesh, fingers)
    assert pe.energy([0.0, 0.0, 0.0]).status == "contact"
    assert pe.energy([0.0, 0.04, 0.0]).status == "free"         # far away: nothing presses
    # a disc is a round pad (SPEC §6): no depth limit, and pressed 5 mm (more than its
    # diameter) into the bar it still pushes it along its axis
    deep = pe.energy([0.0, 0.004, 0.0])
    assert deep.status == "contact" and pe.energy([0.0, 0.0, 0.0]).energy < deep.energy < math.inf
    # a polygon finger 4.5 mm deep (beyond half the inscribed radius) is outside the model
    square = PolygonFinger(((0.005, -0.002), (0.008, -0.002), (0.008, 0.0058), (0.005, 0.0058)))
    assert PlacementEnergy(mesh, [square]).energy([0.0, 0.0, 0.0]).status == "inadmissible"


# ============================================================================ the CLI

@pytest.mark.slow
def test_cli_check_reports_release_energy(tmp_path, capsys):
    from deformclosure.cli.main import main

    pf = tmp_path / "bar.json"
    pf.write_text(json.dumps({"name": "taper", "units": "mm", "outer": taper(1.5), "material": RUBBER,
                              "mesh": {"max_area": 0.4, "min_angle": 30}}))
    _, mesh, fingers = taper_grasp(0.4)
    ff = tmp_path / "f.json"
    ff.write_text(json.dumps({"units": "mm", "fingers": [
        {"type": "disc", "center": [f.center[0] / MM, f.center[1] / MM], "radius": f.radius / MM}
        for f in fingers]}))
    out, png = tmp_path / "r.json", tmp_path / "c.png"
    assert main(["check", str(pf), "--fingers", str(ff), "-o", str(out), "--plot", str(png)]) == 0
    text = out.read_text()
    rep = json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in the report"))
    # SPEC §5 keys kept, §7 keys added
    assert {"deform_closure", "order", "energy", "contacts", "certificate", "units"} <= set(rep)
    assert {"rigid_closure", "U_A", "U_A_infinite", "U_A_error", "escape_path", "quality", "U_L"} <= set(rep)
    assert rep["deform_closure"] is True and rep["U_A"] > rep["U_A_error"] > 0
    assert isinstance(rep["rigid_closure"], bool) and rep["order"] in (1, 2)
    assert rep["quality"] == pytest.approx(min(rep["U_A"], rep["U_L"]))
    ep = rep["escape_path"]
    assert len(ep["placements"]) == len(ep["energy"]) > 2 and all(len(g) == 3 for g in ep["placements"])
    assert ep["target"] == "released"
    assert max(ep["energy"]) - ep["energy"][0] == pytest.approx(rep["U_A"])
    assert rep["units"]["energy"] == "J" and rep["units"]["angle"] == "rad"
    assert png.stat().st_size > 1000
    assert "HELD" in capsys.readouterr().out
