"""Pad grasps (SPEC §6): contact-mechanics verdicts, exact σ*, convergence, Richardson.

The verdicts are facts of frictionless contact, not outputs of this code: a convex part
between frictionless pads slides out wherever a sideways shift keeps or shortens the
chord (a block, an ellipse squeezed across its short axis); pads seated in notches hold.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import deformclosure as dc
from deformclosure.pads import GraspAxis, Pad, PadContact, optimize_pads, pad_grasp, richardson
from deformclosure.pads.landscape import Landscape
from deformclosure.mesh.generate import twin_mesh
from deformclosure.planning.pads import plan_pads

MM = 1e-3
RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0, "elastic_limit_strain": 0.8}
NOTCHED = [[0, 0], [12, 0], [15, 3], [18, 0], [30, 0], [30, 12], [18, 12], [15, 9], [12, 12], [0, 12]]
# No mirror line: two 60° V-notches whose bisectors lie on one line tilted 30° from the
# vertical, roots at (12, 3) and (15.46, 9) mm.
SKEWED = [[0, 0], [6.803848, 0], [12, 3], [12, 0], [30, 0], [30, 12], [20.660254, 12],
          [15.464102, 9], [15.464102, 12], [0, 12]]


def _part(outer, max_area, material=RUBBER):
    return dc.Part.from_dict({"name": "p", "units": "mm", "outer": outer, "material": material,
                              "mesh": {"max_area": max_area}})


def _ellipse(a, b, n=96):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([a * np.cos(t), b * np.sin(t)]).round(6).tolist()


def _solve(part, p, q, pad):
    mesh = dc.mesh_part(part)
    return optimize_pads(mesh, GraspAxis.through(np.array(p) * MM, np.array(q) * MM), pad,
                         twin=PadContact(twin_mesh(part)))


@pytest.mark.parametrize("pad", [Pad(0.0, 1 * MM), Pad(4 * MM, 1 * MM)], ids=["round", "flat"])
def test_block_between_pads_is_not_held(pad):
    """A block between frictionless pads can slide out along its faces (SPEC §3, §6)."""
    r = _solve(_part([[0, 0], [12, 0], [12, 20], [0, 20]], 0.1), [0, 10], [12, 10], pad)
    assert r.verdict == "not held" and r.quality == 0.0 and r.sigma_star is None


def test_ellipse_across_its_short_axis_is_not_held():
    """Squeezed across its shortest chord a convex part is stable against turning but a
    sideways shift shortens the chord: the pads push it out."""
    r = _solve(_part(_ellipse(10, 6), 0.1), [0, -6], [0, 6], Pad(0.0, 2 * MM))
    assert r.verdict == "not held"


def test_pads_seated_in_notches_hold_with_a_resolved_barrier():
    """Pads seated in notches hold (SPEC §6), on one mesh that resolves the contacts
    (``h ≤ ℓ/2`` there: the first level's sizing, :func:`first_sizing`); the same grasp on
    the uniform 0.2 mm² mesh, whose contact elements are larger, decides nothing."""
    from deformclosure.pads.adapt import first_sizing

    part = _part(NOTCHED, 0.2)
    axis = GraspAxis.through(np.array([15, 0]) * MM, np.array([15, 12]) * MM)
    pad = Pad(0.0, 2 * MM)
    coarse = _solve(part, [15, 0], [15, 12], pad)
    assert coarse.quality > 0 and coarse.unresolved and coarse.verdict == "undecided"
    sizing = first_sizing(part, axis, pad, 0.2e-6)
    mesh = dc.mesh_part(part, max_area=sizing.default, sizing=sizing)
    r = optimize_pads(mesh, axis, pad, twin=PadContact(twin_mesh(part)))
    assert r.resolves and r.verdict == "held"
    assert r.U_A > 100 * r.noise, (r.U_A, r.noise)
    # The escape climbs out of the notch: the pads end up off it, not squeezed deeper.
    assert len(r.escape_path) >= 2
    assert abs(r.escape_path[-1].point[0] - 15 * MM) > 1.5 * MM


@pytest.fixture(scope="module")
def notched_coarse():
    part = _part(NOTCHED, 0.4)
    mesh = dc.mesh_part(part)
    pc = PadContact(mesh)
    res = optimize_pads(mesh, GraspAxis.through([15 * MM, 0], [15 * MM, 12 * MM]), Pad(0, 2 * MM),
                        solver=pc, noise=False)
    return mesh, pc, res


@pytest.mark.slow
def test_exact_sigma_star_equals_dense_sampling(notched_coarse):
    """Q evaluated by its definition on 3000 separations never exceeds the exact Q*, and
    comes within one sample step's variation of it."""
    mesh, pc, res = notched_coarse
    pad, grid = res.pad, res.grid
    land = Landscape(pc, pad, grid, res.sigma_L)
    s = grid.vertex(0, 0)
    Us = res.start_curve.energy_at
    U_sL = Us(res.sigma_L)
    sig = np.linspace(res.sigma_L, res.sigma0, 3000)
    Q = np.array([min(land.release(s, x).U_A, U_sL - Us(x)) for x in sig])
    k = int(np.argmax(Q))
    assert Q[k] <= res.quality * (1 + 1e-9)
    step = sig[1] - sig[0]
    slope = np.max(np.abs(np.diff(Q))) / step
    assert res.quality - Q[k] <= slope * step + 1e-12, (res.quality, Q[k])
    # And Q at σ* by definition is the reported quality.
    q_star = min(land.release(s, res.sigma_star).U_A, U_sL - Us(res.sigma_star))
    assert q_star == pytest.approx(res.quality, rel=1e-9)


@pytest.mark.slow
def test_asymmetric_part_best_axis_is_not_on_a_symmetry_line():
    """Notches cut along a line tilted 30° from the vertical, in a bar with no mirror line:
    the planner's best closing axis runs along the notches' common bisector (60° from the
    x axis), found from the whole (θ, c) grid, and beats every axis at 0° or 90°."""
    part = _part(SKEWED, 0.4)
    mesh = dc.mesh_part(part)
    plan = plan_pads(mesh, Pad(0, 1.5 * MM), n_angles=36, n_offsets=40, top=3,
                     twin=PadContact(twin_mesh(part)))
    best = plan.rows[0]
    # verified on this one mesh (no part given: no refinement): a barrier, "undecided"
    # unless the mesh resolves the contacts
    assert best["verdict"] in ("held", "undecided") and best["quality"] > 0
    assert best["verified"] and best["method"] == "exact"
    ang = math.degrees(best["angle"]) % 180
    assert 50 < ang < 70, ang
    ca, cb = np.array(best["contacts"]) / MM
    roots = np.array([[12, 3], [15.464102, 9]])
    assert np.linalg.norm(ca - roots[0]) < 3.5 and np.linalg.norm(cb - roots[1]) < 3.5, (ca, cb)
    square = [r for r in plan.rows
              if min(abs(math.degrees(r["angle"]) % 180 - a) for a in (0, 90, 180)) < 1]
    # on the same screening lattice (a verified row's own value is from finer levels)
    screened = best["lattice_quality"]
    assert square and all(r.get("lattice_quality", r["quality"]) < 0.5 * screened
                          for r in square)


def test_richardson_recovers_an_analytic_sequence():
    """Q(h) = Q∞ + C h^p on h, h/2, h/4: the extrapolation and the order are exact."""
    for p in (1.0, 1.7, 2.0):
        vals = [3.0 + 0.4 * (0.5**k) ** p for k in range(3)]
        ext, err, order = richardson(vals)
        assert ext == pytest.approx(3.0, rel=1e-12)
        assert order == pytest.approx(p, rel=1e-12)
        assert err == pytest.approx(abs(vals[-1] - 3.0), rel=1e-9)
    ext, err, order = richardson([1.0, 1.1])
    assert (ext, order) == (pytest.approx(1.2), None) and err == pytest.approx(0.1)


SHORT_BAR = [[0, 0], [7.5, 0], [10, 2.5], [12.5, 0], [24, 0], [24, 10], [12.5, 10], [10, 7.5],
             [7.5, 10], [0, 10]]
STIFFER = dict(RUBBER, poisson_ratio=0.3, elastic_limit_strain=0.6)
# ℓ = 1.5 mm: the flat pads' corner strains are resolved by the base mesh (SPEC §6 lets a
# material state its critical distance).
WITH_ELL = dict(RUBBER, critical_distance=1.5)

CONVERGENCE = [
    ("notched bar, round pads", NOTCHED, RUBBER, 0.2, [15, 0], [15, 12], Pad(0, 2 * MM)),
    ("skewed notches", SKEWED, RUBBER, 0.2, [12, 3], [15.464102, 9], Pad(0, 1.5 * MM)),
    ("short bar", SHORT_BAR, STIFFER, 0.15, [10, 0], [10, 10], Pad(0, 1.5 * MM)),
    ("notched bar, flat pads", NOTCHED, WITH_ELL, 0.2, [15, 0], [15, 12], Pad(2 * MM, 1 * MM)),
]


@pytest.mark.slow
@pytest.mark.parametrize("name,outer,material,area,p,q,pad", CONVERGENCE,
                         ids=[c[0] for c in CONVERGENCE])
def test_quality_and_sigma_star_converge(name, outer, material, area, p, q, pad):
    """Three uniform levels (h halved, the landscape refined around the saddles): held on
    every level, and the reported estimate is Richardson's, never below the last change.

    (With the grid of axes fixed, these sequences shrank monotonically to < 5 % of Q*; with
    the landscape refined too, Q* of the flat pads falls 17.8 → 18.0 → 14.0 mJ and of the
    skewed notches 2.84 → 2.53 → 2.29 mJ: the grid error a fixed grid hid, SPEC §6, and the
    estimates say so — issue 20 keeps it open.)"""
    part = _part(outer, area, material)
    res = pad_grasp(part, GraspAxis.through(np.array(p) * MM, np.array(q) * MM), pad, refine=3)
    Q = [r.quality for r in res.levels]
    S = [r.sigma_star for r in res.levels]
    assert res.verdict == "held" and all(s is not None for s in S), (Q, S)
    dQ = np.abs(np.diff(Q))
    ext, err, _ = richardson(Q)
    assert ext - err <= Q[-1] <= ext + err
    est = res.error_estimate()
    # the estimate is Richardson's, never less than the last change (pads.refine)
    assert est["quality"] == pytest.approx(max(err, dQ[1])) and est["sigma_star"] is not None
    assert est["sigma_star"] >= abs(S[-1] - S[-2])


# --------------------------------------------------------------------------- expanding
PLATE = [[0, 0], [30, 0], [30, 20], [0, 20]]
PLATE_MAT = dict(RUBBER, poisson_ratio=0.3, elastic_limit_strain=0.5)


def _plate(hole, area=0.2):
    return dc.Part.from_dict({"name": "plate", "units": "mm", "outer": PLATE, "holes": [hole],
                              "material": PLATE_MAT, "mesh": {"max_area": area}})


def _expand(part, p, q, pad):
    mid = 0.5 * (np.array(p) + np.array(q)) * MM
    return pad_grasp(part, GraspAxis.through(np.array(p) * MM, np.array(q) * MM), pad,
                     expanding_from=mid).finest


@pytest.mark.slow
def test_pads_opening_into_the_corners_of_a_rhombus_hole_hold():
    """Opened along the long diagonal, round pads sit in the acute corners: a sideways
    shift or a turn shortens the chord, so the pads must squeeze harder to leave."""
    part, pad = _plate([[8, 10], [15, 13], [22, 10], [15, 7]]), Pad(0, 1 * MM)
    r = _expand(part, [8, 10], [22, 10], pad)
    assert r.start_curve.expanding and r.sigma_star > r.sigma0 and r.sigma_L > r.sigma_star
    assert r.verdict in ("held", "undecided") and r.U_A > 50 * r.noise     # one mesh
    # the verdict itself from the refinement to an accuracy (SPEC §6)
    refined = pad_grasp(part, GraspAxis.through(np.array([8, 10]) * MM, np.array([22, 10]) * MM),
                        pad, expanding_from=np.array([15, 10]) * MM, rtol=0.2)
    assert refined.verdict == "held", refined.convergence()


ROUND_HOLE = (np.array(_ellipse(4, 4, 64)) + [15, 10]).round(6).tolist()


@pytest.mark.parametrize("hole,p,q,pad", [
    ([[10, 5], [20, 5], [20, 15], [10, 15]], [10, 10], [20, 10], Pad(4 * MM, 2 * MM)),
    (ROUND_HOLE, [11, 10], [19, 10], Pad(0, 1 * MM)),
], ids=["square hole, flat pads", "round hole"])
def test_pads_opening_in_a_hole_they_can_slide_or_turn_in_do_not_hold(hole, p, q, pad):
    """Flat pads on the parallel walls of a square hole slide along them; round pads in a
    round hole turn freely about its centre."""
    assert _expand(_plate(hole), p, q, pad).verdict == "not held"


def test_expanding_curve_is_an_exact_contact_solution():
    """Opening curves obey what any frictionless contact solution must: U ≥ 0, increasing
    and convex in σ beyond σ0, dU/dσ = F on every piece (envelope), U = ½ Σ f·u."""
    part = _plate([[8, 10], [15, 13], [22, 10], [15, 7]], area=0.4)
    mesh = dc.mesh_part(part)
    pc = PadContact(mesh)
    from deformclosure.pads.contact import hole_containing
    hole = hole_containing(mesh, [0.015, 0.010])
    for ang, pad in ((0.0, Pad(0, 1 * MM)), (0.3, Pad(1 * MM, 0.8 * MM))):
        c = pc.curve(GraspAxis.at([0.015, 0.010], ang), pad, 0.020, hole)
        assert c.expanding and c.path is not None
        sig = np.linspace(c.sigma0, c.sigma_end, 301)
        U = c.energy(sig)
        assert np.all(U >= 0) and np.all(np.diff(U) >= -1e-15) and np.all(np.diff(U, 2) >= -1e-12 * U.max())
        k = c.kinks()
        mids = 0.5 * (k[:-1] + k[1:])
        h = 1e-7 * (c.sigma_end - c.sigma0)
        for m in mids[np.diff(k) > 4 * h]:
            dU = (c.energy_at(m + h) - c.energy_at(m - h)) / (2 * h)
            assert dU == pytest.approx(c.axial_force(m), rel=1e-5)
        m = float(mids[-1])
        lam = c.path.multipliers(c.delta(m))
        f = pc.load_vector(c, lam)
        assert 0.5 * f @ pc.displacement(f) == pytest.approx(c.energy_at(m), rel=1e-9)


def test_capped_release_gives_the_same_quality(notched_coarse):
    """Landscape.release with a cap (the finite-strain σ*-search's ``cap = U_L``): where it
    stops early its U_A is a lower bound above the cap and below the full search's; where it
    does not, it is the full search's result; so min(U_A, cap) is the same either way."""
    mesh, pc, res = notched_coarse
    s = res.grid.vertex(0, 0)
    full = Landscape(pc, res.pad, res.grid, res.sigma_L)
    capped = Landscape(pc, res.pad, res.grid, res.sigma_L)
    n_bounded = 0
    for x in np.linspace(res.sigma_L, res.sigma0, 9)[1:-1]:
        ref = full.release(s, float(x))
        for frac in (0.05, 0.5, 0.95, 2.0):
            cap = frac * ref.U_A if np.isfinite(ref.U_A) and ref.U_A > 0 else frac * 1e-3
            r = capped.release(s, float(x), 0.0, cap)
            if r.bounded:
                n_bounded += 1
                assert cap < r.U_A <= ref.U_A and r.path == [] and r.saddle is None
            else:
                assert (r.U_A, r.path, r.saddle) == (ref.U_A, ref.path, ref.saddle)
            assert min(r.U_A, cap) == min(ref.U_A, cap)
    assert n_bounded > 0
