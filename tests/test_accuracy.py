"""Pads answers to a stated accuracy (SPEC §6 "Accuracy by default", issue 20).

* Verdicts by contact-mechanics fact at the *default* settings (``--rtol 0.05``,
  adaptive): a convex part between frictionless pads is never held, at any rtol; round
  pads seated in notches hold; on an asymmetric notched part the notch axis — off the
  part's symmetry line — holds and a parallel axis through the flat faces does not.
* Error estimates are claims: on three parts and for rtol 0.2, 0.1 and 0.05, the reported
  error of ``quality``, ``U_A`` and ``sigma_star`` bounds the difference to a finer
  reference — the finest level's own mesh refined once more uniformly (every element's
  area / 4) and the landscape around the saddles twice more (factor × 4) — in at least
  90 % of the quantities; and the converged Q* of two rtols differ by no more than their
  estimates together.
* The pieces: the recovered-strain indicator vanishes on a uniform strain and is largest
  at a notch root; the saddle-refined grid is a symmetric graph whose coarse part is the
  coarse grid; the sizing field meshes to its areas.
"""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import deformclosure as dc
from deformclosure import reports
from deformclosure.jsonfile import Source
from deformclosure.elasticity.error import bulk_marking, recovered_strain_indicator
from deformclosure.mesh.generate import twin_mesh
from deformclosure.mesh.sizing import Sizing
from deformclosure.pads import GraspAxis, Pad, PadContact, pad_grasp
from deformclosure.pads.landscape import AxisGrid
from deformclosure.pads.refine import level_error, solve_level
from deformclosure.pads.saddle_grid import SaddleRefinedGrid

MM = 1e-3
RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 0.002,
          "elastic_limit_strain": 0.8, "plane": "stress"}
GRID = dict(n_angles=16, n_offsets=20)          # a coarse base landscape keeps this fast


def _block(L: float, H: float, notches=(), r: float = 1.5, k: int = 12, max_area: float = 0.8,
           name: str = "block") -> dc.Part:
    """An L × H mm block; ``notches``: x positions (mm) of facing round notches of radius
    ``r`` mm in its bottom and top faces (``(x_bottom, x_top)`` pairs)."""
    bottom, top = [[0.0, 0.0]], [[L, H]]
    for xb, _ in sorted(notches):
        t = np.linspace(np.pi, 0.0, k + 1)
        bottom += [[xb + r * np.cos(a), r * np.sin(a)] for a in t]
    bottom.append([L, 0.0])
    for _, xt in sorted(notches, key=lambda n: -n[1]):
        t = np.linspace(np.pi, 0.0, k + 1)
        top += [[xt - r * np.cos(a), H - r * np.sin(a)] for a in t]
    top.append([0.0, H])
    return dc.Part.from_dict({"name": name, "units": "mm",
                              "outer": np.round(bottom + top, 9).tolist(), "holes": [],
                              "material": RUBBER, "mesh": {"max_area": max_area, "min_angle": 30}})


def _axis(p, q) -> GraspAxis:
    return GraspAxis.through(np.array(p) * MM, np.array(q) * MM)


# ----------------------------------------------------------------------------- verdicts


def _optimize(part: dc.Part, at, radius: float, **extra) -> dict:
    """``optimize`` at its default settings (but a coarser landscape and a 600 s budget),
    the part given as the bytes of its part file (SI), lengths here in mm.

    The default budget (120 s of wall time) is left out: these tests are about the verdict
    and the refinement, and a loaded machine (two test workers on two cores, other jobs)
    can spend it on the first level, which ends the refinement there (``"none"``)."""
    params = {"at": tuple(f"{x},{y}" for x, y in at), "pad_radius": radius, "units": "mm",
              "grid_angles": 24, "grid_offsets": 30, "max_seconds": 600, **extra}
    src = Source(f"{part.name}.json", json.dumps(part.to_dict()).encode())
    return reports.run("optimize", src, params).data


@pytest.mark.slow
@pytest.mark.parametrize("rtol", [None, 0.2])
def test_a_convex_part_between_frictionless_pads_is_never_held(rtol):
    extra = {} if rtol is None else {"rtol": rtol}
    for part, at in [(_block(12, 20, max_area=1.0), [(0, 10), (12, 10)]),
                     (_block(12, 20, max_area=1.0), [(0, 4), (12, 13)])]:
        d = _optimize(part, at, 1.0, **extra)
        assert d["verdict"] != "held", d["convergence"]
        assert d["refinement"] == "adaptive" and d["rtol"] == (0.05 if rtol is None else rtol)


