"""The ε-approximation against the exact optimum on meshed random parts (paper §4.7).

Complements ``test_separation.py`` (random contact graphs with synthetic stiffnesses):
here each case is a real part — a random star-shaped polygon, meshed, with its CST
stiffness — a random perimeter jaw pair and a random ε, run through the public
``optimize_separation``.
"""

from __future__ import annotations

import numpy as np
import pytest

import deformclosure as dc
from deformclosure.grasp.analysis import grasp_model, optimize_separation

pytestmark = pytest.mark.slow

MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 1.0,
       "elastic_limit_strain": 0.5, "plane": "stress"}


def random_part(rng: np.random.Generator) -> dc.Part:
    n = int(rng.integers(5, 10))
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    rad = rng.uniform(6.0, 12.0, n)
    outer = np.c_[rad * np.cos(ang), rad * np.sin(ang)]
    return dc.Part.from_dict({"units": "mm", "outer": outer.tolist(), "material": MAT,
                              "mesh": {"max_area": 12.0, "min_angle": 25}})


@pytest.mark.parametrize("seed", range(24))
def test_approx_within_eps_of_exact_on_random_parts(seed):
    rng = np.random.default_rng(1000 + seed)
    try:
        mesh = dc.mesh_part(random_part(rng))
    except dc.PartError:  # a degenerate random ring: draw again from the next seed's stream
        mesh = dc.mesh_part(random_part(rng))
    model = grasp_model(mesh)
    # Most node pairs cannot hold (a jaw slides to a neighbour of lower energy, Q ≡ 0);
    # draw among the pairs that can, found by the planner's coarse lattice.
    plan = dc.plan_grasps(mesh, model=model, top=0, n_sigma=40)
    holding = np.flatnonzero(plan.quality > 0)
    assert len(holding), "every random part has a holding pair (e.g. across its diameter)"
    jaws = tuple(int(v) for v in plan.pairs[rng.choice(holding)])
    exact = optimize_separation(mesh, jaws, method="exact", model=model)
    assert exact.quality > 0
    # ε well below Q*, so that the bound is not met trivially
    eps = float(exact.quality * 10 ** rng.uniform(-3.0, -0.7))
    approx = optimize_separation(mesh, jaws, method="approx", eps=eps, model=model)
    assert approx.separation.epsilon == eps
    assert exact.quality - approx.quality <= eps
    assert approx.quality <= exact.quality * (1 + 1e-12) + 1e-18
