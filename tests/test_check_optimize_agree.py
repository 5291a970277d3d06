"""SPEC §7 "one mechanics": two round fingers in ``check`` and two round pads in
``optimize`` at the same separation σ give the same ``U_A`` within their error estimates
(issue 19, item 4), on a notched part and on a block.

Both are the same contact problem. ``optimize`` (SPEC §6) solves it on a grasp axis with
the part floating along the axis; ``check`` (SPEC §7) solves it for the part placed among
two fixed disc fingers of the pads' radius at the pads' places. So

* at one axis, ``check``'s energy minimised over the float along the axis (a scalar
  minimisation written here) equals the pads' energy of that axis — at the start and on
  every axis the pads' escape crosses, including those where a pad is pressed more than
  its diameter into the part;
* ``check``'s equilibrium energy equals the pads' energy of the axis through its fingers
  there;
* the two release energies agree within ``check``'s error estimate plus the pads' noise
  floor (the library's jitter estimate at σ, relative, times the barrier height).

Before issue 19's fix a disc stopped pushing material it was pressed into by more than its
diameter, its centre added rows a pad does not have, and it had a depth limit a pad does
not have: on the notched bar ``check`` gave 24.7 µJ (an "equilibrium" against an
inadmissible region) against the pads' 44.0 µJ, and on the built-in notched bar at σ*
∞ (a "cage") against 13.8 mJ. The block agreed before and after (a convex part: no deep
states on its way out); it guards the other direction.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from deformclosure import Part, mesh_part
from deformclosure.dspace import DiscFinger, PlacementEnergy, release_energy_fingers
from deformclosure.pads import GraspAxis, Pad, PadContact, optimize_pads
from deformclosure.mesh.generate import twin_mesh
from deformclosure.pads.noise import jitter_noise

MM = 1e-3
RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 0.002, "elastic_limit_strain": 0.8,
          "plane": "stress"}
RHO = 2.0                                                    # pad / disc radius, mm
SIGMA = [0.0]                                                # the σ (m) the float ranges are for


def notched_bar(L=36.0, H=14.0, xn=24.0, r=3.0, k=24):
    """A 36 × 14 mm bar with two round notches of radius 3 mm facing each other at x = 24 mm."""
    t = np.linspace(np.pi, 0.0, k + 1)
    bottom = [[xn + r * np.cos(a), r * np.sin(a)] for a in t]
    top = [[xn - r * np.cos(a), H - r * np.sin(a)] for a in t]
    return [[0, 0]] + bottom + [[L, 0], [L, H]] + top + [[0, H]]


GRASPS = {
    # name: (outer (mm), max_area (mm²), axis through two points (mm), held)
    "notched bar": (notched_bar(), 0.4, ([24, 0], [24, 14]), True),
    "12 x 20 mm block": ([[0, 0], [12, 0], [12, 20], [0, 20]], 0.4, ([0, 10], [12, 10]), False),
}


@functools.lru_cache(maxsize=None)
def grasp(name):
    """The pads' optimisation, σ (the middle sample of its curve: half the squeeze range),
    the pads' U_A there, and the disc fingers at the pads' places at σ."""
    outer, area, (p, q), held = GRASPS[name]
    part = Part.from_dict({"name": name, "units": "mm", "outer": [list(map(float, v)) for v in outer],
                           "material": RUBBER, "mesh": {"max_area": area, "min_angle": 30}})
    mesh = mesh_part(part)
    axis = GraspAxis.through(np.asarray(p) * MM, np.asarray(q) * MM)
    pad = Pad(0.0, RHO * MM)
    res = optimize_pads(mesh, axis, pad, twin=PadContact(twin_mesh(part)), n_samples=8, n_curve=5)
    sigma, U_pads = res.curve["sigma"][2], res.curve["U_A"][2]
    assert sigma == pytest.approx(0.5 * (res.sigma0 + res.sigma_L), rel=1e-12)
    # the discs: pad A's face moved half the squeeze past first touch, centres ρ behind the
    # faces (the part floats between them, so only their separation matters)
    sc = res.start_curve
    a = sc.axis.direction
    face = np.asarray(sc.axis.origin) + sc.touch.z_a * a + sc.axis.offset * sc.axis.normal
    za = face + 0.5 * (sc.sigma0 - sigma) * a
    r = pad.radius
    fingers = [DiscFinger(tuple(za - r * a), r), DiscFinger(tuple(za + (sigma + r) * a), r)]
    return part, mesh, axis, pad, res, sigma, U_pads, fingers, held


def _float_min(pe, g, a, lo, hi):
    """``min_t E(g + t a)`` (J) over the float ``t ∈ [lo, hi]`` (m) along the world axis ``a``:
    a scan, then a bounded scalar minimisation about its best point."""
    E = lambda t: pe.energy(np.r_[g[:2] + t * a, g[2]]).energy   # noqa: E731
    ts = np.linspace(lo, hi, 33)
    k = int(np.argmin([E(t) for t in ts]))
    r = minimize_scalar(E, bounds=(ts[max(k - 1, 0)], ts[min(k + 1, len(ts) - 1)]), method="bounded",
                        options={"xatol": 1e-12})
    return min(r.fun, E(ts[k]))


def _squeeze_range(pe, g, curve, a_w):
    """The floats ``[lo, hi]`` (m) at which both discs press at most the squeeze
    ``σ0 − σ`` past the pads' first touch on ``curve``'s axis (where the pads' float
    lies): disc A's face moves ``−t`` along the axis in the part frame."""
    ax = curve.axis
    c, s = math.cos(g[2]), math.sin(g[2])
    A = np.array([[c, s], [-s, c]]) @ (np.asarray(pe.fingers[0].center) - pe.centroid - g[:2]) + pe.centroid
    face_a = (A - np.asarray(ax.origin)) @ ax.direction + pe.fingers[0].radius
    delta = curve.delta(SIGMA[0])          # < 0: the pads do not reach the part at σ
    return tuple(sorted((face_a - curve.touch.z_a - delta, face_a - curve.touch.z_a)))