@pytest.mark.slow
def test_round_pads_in_notches_hold_and_the_asymmetric_notch_axis_is_the_one():
    part = _block(24, 10, notches=[(8.0, 8.0)], name="asymmetric")   # symmetry line x = 12
    notch = _optimize(part, [(8, 0), (8, 10)], 1.2)
    assert notch["verdict"] == "held" and notch["converged"], notch["convergence"]
    assert notch["error_estimate"]["quality"] <= 0.05 * notch["quality"]
    # the parallel axis on the symmetry line meets only flat faces: a shift lowers it
    flat = _optimize(part, [(14, 0), (14, 10)], 1.2)
    assert flat["verdict"] != "held"


# ----------------------------------------------------------------------------- honesty

PARTS = {
    # name: (part, axis points (mm), pad radius (mm))
    "notched block": (_block(20, 8, notches=[(10.0, 10.0)]), ([10, 0], [10, 8]), 1.0),
    "asymmetric notches": (_block(24, 10, notches=[(8.0, 8.0)]), ([8, 0], [8, 10]), 1.2),
    "notched bar": (dc.notched_part(), ([15, 0], [15, 12]), 2.0),
}


@functools.lru_cache(maxsize=None)
def _run(name: str, rtol: float):
    part, (p, q), rho = PARTS[name]
    return pad_grasp(part, _axis(p, q), Pad(0.0, rho * MM), rtol=rtol, max_seconds=600, **GRID)


@functools.lru_cache(maxsize=None)
def _reference(name: str, area_factor: float = 4.0):
    """The finest level of the rtol 0.05 run refined uniformly: every element's area /
    ``area_factor`` (4: ``h`` halved; its twin alike), and the landscape two levels finer
    (factor × 4) around every saddle found, by the levels' own rule (:func:`solve_level`).
    Two mesh levels (16) take 13 minutes for the three parts, so they are the opt-in
    ``tests/test_accuracy_reference.py``."""
    part, (p, q), rho = PARTS[name]
    run = _run(name, 0.05)
    mesh = run.finest.solver.mesh
    default = float(mesh.areas.max()) / area_factor
    sizing = Sizing(default, points=mesh.nodes[mesh.triangles].mean(axis=1),
                    areas=mesh.areas / area_factor)
    ref_mesh = dc.mesh_part(part, max_area=default, sizing=sizing)
    twin = twin_mesh(part, max_area=default, sizing=sizing)
    return solve_level(ref_mesh, twin, _axis(p, q), Pad(0.0, rho * MM), len(run.levels) + 1,
                       list(run.saddles), None, GRID)


def _quantities(res) -> dict:
    return {"quality": res.quality, "U_A": res.U_A, "sigma_star": res.sigma_star}


def bracketing_failures(area_factor: float) -> tuple[int, list]:
    """``(checked, failures)``: the quantities of the three parts at rtol 0.2, 0.1, 0.05
    whose reported error does not bound the difference to :func:`_reference` with this
    ``area_factor``; prints the table (shown with ``-s``)."""
    checked, failures = 0, []
    for name in PARTS:
        ref = _quantities(_reference(name, area_factor))
        assert ref["quality"] > 0, name                   # the parts are held: values to check
        for rtol in (0.2, 0.1, 0.05):
            run = _run(name, rtol)
            err, val = run.error_estimate(), _quantities(run.finest)
            for key in ("quality", "U_A", "sigma_star"):
                checked += 1
                e = err[key]
                print(f"{name:20} rtol {rtol:<4} {key:10} {val[key]} ± {e}  reference {ref[key]}")
                if e is None or val[key] is None or abs(val[key] - ref[key]) > e:
                    failures.append((name, rtol, key, val[key], ref[key], e))
    return checked, failures


@pytest.mark.slow
def test_error_estimates_bound_the_difference_to_a_much_finer_reference():
    checked, failures = bracketing_failures(4.0)
    assert len(failures) <= 0.1 * checked, failures


@pytest.mark.slow
def test_the_converged_qualities_of_two_rtols_agree_within_their_estimates():
    for name in PARTS:
        a, b = _run(name, 0.2), _run(name, 0.05)
        ea, eb = a.error_estimate()["quality"], b.error_estimate()["quality"]
        assert abs(a.finest.quality - b.finest.quality) <= ea + eb, name
        assert b.converged and len(b.levels) >= len(a.levels)


# ----------------------------------------------------------------------------- pieces


