"""Grasp planner: the shared lattice equals the per-pair ε-approximation on the same
lattice, the refined quality is never below it; the per-pair e_max of the block solve
equals the single-pair computation. (The per-pair ε guarantee against the exact method:
tests/test_plan_eps.py.)"""

from __future__ import annotations

import json

import numpy as np
import pytest

import deformclosure as dc
from deformclosure.cli.main import main
from deformclosure.errors import GraspError
from deformclosure.grasp.analysis import optimize_separation
from deformclosure.grasp.elastic_limit import elastic_limit
from deformclosure.grasp.separation import optimize_separation_arrays
from deformclosure.planning.plan import lattice, plan_grasps

MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0, "elastic_limit_strain": 0.8}

SHAPES = {
    "rectangle": ([[0, 0], [12, 0], [12, 20], [0, 20]], [], 8.0),
    "l_shape": ([[0, 0], [20, 0], [20, 8], [8, 8], [8, 20], [0, 20]], [], 10.0),
    "holed": ([[0, 0], [16, 0], [16, 12], [0, 12]], [[[6, 4], [6, 8], [10, 8], [10, 4]]], 8.0),
}


def _mesh(name):
    outer, holes, area = SHAPES[name]
    return dc.mesh_part(dc.Part.from_dict({"units": "mm", "outer": outer, "holes": holes,
                                           "material": MAT,
                                           "mesh": {"max_area": area, "min_angle": 28}}))


@pytest.mark.parametrize("name,mode", [("rectangle", "contracting"), ("l_shape", "contracting"),
                                       ("holed", "expanding")])
def test_plan_quality_equals_per_pair_approx(name, mode):
    mesh = _mesh(name)
    plan = plan_grasps(mesh, mode=mode, top=0, n_sigma=120)
    model = plan.model
    rng = np.random.default_rng(3)
    for i in rng.choice(len(plan.pairs), size=min(25, len(plan.pairs)), replace=False):
        a, b = (int(v) for v in plan.pairs[i])
        s = model.graph.vertex_index(a, b)
        ref = optimize_separation_arrays(model.stiffness.sigma0, model.stiffness.k, model.graph,
                                         s, plan.sigma_L[i], mode=mode, method="approx",
                                         eps=plan.epsilon, grid="lattice",
                                         lipschitz=plan.lipschitz)
        assert plan.lattice_quality[i] == pytest.approx(ref.quality, rel=1e-9, abs=1e-18)
        # The reported quality refines the lattice value, within ε of the optimum.
        assert plan.quality[i] >= plan.lattice_quality[i] * (1 - 1e-9)
        assert plan.quality[i] <= plan.quality_upper[i] <= plan.quality[i] + plan.epsilon
    # Ranking: qualities are sorted, every pair of the graph is present exactly once.
    assert np.all(np.diff(plan.quality) <= 0)
    assert len({tuple(p) for p in plan.pairs.tolist()}) == model.graph.n_vertices


def test_plan_e_max_matches_single_pair_solution():
    mesh = _mesh("l_shape")
    plan = plan_grasps(mesh, top=0, n_sigma=20)
    for i in np.random.default_rng(0).choice(len(plan.pairs), 8, replace=False):
        a, b = (int(v) for v in plan.pairs[i])
        lim = elastic_limit(mesh, plan.model.condensed, a, b)
        assert plan.e_max[i] == pytest.approx(lim.e_max, rel=1e-9)
        assert plan.sigma_L[i] == pytest.approx(lim.sigma_L, rel=1e-9, abs=1e-15)


def test_plan_e_max_matches_single_pair_solution_for_wide_jaws():
    """Finite-width jaws load several nodes per jaw; the planner's kernel must sum them
    exactly like the single-pair solve."""
    mesh = _mesh("rectangle")
    width = 2.5e-3
    plan = plan_grasps(mesh, top=0, n_sigma=10, jaw_width=width)
    for i in np.random.default_rng(1).choice(len(plan.pairs), 8, replace=False):
        a, b = (int(v) for v in plan.pairs[i])
        lim = elastic_limit(mesh, plan.model.condensed, a, b, jaw_width=width)
        assert plan.e_max[i] == pytest.approx(lim.e_max, rel=1e-9)