def _placement_on(pe, axis, angle_world):
    """A placement that puts the two disc centres on the part-frame ``axis`` (the float
    along it left at the fingers' own place)."""
    phi = angle_world - axis.angle
    c, s = math.cos(phi), math.sin(phi)
    R = np.array([[c, -s], [s, c]])
    A = np.asarray(pe.fingers[0].center)
    n = axis.normal
    t_n = n @ (R.T @ (A - pe.centroid)) + n @ pe.centroid - axis.offset - n @ np.asarray(axis.origin)
    n_w = np.array([-math.sin(angle_world), math.cos(angle_world)])
    return np.r_[t_n * n_w, phi]


def _axis_through_fingers(pe, g, origin):
    """The part-frame axis through the disc centres at placement ``g``."""
    c, s = math.cos(g[2]), math.sin(g[2])
    P = [np.array([[c, s], [-s, c]]) @ (np.asarray(f.center) - pe.centroid - g[:2]) + pe.centroid
         for f in pe.fingers]
    return GraspAxis.through(P[0], P[1], origin)


@pytest.mark.parametrize("name", list(GRASPS))
def test_disc_energy_is_the_pad_energy_on_every_axis(name):
    """At the start axis and on axes slid across the part (the pads' way out, through the
    notch shoulder and over the full section, where a pad is pressed more than its
    diameter into it), check's energy minimised over the float is the pads' energy."""
    part, mesh, axis, pad, res, sigma, _, fingers, _ = grasp(name)
    solver = res.solver
    pe = PlacementEnergy(mesh, fingers, solver=solver)
    a_w = (np.asarray(fingers[1].center) - fingers[0].center) / np.linalg.norm(
        np.asarray(fingers[1].center) - fingers[0].center)
    ang_w = math.atan2(a_w[1], a_w[0])
    SIGMA[0] = sigma
    U_s = float(res.start_curve.energy_at(sigma))
    lo, hi = _squeeze_range(pe, np.zeros(3), res.start_curve, a_w)
    assert _float_min(pe, np.zeros(3), a_w, lo, hi) == pytest.approx(U_s, rel=1e-6)
    _, x = axis.coordinates(mesh.nodes[mesh.outer_loop])
    deep = 0
    for c in np.linspace(axis.offset, x.max() + axis.offset + pad.radius, 9)[1:]:
        ax = GraspAxis(axis.angle, float(c), axis.origin)
        curve = solver.curve(ax, pad, sigma)
        U = float(curve.energy_at(sigma))
        g = _placement_on(pe, ax, ang_w)
        if curve.touch is None:                       # the pads miss the part
            assert U == 0.0 and pe.energy(g).energy == 0.0
            continue
        E = _float_min(pe, g, a_w, *_squeeze_range(pe, g, curve, a_w))
        assert E == pytest.approx(U, rel=1e-6, abs=1e-9 * U_s), (c, E, U)
        if curve.sigma0 - sigma > 4 * pad.radius:
            deep += 1                 # each pad pressed more than its diameter into the part
    if name == "notched bar":
        assert deep >= 2


