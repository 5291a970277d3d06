"""The grip force (SPEC §6 "Grip force"): ``force`` at σ*, ``curve.F`` and ``stiffness``.

Independent values: the force is the derivative of the energy, ``F = −dU/dσ``, checked by
central finite differences of the energy curve; a block squeezed between flat pads wider
than it is in uniaxial stress, ``F = E′ t W δ / L`` with ``E′ = E`` (plane stress) or
``E/(1 − ν²)`` (plane strain), exact on any mesh in the SPEC §6 gauge, and its stiffness
is ``E′ t W / L``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import deformclosure as dc
from deformclosure import reports
from deformclosure.pads import GraspAxis, Pad
from deformclosure.pads.contact import PadContact
from deformclosure.pads.limit import pad_strain_at

ROOT = Path(__file__).resolve().parents[1]
MM = 1e-3
E, NU, T = 2e6, 0.3, 1.0          # Pa, -, mm


def _block(W: float, L: float, plane: str, max_area: float, points=()):
    """A W × L mm block (W across the axis, L along it) meshed unstructured."""
    raw = {"name": "block", "units": "mm",
           "outer": [[0, 0], [W, 0], [W, L], [0, L]], "holes": [],
           "material": {"youngs_modulus": E, "poisson_ratio": NU, "thickness": T,
                        "elastic_limit_strain": 0.5, "plane": plane},
           "mesh": {"max_area": max_area, "min_angle": 25, "points": [list(p) for p in points]}}
    return dc.mesh_part(dc.Part.from_dict(raw))


MESHES = [  # (max_area mm², inserted points): three different unstructured meshes
    (4.0, ()),
    (1.7, ((3.1, 7.3), (7.9, 2.2))),
    (0.9, ((1.3, 11.1), (5.55, 5.05), (8.2, 13.7))),
]


@pytest.mark.parametrize("plane", ["stress", "strain"])
@pytest.mark.parametrize("mesh_case", MESHES, ids=["coarse", "medium", "fine"])
def test_uniform_compression_force_and_stiffness_exact(plane, mesh_case):
    W, L = 10.0, 16.0
    mesh = _block(W, L, plane, *mesh_case)
    pc = PadContact(mesh)
    # closing along y through the block's middle; pads 3 W wide with a small end radius
    axis = GraspAxis.at(np.array([W / 2, 0.0]) * MM, math.pi / 2, tuple(pc.centroid))
    pad = Pad(3 * W * MM, 0.2 * MM)
    curve = pc.curve(axis, pad, 0.6 * L * MM)
    assert curve.sigma0 == pytest.approx(L * MM, rel=1e-12)
    Ep = E if plane == "stress" else E / (1 - NU**2)
    k_exact = Ep * T * MM * W * MM / (L * MM)          # N/m
    for frac in (0.01, 0.1, 0.3):
        delta = frac * L * MM
        sigma = L * MM - delta
        F = curve.axial_force(sigma)
        assert F == pytest.approx(k_exact * delta, rel=1e-11)
        assert curve.axial_stiffness(sigma) == pytest.approx(k_exact, rel=1e-11)
        assert float(curve.energy(sigma)) == pytest.approx(0.5 * k_exact * delta**2, rel=1e-11)
        # uniaxial stress: the strain measure (largest |principal strain|) is δ / L
        assert pad_strain_at(pc, curve, sigma) == pytest.approx(frac, rel=1e-10)


def test_force_is_minus_dU_dsigma_on_a_notched_part():
    """``curve.F`` and ``force`` from a pad grasp equal central differences of ``U(σ)``
    (away from the kinks of the piecewise-quadratic energy)."""
    mesh = dc.mesh_part(dc.notched_part(), max_area=0.6e-6)
    pc = PadContact(mesh)
    axis = GraspAxis.at(np.array([15.0, 0.0]) * MM, math.pi / 2, tuple(pc.centroid))
    curve = pc.curve(axis, Pad(0.0, 2 * MM), 0.5 * 7.6 * MM)
    kinks = curve.kinks()
    checked = 0
    for sigma in np.linspace(curve.sigma0 - 0.2 * MM, curve.sigma0 - 3.0 * MM, 23):
        h = 1e-4 * MM
        if np.min(np.abs(kinks - sigma)) < 2 * h:
            continue
        dU = (float(curve.energy(sigma - h)) - float(curve.energy(sigma + h))) / (2 * h)
        F = curve.axial_force(sigma)
        assert F == pytest.approx(dU, rel=1e-6)
        # the stiffness is the derivative of the force
        dF = (curve.axial_force(sigma - h) - curve.axial_force(sigma + h)) / (2 * h)
        assert curve.axial_stiffness(sigma) == pytest.approx(dF, rel=1e-6)
        checked += 1
    assert checked >= 15


def test_optimize_report_carries_the_force(tmp_path):
    """The optimize report: ``force`` at σ*, ``curve.F`` at every curve σ (N) and
    ``stiffness`` (N/m), consistent with one another and printed with units."""
    raw = json.loads((ROOT / "examples" / "notched_bar.json").read_text())
    raw["mesh"]["max_area"] = 1.0                     # mm², coarse: a fast report
    part = tmp_path / "bar.json"
    part.write_text(json.dumps(raw))
    rep = reports.run("optimize", str(part), {"axis": "15,6,90", "pad_radius": 2.0})
    d = rep.data
    assert d["sigma_star"] is not None
    sig = np.array(d["curve"]["sigma"])
    F = np.array([np.nan if v is None else v for v in d["curve"]["F"]])
    assert len(F) == len(sig) and np.all(np.isfinite(F)) and np.all(F >= 0)
    i = int(np.argmin(np.abs(sig - d["sigma_star"])))
    assert sig[i] == d["sigma_star"] and F[i] == pytest.approx(d["force"], rel=1e-12)
    assert d["force"] > 0 and d["stiffness"] > 0
    # the force grows as the pads close, and the stiffness is its slope there
    order = np.argsort(sig)
    assert np.all(np.diff(F[order]) <= 1e-12 * F.max())
    assert any("grip force" in line and " N " in line and "N/m" in line for line in rep.lines)


def test_linear_runs_beyond_small_strain_warn(tmp_path):
    """SPEC §8: a linear run whose strain at σ* exceeds 0.05 says so."""
    raw = json.loads((ROOT / "examples" / "notched_bar.json").read_text())
    raw["mesh"]["max_area"] = 1.0
    part = tmp_path / "bar.json"
    part.write_text(json.dumps(raw))
    rep = reports.run("optimize", str(part), {"axis": "15,6,90", "pad_radius": 2.0,
                                              "grid_angles": 12, "grid_offsets": 16})
    e = rep.data["strain_at_sigma_star"]
    assert e > 0.05 and rep.data["elasticity"] == "linear"
    assert any("outside its range" in w and f"{e:.3g}" in w for w in rep.warnings)
