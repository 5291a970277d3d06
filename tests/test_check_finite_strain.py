"""``check --elasticity neo-hookean``: the release energy of fixed fingers at finite strain
(SPEC §7, §8; :mod:`deformclosure.dspace.finite_strain_release`).

* The edge rows of the finite-strain contact solver (a boundary edge kept out of a round
  body): gradient and Hessian against finite differences; a coarse facet pressed by a
  disc no longer sags into it (it does with node rows alone).
* Small squeeze: the neo-Hookean placement energy over the small-strain law's (same exact
  contact) tends to 1 at the rate O(δ).
* Frame invariance: part and fingers moved by a rigid motion give the same energies.
* Verdicts follow mechanics: at rest (nothing squeezed) the finite-strain verdict is the
  rigid form-closure test's (Thm 1) on held and escaping sets; a convex block squeezed by
  two frictionless discs is not held; a budget-limited search brackets the lattice's value.
* The command: the report's keys, and the one-line refusals.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from deformclosure import Part, mesh_part
from deformclosure.contact.compliance import gauge_functionals
from deformclosure.contact.large_deformation import (CapsuleObstacle, FiniteStrainContact,
                                                     HalfPlaneObstacle, _edge_rows, follow_squeeze)
from deformclosure.dspace import DiscFinger, HalfPlaneFinger, deform_closure, release_energy_fingers
from deformclosure.dspace.finite_strain_release import FiniteStrainPlacements, finite_strain_release
from deformclosure.dspace.placement_energy import disc_axes
from deformclosure.elasticity.neohookean import NeoHookean

MM = 1e-3
RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0, "elastic_limit_strain": 0.8,
          "plane": "stress"}
MAT_M = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 0.002, "elastic_limit_strain": 0.5}
BAR = np.array([[-1.0, -0.5], [1.0, -0.5], [1.0, 0.5], [-1.0, 0.5]])      # m


def _part(outer, max_area, material, units="mm"):
    return Part.from_dict({"name": "t", "units": units, "outer": [list(map(float, p)) for p in outer],
                           "material": material, "mesh": {"max_area": max_area, "min_angle": 30}})


# --------------------------------------------------------------------------- edge rows
@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_edge_row_gradient_and_hessian_match_finite_differences(seed):
    rng = np.random.default_rng(seed)
    k = 8
    xa = rng.normal(size=(k, 2))
    e = rng.normal(size=(k, 2))
    e *= (0.5 + rng.random(k))[:, None] / np.linalg.norm(e, axis=1)[:, None]
    xb = xa + e
    m = np.stack([-e[:, 1], e[:, 0]], 1) / np.linalg.norm(e, axis=1)[:, None]   # inward
    # feet inside the edge and beyond its end vertex (clamped: the distance to the vertex)
    s0 = np.where(rng.random(k) < 0.7, rng.uniform(0.1, 0.9, k), rng.uniform(1.1, 1.6, k))
    C = np.column_stack([xa + s0[:, None] * e - rng.uniform(0.05, 1.0, k)[:, None] * m,
                         rng.uniform(0.0, 0.5, k)])
    g, n, s, H = _edge_rows(xa, xb, C, 1e3)
    # the gap is the centre's distance from the segment less the radius (brute force:
    # the nearest of many points of the segment)
    assert np.allclose(s, np.minimum(s0, 1.0), atol=1e-12)
    t = np.linspace(0.0, 1.0, 20001)
    pts = xa[:, None, :] + t[None, :, None] * e[:, None, :]
    brute = np.linalg.norm(pts - C[:, None, :2], axis=2).min(axis=1)
    assert np.allclose(g, brute - C[:, 2], atol=1e-8)
    y = np.concatenate([xa, xb], 1)
    h = 1e-6

    def grad_at(z):
        _, nn, ss, _ = _edge_rows(z[:, :2], z[:, 2:], C, 1e3)
        return np.concatenate([(1 - ss)[:, None] * nn, ss[:, None] * nn], 1)

    G_fd, H_fd = np.zeros((k, 4)), np.zeros((k, 4, 4))
    for i in range(4):
        d = np.zeros(4)
        d[i] = h
        G_fd[:, i] = (_edge_rows((y + d)[:, :2], (y + d)[:, 2:], C, 1e3)[0]
                      - _edge_rows((y - d)[:, :2], (y - d)[:, 2:], C, 1e3)[0]) / (2 * h)
        H_fd[:, :, i] = (grad_at(y + d) - grad_at(y - d)) / (2 * h)
    assert np.allclose(grad_at(y), G_fd, atol=1e-7)
    assert np.allclose(H, H_fd, atol=1e-6 * (1 + np.abs(H).max()))
    assert np.allclose(H, np.transpose(H, (0, 2, 1)), atol=1e-12)


def test_edge_rows_keep_a_coarse_facet_out_of_a_disc():
    """A 30 × 6 mm block on a floor, pressed 0.3 mm by a 2 mm disc above the middle of
    its longest top facet (≥ 4 mm): with node rows alone the facet sags into the disc (by
    up to L²/8ρ, here the disc passes between the nodes); with edge rows no point of the
    deformed boundary is inside it."""
    mesh = mesh_part(_part([(0, 0), (30, 0), (30, 6), (0, 6)], 30.0, RUBBER))
    E = mesh.boundary_edges
    xa, xb = mesh.nodes[E[:, 0]], mesh.nodes[E[:, 1]]
    on_top = (np.abs(xa[:, 1] - 6 * MM) < 1e-12) & (np.abs(xb[:, 1] - 6 * MM) < 1e-12)
    length = np.where(on_top, np.abs(xb[:, 0] - xa[:, 0]), 0.0)
    k = int(np.argmax(length))
    assert length[k] >= 4 * MM
    xc = 0.5 * (xa[k, 0] + xb[k, 0])
    law = NeoHookean(mesh)
    disc = CapsuleObstacle((xc, 7.7 * MM), (xc, 7.7 * MM), 2 * MM)
    floor = HalfPlaneObstacle((0.0, 0.0), (0.0, 1.0))
    loop = mesh.outer_loop
    worst = {}
    for with_edges in (False, True):
        edges = [(mesh.boundary_edges, 0, 0)] if with_edges else []
        prob = FiniteStrainContact(law, mesh.nodes, [(loop, 0), (loop, 1)], gauge_functionals(mesh)[:1],
                                   mesh.diameter, mesh.triangles, edges)

        def bodies(t, prob=prob):
            c = (xc, 7.7 * MM + (1.0 - t) * 0.3 * MM)
            return [CapsuleObstacle(c, c, 2 * MM), floor]

        path = follow_squeeze(prob, bodies, [0.25, 0.5, 0.75, 1.0])
        assert path.reached
        u = path.states[-1].u.reshape(-1, 2)
        x = mesh.nodes + u
        t = np.linspace(0, 1, 201)[:, None, None]
        pts = (x[E[:, 0]][None] * (1 - t) + x[E[:, 1]][None] * t).reshape(-1, 2)
        worst[with_edges] = float(disc.distance(pts)[0].min())
    assert worst[False] < -1e-5 * MM * 10                 # a sag of > 0.1 µm into the disc
    assert worst[True] > -1e-9 * mesh.diameter


# --------------------------------------------------------------------------- placements
def _squeezed_block(depth_mm, max_area=4.0):
    """A 12 × 20 mm rubber block between two 2 mm discs at the middles of its long sides,
    each overlapping it by ``depth_mm``."""
    mesh = mesh_part(_part([(0, 0), (12, 0), (12, 20), (0, 20)], max_area, RUBBER))
    r = 2.0
    fingers = [DiscFinger(((-r + depth_mm) * MM, 10 * MM), r * MM),
               DiscFinger(((12 + r - depth_mm) * MM, 10 * MM), r * MM)]
    return mesh, fingers


def _centroid(mesh):
    A = mesh.areas
    return (A[:, None] * mesh.nodes[mesh.triangles].mean(axis=1)).sum(0) / A.sum()


def test_small_squeeze_neo_hookean_over_small_strain_tends_to_one():
    """The same exact contact, two laws: U_neo / U_small-strain − 1 = O(δ)."""
    mesh, _ = _squeezed_block(0.1)
    c = _centroid(mesh)
    dev = []
    for depth in (0.2, 0.1, 0.05):
        _, fingers = _squeezed_block(depth)
        ax = disc_axes(mesh, fingers)
        E = [FiniteStrainPlacements(mesh, fingers, ax, c, law).solve(np.zeros(3)).energy
             for law in ("neo-hookean", "linear")]
        dev.append(abs(E[0] / E[1] - 1.0))
    assert dev[0] > dev[1] > dev[2] > 0
    assert dev[1] / dev[0] == pytest.approx(0.5, abs=0.15)
    assert dev[2] / dev[1] == pytest.approx(0.5, abs=0.15)


def test_placement_energies_are_frame_invariant():
    """Part and fingers rotated and translated together: the same finite-strain energy at
    the corresponding placements (translations turn with the motion)."""
    mesh, fingers = _squeezed_block(0.3, max_area=2.0)
    c = _centroid(mesh)
    ang, c0, t0 = 0.83, np.array([3e-3, -2e-3]), np.array([0.05, 0.02])
    R = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
    mesh2 = mesh.rotated(ang, c0).translated(t0)
    move = lambda p: tuple(R @ (np.asarray(p, float) - c0) + c0 + t0)      # noqa: E731
    fingers2 = [DiscFinger(move(f.center), f.radius) for f in fingers]
    fs1 = FiniteStrainPlacements(mesh, fingers, disc_axes(mesh, fingers), c)
    fs2 = FiniteStrainPlacements(mesh2, fingers2, disc_axes(mesh2, fingers2), np.asarray(move(c)))
    rng = np.random.default_rng(7)
    for g in [np.zeros(3)] + [np.r_[rng.normal(scale=0.2e-3, size=2), rng.normal(scale=0.02)] for _ in range(3)]:
        g2 = np.r_[R @ g[:2], g[2]]
        a, b = fs1.solve(g), fs2.solve(g2)
        assert a.energy > 0
        assert b.energy == pytest.approx(a.energy, rel=1e-8)


# --------------------------------------------------------------------------- verdicts
def _rest_sets():
    return {
        "three walls and a disc on top (held)": [
            HalfPlaneFinger((-1.0, 0.0), (1.0, 0.0)), HalfPlaneFinger((1.0, 0.0), (-1.0, 0.0)),
            HalfPlaneFinger((0.0, -0.5), (0.0, 1.0)), DiscFinger((0.3, 0.8), 0.3)],
        "two walls (escapes)": [HalfPlaneFinger((-1.0, 0.0), (1.0, 0.0)),
                                HalfPlaneFinger((1.0, 0.0), (-1.0, 0.0))],
        "four discs at the mid-sides (held)": [
            DiscFinger((-1.3, 0.0), 0.3), DiscFinger((1.3, 0.0), 0.3), DiscFinger((0.0, 0.8), 0.3),
            DiscFinger((0.0, -0.8), 0.3)],
        "floor and a disc (escapes)": [HalfPlaneFinger((0.0, -0.5), (0.0, 1.0)), DiscFinger((0.0, 0.8), 0.3)],
    }


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if "(held)" in n else n
                                  for n in _rest_sets()])
def test_at_rest_the_finite_strain_verdict_is_the_rigid_test(name):
    """Thm 1 (SPEC §7) at finite strain: nothing squeezed, so deform closure is the rigid
    form-closure test; a held set is decided on the certified lower bound even when the
    search is stopped by its budget."""
    fingers = _rest_sets()[name]
    part = _part(BAR, np.ptp(BAR, axis=0).prod() / 40, MAT_M, units="m")
    mesh = mesh_part(part)
    rigid = deform_closure(mesh, fingers).deform_closure
    assert rigid == ("held" in name)
    lin = release_energy_fingers(mesh, fingers, part=part, rigid_closed=rigid, levels=0)
    fs = finite_strain_release(mesh, fingers, lin, levels=0, max_evaluations=60)
    assert fs.energy == 0.0
    assert fs.deform_closure == rigid
    assert (fs.U_A_lower > 0) == rigid
    if not rigid:
        assert fs.U_A == 0.0


def test_convex_block_between_frictionless_discs_is_not_held(tmp_path):
    """A convex block squeezed 0.3 mm by two discs slides out between them at no cost:
    not held at finite strain (edge rows: the discs cannot nest in the coarse facets)."""
    from deformclosure import reports

    fingers = tmp_path / "discs.json"
    fingers.write_text(json.dumps({"units": "mm", "fingers": [
        {"type": "disc", "center": [-1.7, 10], "radius": 2},
        {"type": "disc", "center": [13.7, 10], "radius": 2}]}))
    rep = reports.run("check", "examples/rectangle.json",
                      {"fingers": str(fingers), "max_area": 4.0, "refine": 1,
                       "elasticity": "neo-hookean"})
    d = rep.data
    assert d["elasticity"] == "neo-hookean"
    assert d["release"]["equilibrium_energy"] > 0
    assert not d["deform_closure"] and d["U_A"] == 0.0 and d["finite_strain_verdict"] == "not held"
    assert d["U_A_is_upper_bound"] is False and d["release"]["finite_strain_search"] == "whole lattice"
    assert set(d["linear_model_error"]) == {"U", "F", "quality", "sigma_star"}
    assert d["linear"]["deform_closure"] is False
    assert abs(d["linear_model_error"]["U"]) < 0.5
    assert any(line.startswith("finite strain (neo-hookean)") for line in rep.lines)


@pytest.mark.slow
def test_budgeted_searches_bracket_one_value():
    """The bracket is a claim: a search stopped by its budget says the lattice's U_A lies
    in [U_A_lower, U_A]; two budgets must then give overlapping brackets, the larger's
    level reached at least the smaller's, and the same verdict (four discs at rest)."""
    fingers = _rest_sets()["four discs at the mid-sides (held)"]
    part = _part(BAR, np.ptp(BAR, axis=0).prod() / 40, MAT_M, units="m")
    mesh = mesh_part(part)
    lin = release_energy_fingers(mesh, fingers, part=part, rigid_closed=True, levels=0)
    runs = [finite_strain_release(mesh, fingers, lin, levels=0, max_evaluations=b) for b in (40, 240)]
    for r in runs:
        assert not r.exact and r.deform_closure and r.verdict == "held"
        assert 0 < r.U_A_lower <= r.U_A
    assert max(r.U_A_lower for r in runs) <= min(r.U_A for r in runs)
    assert runs[1].U_A_lower >= runs[0].U_A_lower * (1 - 1e-12)