@pytest.mark.parametrize("name", list(GRASPS))
def test_check_and_optimize_give_the_same_release_energy(name):
    """U_A at the same σ: check's within its error estimate plus the pads' noise floor of
    optimize's; the start energies to solver accuracy; the same verdict."""
    part, mesh, axis, pad, res, sigma, U_pads, fingers, held = grasp(name)
    rel = release_energy_fingers(mesh, fingers, part=part, solver=res.solver)
    # the start: at check's equilibrium g*, its energy minimised over the float is the pads'
    # energy of the axis through its fingers there (the same contact problem), and g*'s own
    # energy is that minimum to the equilibrium search's accuracy
    SIGMA[0] = sigma
    pe = PlacementEnergy(mesh, fingers, solver=res.solver)
    ax = _axis_through_fingers(pe, rel.equilibrium, res.solver.centroid)
    curve = res.solver.curve(ax, pad, sigma)
    U_eq = float(curve.energy_at(sigma))
    a_w = (np.asarray(fingers[1].center) - fingers[0].center) / np.linalg.norm(
        np.asarray(fingers[1].center) - fingers[0].center)
    E_axis = _float_min(pe, rel.equilibrium, a_w, *_squeeze_range(pe, rel.equilibrium, curve, a_w))
    assert E_axis == pytest.approx(U_eq, rel=1e-6)
    assert U_eq * (1 - 1e-9) <= rel.energy <= U_eq * (1 + 1e-4)
    U_s = float(res.start_curve.energy_at(sigma))
    assert rel.energy <= U_s * (1 + 1e-9)                # the equilibrium is a minimum
    # the pads' error at σ: the library's noise floor (jitter of the start axis' energy
    # under sub-cell moves, relative) times the barrier's height
    start = GraspAxis.at(axis.point, axis.angle, res.solver.centroid)
    tau = jitter_noise(res.solver, pad, start, res.grid.d_offset, res.grid.d_angle, res.sigma_L)(sigma)
    pads_err = tau * (U_s + U_pads)
    assert (rel.U_A > rel.U_A_error) == held == (U_pads > pads_err)
    assert abs(rel.U_A - U_pads) <= rel.U_A_error + pads_err, (rel.U_A, rel.U_A_error, U_pads, pads_err)
    if held:
        assert rel.target == "released" and rel.deform_closure
        # the estimates are tight enough to mean something: a few % of U_A
        assert rel.U_A_error + pads_err <= 0.1 * U_pads