def test_the_indicator_vanishes_on_a_uniform_strain_and_peaks_at_a_notch_root():
    part = _block(20, 8, notches=[(10.0, 10.0)])
    mesh = dc.mesh_part(part)
    rng = np.random.default_rng(1)
    G = rng.normal(size=(2, 2)) * 1e-3
    u = mesh.nodes @ G.T + rng.normal(size=2) * 1e-4          # affine: recovered exactly
    assert recovered_strain_indicator(mesh, u).max() < 1e-12 * np.abs(u).max() ** 2 * 2e6
    # squeeze through the notches: the indicator's largest elements sit at the roots
    axis = _axis([10, 0], [10, 8])
    solver = PadContact(mesh)
    curve = solver.curve(axis, Pad(0.0, 1e-3), 0.5 * 5e-3)
    lam = curve.path.multipliers(curve.delta(0.5 * (curve.sigma0 + curve.sigma_end)))
    u = solver.displacement(solver.load_vector(curve, lam))
    eta2 = recovered_strain_indicator(mesh, u)
    top = np.argsort(eta2)[-5:]
    c = mesh.nodes[mesh.triangles[top]].mean(axis=1)
    assert np.all(np.abs(c[:, 0] - 0.010) < 3e-3)             # under the pads, at the notches


# subnormal indicators excluded: θ·Σ of a lone 5e-324 underflows to 0 (found by hypothesis)
@given(st.lists(st.floats(0.0, 1e3, allow_subnormal=False), min_size=1, max_size=40),
       st.floats(0.05, 1.0))
def test_bulk_marking_is_the_smallest_set_with_the_share(eta2, theta):
    eta2 = np.array(eta2)
    marked = bulk_marking(eta2, theta)
    total = eta2.sum()
    if total == 0:
        assert not marked.any()
        return
    assert eta2[marked].sum() >= theta * total * (1 - 1e-12)
    # no smaller set reaches it: the largest k-1 fall short
    k = int(marked.sum())
    assert np.sort(eta2)[::-1][:k - 1].sum() < theta * total


@settings(max_examples=25, deadline=None)
@given(st.integers(2, 5), st.sampled_from([1, 2, 4]), st.integers(0, 1000))
def test_the_saddle_refined_grid_is_a_symmetric_graph_over_the_coarse_grid(n_angles, f, seed):
    rng = np.random.default_rng(seed)
    base = AxisGrid.around(GraspAxis(0.3, 0.002, (0.0, 0.0)), 0.01, 0.02, n_angles, 6)
    centres = [base.axis(int(v)) for v in rng.integers(0, base.size, 2)]
    g = SaddleRefinedGrid.around(base, f, centres)
    coarse = {g.vertex(*base.cell(v)) for v in range(base.size)}
    verts = coarse | set(g.patch)
    for v in verts:
        nb = g.neighbours(v)
        assert len(nb) == len(set(nb)) and v not in nb
        for w in nb:
            assert w in verts and v in g.neighbours(w)                 # symmetric
            assert g.axis(w) is not None
    if f == 1:   # no refinement: the coarse grid itself
        for v in range(base.size):
            assert sorted(g.neighbours(v)) == sorted(base.neighbours(v))
    # the start's strictness test keeps the coarse neighbours
    s = g.vertex(0, 0)
    assert sorted(g.start_neighbours(s)) == sorted(g.vertex(*base.cell(w))
                                                   for w in base.neighbours(base.vertex(0, 0)))


def test_the_sizing_field_meshes_to_its_areas():
    part = _block(20, 8, notches=[(10.0, 10.0)])
    disc = (0.010, 0.0015, 0.002, 2e-8)
    s = Sizing(4e-7, (disc,))
    mesh = dc.mesh_part(part, max_area=4e-7, sizing=s)
    c = mesh.nodes[mesh.triangles].mean(axis=1)
    assert np.all(mesh.areas <= s(c) * (1 + 1e-9))
    near = np.hypot(c[:, 0] - disc[0], c[:, 1] - disc[1]) < disc[2]
    assert near.sum() > 20 and mesh.areas[near].max() <= 2e-8 * (1 + 1e-9)


def test_level_error_is_never_below_the_last_change():
    assert level_error([1.0]) is None
    assert level_error([1.0, 1.5]) == pytest.approx(0.5)
    assert level_error([1.0, 1.5, 1.6]) >= 0.1
    assert level_error([1.0, 1.5, 1.2]) >= 0.3          # not monotone: no credit
    assert level_error([math.inf, math.inf]) == 0.0 and level_error([1.0, math.inf]) == math.inf