def test_check_refuses_fingers_without_finite_strain_contact(tmp_path, capsys):
    from deformclosure.cli.main import main

    f = tmp_path / "poly.json"
    f.write_text(json.dumps({"units": "mm", "fingers": [
        {"type": "polygon", "vertices": [[-4, 8], [0.2, 8], [0.2, 12], [-4, 12]]},
        {"type": "disc", "center": [13.7, 10], "radius": 2}]}))
    code = main(["check", "examples/rectangle.json", "--fingers", str(f), "--elasticity", "neo-hookean"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert "fingers[0]" in err and "polygon finger" in err and len(err.strip().splitlines()) == 1


def test_transfer_operator_carries_a_linear_field_exactly():
    """The twin mesh gets the landscape's state by linear interpolation: a linear field
    is carried exactly to every twin node inside the mesh, and to within the boundary's
    discretisation elsewhere."""
    from deformclosure.dspace.finite_strain_release import transfer_operator
    from deformclosure.mesh.generate import twin_mesh

    part = _part([(0, 0), (12, 0), (12, 20), (0, 20)], 4.0, RUBBER)
    mesh, twin = mesh_part(part), twin_mesh(part)
    f = lambda X: np.column_stack([0.3 * X[:, 0] - 0.1 * X[:, 1] + 1e-3, 0.2 * X[:, 1]])  # noqa: E731
    out = transfer_operator(mesh, twin) @ f(mesh.nodes)
    assert np.allclose(out, f(twin.nodes), atol=1e-12 + 1e-9 * np.abs(f(twin.nodes)).max())