def test_disc_gap_behind_in_buried_material_is_the_pad_profile():
    """Behind the disc (``s < −r``; in front: tests/test_finger_methods.py), in material the
    disc is buried in (pressed more than its diameter), the kernel's gap of a boundary node
    is still the pad's (SPEC §6, :meth:`Pad.profile`): the distance along the axis to the
    surface at the node's cross coordinate, per unit gradient, within the reach; not
    enforced beyond it. Before issue 19's fix it was the radial distance: free."""
    from deformclosure.dspace.placement_energy import _body_sd

    r = 2e-3
    pad = Pad(0.0, r)
    ang = 0.3
    a, n = np.array([math.cos(ang), math.sin(ang)]), np.array([-math.sin(ang), math.cos(ang)])
    centre = np.array([1e-3, -2e-3])
    kind, par, _, _ = DiscFinger(tuple(centre), r).kernel_encoding(a)
    assert par[5] == pytest.approx(pad.reach, rel=1e-15)
    # a 40 × 40 mm square around the disc: every point below is inside it, its boundary
    # facing the disc (inward normal along the axis)
    sq = centre + 0.02 * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
    e = np.roll(sq, -1, axis=0) - sq
    en = np.c_[-e[:, 1], e[:, 0]] / np.linalg.norm(e, axis=1)[:, None]       # inward (CCW)
    part = (sq, np.arange(4), np.roll(np.arange(4), -1), en, (e * e).sum(1), np.roll(np.arange(4), 1),
            np.arange(4), np.ones(4, bool))
    rng = np.random.default_rng(7)
    empty = np.zeros((0, 2))
    for _ in range(400):
        s, x = rng.uniform(-3 * r, -r), rng.uniform(-1.2 * r, 1.2 * r)
        p = centre + s * a + x * n
        sd, ox, oy = _body_sd(kind, par, 0, 0, empty, empty, np.zeros(0), p[0], p[1], a[0], a[1], part)
        d, slope = pad.profile(np.array([x]))
        if not np.isfinite(d[0]):
            assert math.isinf(sd)
            continue
        gap = (s - r) + d[0]                          # pad face at s = r from the centre
        assert sd == pytest.approx(gap / math.hypot(1.0, slope[0]), rel=1e-12, abs=1e-15)
        # the force on the part along the pad's normal there (pad A's row gradient)
        assert np.allclose([ox, oy], (a + slope[0] * n) / math.hypot(1.0, slope[0]), atol=1e-12)


def test_builtin_notched_bar_at_sigma_star():
    """The built-in notched bar between round 2 mm pads at optimize's σ*: the way out sinks
    a pad 3 mm into the 12 mm wide bar (beyond half the inscribed radius, the depth limit
    a disc had): check's U_A was ∞ (a "cage"); now optimize's within the two error
    estimates (check's, and the pads' noise floor at σ* times the barrier's height)."""
    from deformclosure import notched_part

    part = notched_part()
    mesh = mesh_part(part)
    axis, pad = GraspAxis(math.pi / 2, -0.015), Pad(0.0, RHO * MM)
    res = optimize_pads(mesh, axis, pad, twin=PadContact(twin_mesh(part)), n_curve=3)
    sigma = res.sigma_star
    assert res.quality > 0 and math.isfinite(res.U_A)          # one mesh: "undecided"
    sc = res.start_curve
    a = sc.axis.direction
    face = np.asarray(sc.axis.origin) + sc.touch.z_a * a + sc.axis.offset * sc.axis.normal
    za = face + 0.5 * (sc.sigma0 - sigma) * a
    fingers = [DiscFinger(tuple(za - pad.radius * a), pad.radius),
               DiscFinger(tuple(za + (sigma + pad.radius) * a), pad.radius)]
    rel = release_energy_fingers(mesh, fingers, part=part, solver=res.solver)
    pads_err = res.noise_relative * (float(sc.energy_at(sigma)) + res.U_A)
    assert rel.deform_closure and rel.target == "released"
    assert abs(rel.U_A - res.U_A) <= rel.U_A_error + pads_err, (rel.U_A, rel.U_A_error, res.U_A, pads_err)