def test_refined_top_pairs_are_exact_and_not_worse_than_lattice():
    mesh = _mesh("rectangle")
    plan = plan_grasps(mesh, top=3, n_sigma=150)
    assert 1 <= len(plan.refined) <= 3
    for r in plan.refined:
        ex = optimize_separation(mesh, r.jaws, method="exact", model=plan.model)
        assert r.quality == pytest.approx(ex.quality, rel=1e-12)
        i = next(j for j, p in enumerate(plan.pairs.tolist()) if sorted(p) == sorted(r.jaws))
        # The exact supremum is never below a sampled value; the plan reports it.
        assert r.quality >= plan.lattice_quality[i] * (1 - 1e-9)
        assert plan.exact[i] and plan.quality[i] == r.quality
    assert np.all(np.diff(plan.quality) <= 0) and plan.exact[: len(plan.refined)].all()


def test_filters_restrict_pairs():
    mesh = _mesh("rectangle")
    full = plan_grasps(mesh, top=0, n_sigma=10)
    rng_plan = plan_grasps(mesh, top=0, n_sigma=10, separation_range=(0.010, 0.015))
    assert 0 < len(rng_plan.pairs) < len(full.pairs)
    assert np.all((rng_plan.sigma0 >= 0.010) & (rng_plan.sigma0 <= 0.015))
    box = (-0.001, -0.001, 0.0005, 0.021)        # the left side only
    reg = plan_grasps(mesh, top=0, n_sigma=10, regions=[box])
    assert np.all(mesh.nodes[reg.pairs][..., 0] <= 0.0005 + 1e-12)
    with pytest.raises(GraspError, match="no jaw pair"):
        plan_grasps(mesh, top=0, separation_range=(1.0, 2.0))
    with pytest.raises(GraspError, match="eps"):
        plan_grasps(mesh, eps=-1.0)


def test_cli_plan_report(tmp_path):
    part = tmp_path / "p.json"
    outer, holes, area = SHAPES["rectangle"]
    part.write_text(json.dumps({"units": "mm", "outer": outer, "material": MAT,
                                "mesh": {"max_area": area}}))
    out = tmp_path / "plan.json"
    assert main(["plan", str(part), "--model", "paper", "--top", "2", "-o", str(out), "--quiet",
                 "--plot", str(tmp_path / "plots")]) == 0
    r = json.loads(out.read_text())
    assert {"pairs", "epsilon", "units"} <= set(r)
    q = [row["quality"] for row in r["pairs"]]
    assert q == sorted(q, reverse=True)
    assert all({"a", "b", "sigma_star", "quality", "U_A", "U_L"} <= set(row) for row in r["pairs"])
    n_outer = len(dc.mesh_part(dc.Part.from_file(part)).outer_loop)
    assert len(r["pairs"]) == n_outer * (n_outer - 1) // 2          # zero-quality ones included
    assert r["units"]["energy"] == "J" and r["epsilon"] > 0
    assert (tmp_path / "plots" / "quality_map.png").exists()
    assert main(["plan", str(part), "--eps", "0"]) == 2


def test_plan_is_thread_safe_and_deterministic():
    """Several plans at once on threads (as jobs on one Dask worker run) give the same
    ranking and qualities as one plan alone."""
    from concurrent.futures import ThreadPoolExecutor

    mesh = _mesh("l_shape")
    ref = plan_grasps(mesh, top=1, n_sigma=30)
    with ThreadPoolExecutor(4) as pool:
        runs = list(pool.map(lambda _: plan_grasps(mesh, top=1, n_sigma=30), range(4)))
    for r in runs:
        assert np.array_equal(r.pairs, ref.pairs)
        assert np.array_equal(r.quality, ref.quality) and np.array_equal(r.e_max, ref.e_max)


def test_tiny_eps_is_honoured_not_refused():
    """A tiny ε used to be refused (the shared lattice would need ~10¹⁰ values); now the
    lattice stays coarse and every pair is settled within ε by bounds or exactly."""
    mesh = _mesh("rectangle")
    plan = plan_grasps(mesh, eps=1e-15, top=0)
    assert plan.n_sigma <= 401
    assert np.all(plan.quality_upper - plan.quality <= 1e-15)
    model = plan.model
    for i in np.flatnonzero(plan.quality > 0)[:6]:
        a, b = (int(v) for v in plan.pairs[i])
        ex = optimize_separation(mesh, (a, b), method="exact", model=model)
        assert abs(ex.quality - plan.quality[i]) <= 1e-15 + 1e-12 * ex.quality
    with pytest.raises(GraspError, match="lattice values.*larger eps"):
        lattice(0.0, 1.0, 1e-9, max_size=1000)
