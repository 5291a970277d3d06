"""The pads pictures (issue 24 items 1-3) on figure objects, Agg backend: the deformed
part's strain colours against the averaged strains computed here by another route, the
pads touching the deformed part, the contact pressure, the frame on the part, the
force-squeeze curve, the escape strip's energies against U_A, the plan's (θ, c) map and
top grasps, the convergence plot; and ``--plot`` formats (svg/pdf magic bytes, an unknown
suffix refused in one line before any analysis)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import shapely  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402
from matplotlib.quiver import Quiver  # noqa: E402

import deformclosure as dc  # noqa: E402
from deformclosure.errors import DeformClosureError  # noqa: E402
from deformclosure.pads import GraspAxis, Pad  # noqa: E402
from deformclosure.pads.optimize import optimize_pads  # noqa: E402
from deformclosure.planning.pads import plan_pads  # noqa: E402
from deformclosure.plotting import pads as pp  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MM = 1e-3


@pytest.fixture(scope="module")
def notched():
    """The notched bar on 300 nodes, round 2 mm pads seated in its notches (about 4 s): a
    grasp with a finite barrier, so an escape path (one mesh: its verdict "undecided"), and
    a plan whose best candidate is verified to ``rtol = 0.2`` on refined meshes ("held")."""
    part = dc.notched_part()
    part = replace(part, mesh_options=replace(part.mesh_options, max_area=1e-6))
    mesh = dc.mesh_part(part)
    res = optimize_pads(mesh, GraspAxis(np.pi / 2, -0.015), Pad(0.0, 2e-3), n_angles=8,
                        n_offsets=8, noise=False)
    assert res.quality > 0 and res.escape_path and np.isfinite(res.U_A)
    plan = plan_pads(mesh, Pad(0.0, 2e-3), n_angles=6, n_offsets=16, n_sigma=16, top=1,
                     part=part, rtol=0.2)
    return {"part": part, "mesh": mesh, "res": res, "plan": plan}


@pytest.fixture(scope="module")
def notched_grasp(notched):
    """The notched grasp's picture at σ* (mm, true scale) and its state, drawn once for the
    tests that only read them (closing the figure keeps its artists readable)."""
    res = notched["res"]
    fig = pp.plot_pad_grasp(res, units="mm")
    return {"fig": fig, "ax": fig.axes[0], "state": pp.pad_state(res)}


@pytest.fixture(scope="module")
def rhombus():
    """Round pads opening into the acute corners of a rhombus hole (expanding, a barrier;
    about 0.5 s)."""
    from deformclosure.pads.contact import hole_containing

    part = dc.Part.from_dict({
        "name": "plate", "units": "mm", "outer": [[0, 0], [30, 0], [30, 20], [0, 20]],
        "holes": [[[8, 10], [15, 13], [22, 10], [15, 7]]], "mesh": {"max_area": 0.4},
        "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 1.0,
                     "elastic_limit_strain": 0.5}})
    mesh = dc.mesh_part(part)
    res = optimize_pads(mesh, GraspAxis.through(np.array([8, 10]) * MM, np.array([22, 10]) * MM),
                        Pad(0.0, MM), hole=hole_containing(mesh, [0.015, 0.010]), n_angles=12,
                        n_offsets=12, noise=False)
    assert res.start_curve.expanding and res.quality > 0 and res.escape_path
    return {"part": part, "mesh": mesh, "res": res}


@pytest.fixture(autouse=True)
def _close():
    plt.close("all")
    yield
    plt.close("all")


def _strain_collection(ax) -> PolyCollection:
    cols = [c for c in ax.collections if isinstance(c, PolyCollection) and c.get_array() is not None]
    assert len(cols) == 1, ax.collections
    return cols[0]


def _independent_strains(res) -> np.ndarray:
    """SPEC §6's measure per element, by the elasticity module's own functions on the
    state of ``PadGraspResult.state_at`` (not the pictures' route through the fields)."""
    from deformclosure.elasticity.critical_distance import averaged_strain_magnitude
    from deformclosure.elasticity.strain import element_strains

    mesh = res.solver.mesh
    u = res.state_at(res.sigma_star, "s").displacement
    return averaged_strain_magnitude(mesh, element_strains(mesh, np.ravel(u)),
                                     res.limit.critical_distance)


def test_deformed_colours_are_the_averaged_strains(notched, notched_grasp):
    res = notched["res"]
    ax = notched_grasp["ax"]
    colours = np.asarray(_strain_collection(ax).get_array(), float)
    np.testing.assert_allclose(colours, _independent_strains(res), rtol=1e-9, atol=1e-15)
    # its maximum is the strain the report states at σ* (pad_strain_at: a third route)
    assert colours.max() == pytest.approx(res.strain_at_sigma_star, rel=1e-9)


def test_deformed_picture_title_labels_colour_bar(notched, notched_grasp):
    res = notched["res"]
    ax, cax = notched_grasp["fig"].axes
    title = ax.get_title()
    assert f"F = {res.force:.4g} N" in title and f"{res.sigma_star / MM:.4g} mm" in title
    assert "true scale" in title
    assert ax.get_xlabel() == "x (mm)" and ax.get_ylabel() == "y (mm)"
    assert "(m/m)" in cax.get_ylabel() and "e_L" in cax.get_ylabel()
    # the colour bar's range holds both the largest strain and e_L (marked)
    lo, hi = _strain_collection(ax).get_clim()
    assert lo == 0.0 and hi == pytest.approx(max(res.strain_at_sigma_star, res.e_L))
    labels = ax.get_legend().get_texts()
    assert {"part at rest", "pads"} <= {t.get_text() for t in labels}


def test_frame_is_tight_on_the_deformed_part(notched, notched_grasp):
    """The frame holds the deformed part and stays within the pads' stubs (their radius
    and 5 % of the part's size) and a margin of it: no axis line stretches it."""
    res, mesh = notched["res"], notched["mesh"]
    ax, st = notched_grasp["ax"], notched_grasp["state"]
    xy = (mesh.nodes + st.displacement) / MM
    lo, hi = np.minimum(xy.min(0), mesh.nodes.min(0) / MM), np.maximum(xy.max(0), mesh.nodes.max(0) / MM)
    margin = (res.pad.radius + 0.1 * mesh.diameter) / MM       # the pads' stubs, a margin
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert lo[0] - margin <= x0 <= lo[0] and hi[0] <= x1 <= hi[0] + margin
    assert lo[1] - margin <= y0 <= lo[1] and hi[1] <= y1 <= hi[1] + margin


@pytest.mark.parametrize("case", ["notched", "rhombus"])
def test_pads_touch_the_deformed_part_where_the_path_presses(case, request):
    """Each pressed node of the deformed part lies on a drawn pad's outline (within 10 %
    of the squeeze: the contact is linearised along the axis) and inside none — closing
    on the notched bar, opening in the rhombus hole."""
    c = request.getfixturevalue(case)
    res, mesh = c["res"], c["mesh"]
    ax = pp.plot_pad_grasp(res).axes[0]
    pads = [shapely.Polygon(p.get_xy()) for p in ax.patches if isinstance(p, Polygon)]
    assert len(pads) == 2
    st = pp.pad_state(res)
    pressed = np.flatnonzero(np.linalg.norm(st.forces, axis=1) > 0)
    assert len(pressed) >= 2
    pts = shapely.points((mesh.nodes[pressed] + st.displacement[pressed]) / MM)
    dist = np.min([shapely.distance(p.exterior, pts) for p in pads], axis=0)
    assert np.all(dist <= 0.1 * st.delta / MM), dist / (st.delta / MM)
    assert not any(shapely.contains(p, pts).any() for p in pads)


def test_draw_pads_puts_the_pads_where_the_picture_does(notched, notched_grasp):
    res = notched["res"]
    drawn = [np.asarray(p.get_xy()) for p in notched_grasp["ax"].patches]
    fig, ax = plt.subplots()
    pp.draw_pads(ax, res, res.sigma_star)
    for a, b in zip(drawn, [np.asarray(p.get_xy()) for p in ax.patches], strict=True):
        np.testing.assert_allclose(a, b)


def test_contact_pressure_arrows(notched, notched_grasp):
    res, mesh = notched["res"], notched["mesh"]
    ax, st = notched_grasp["ax"], notched_grasp["state"]
    quiv = [c for c in ax.collections if isinstance(c, Quiver)]
    assert len(quiv) == 1
    f = np.linalg.norm(st.forces, axis=1)
    assert np.count_nonzero(f) <= pp.MAX_PRESSURE_ARROWS
    assert quiv[0].N == np.count_nonzero(f)              # few pressed nodes: every one
    # pressure = normal force / (half the two boundary edges at the node × thickness)
    e = mesh.boundary_edges
    trib = np.zeros(mesh.n_nodes)
    for a, b in e:
        L = np.linalg.norm(mesh.nodes[a] - mesh.nodes[b])
        trib[a] += L / 2
        trib[b] += L / 2
    p = f[f > 0] / (trib[f > 0] * mesh.material.thickness)
    np.testing.assert_allclose(st.pressure[f > 0], p, rtol=1e-12)
    label = quiv[0].get_label()
    assert label.startswith("contact pressure (max ") and "kPa" in label
    assert float(label.split("max ")[1].split()[0]) == pytest.approx(p.max() / 1e3, rel=1e-2)
    # pad A's forces along the axis add up to the grip force of the title
    c = res.start_curve
    lam = c.path.multipliers(c.delta(res.sigma_star))
    on_a = np.unique(c.nodes[(c.pad_of == 0) & (lam > 0)])      # pressed by pad A
    assert not set(on_a) & set(c.nodes[(c.pad_of == 1) & (lam > 0)])
    assert float(np.sum(st.forces[on_a] @ res.axis.direction)) == pytest.approx(res.force,
                                                                                 rel=1e-9)


def test_pressure_arrows_thin_out_on_fine_meshes(notched):
    """More pressed nodes than MAX_PRESSURE_ARROWS: evenly many along the boundary, the
    most pressed one among them."""
    mesh = notched["mesh"]
    rng = np.random.default_rng(3)
    p = np.zeros(mesh.n_nodes)
    ring = np.concatenate(mesh.loops)
    p[ring] = rng.uniform(1.0, 2.0, len(ring))
    pick = pp.pressure_nodes(mesh, p)
    assert len(pick) <= pp.MAX_PRESSURE_ARROWS and np.argmax(p) in pick
    assert set(pick) <= set(ring)
    pos = np.array([np.flatnonzero(ring == k)[0] for k in pick])    # along the loops
    assert np.ptp(pos) > 0.9 * len(ring) and np.diff(np.sort(pos)).max() < 0.2 * len(ring)
    few = np.zeros(mesh.n_nodes)
    few[ring[:5]] = 1.0
    assert sorted(pp.pressure_nodes(mesh, few)) == sorted(ring[:5])


def test_scale_magnifies_the_displacements_and_moves_the_pads(notched):
    res = notched["res"]
    outline = {}
    pads = {}
    for k in (1.0, 3.0):
        ax = pp.plot_pad_grasp(res, scale=k).axes[0]
        outline[k] = [ln.get_xydata() for ln in ax.lines if ln.get_linestyle() == "-"][0]
        pads[k] = [np.asarray(p.get_xy()) for p in ax.patches]
        assert ("true scale" in ax.get_title()) == (k == 1.0)
    st = pp.pad_state(res)
    ring = np.append(notched["mesh"].loops[0], notched["mesh"].loops[0][0])
    X = notched["mesh"].nodes[ring] / MM
    np.testing.assert_allclose(outline[1.0], X + st.displacement[ring] / MM)
    np.testing.assert_allclose(outline[3.0], X + 3.0 * st.displacement[ring] / MM)
    # pad B moves by 3 × (δ + t) along −a, pad A by 3 × t
    a = res.axis.direction
    shift_a = (pads[3.0][0] - pads[1.0][0]).mean(axis=0) @ a * MM
    shift_b = (pads[3.0][1] - pads[1.0][1]).mean(axis=0) @ a * MM
    assert shift_a == pytest.approx(-2.0 * st.translation, rel=1e-9, abs=1e-15)
    assert shift_b == pytest.approx(-2.0 * (st.delta + st.translation), rel=1e-9)
    with pytest.raises(DeformClosureError, match="--scale"):
        pp.plot_pad_grasp(res, scale=0.0)


def test_force_squeeze_curve(notched):
    res = notched["res"]
    ax = pp.plot_force_squeeze(res).axes[0]
    curve = [ln for ln in ax.lines if ln.get_label().startswith("$F")][0]
    sig = np.array(res.curve["sigma"])
    order = np.argsort(sig)
    np.testing.assert_allclose(curve.get_xdata(), sig[order] / MM)
    F = np.array([res.start_curve.axial_force(s) for s in sig[order]])   # by the curve itself
    np.testing.assert_allclose(curve.get_ydata(), F, rtol=1e-12)
    star = [ln for ln in ax.lines if ln.get_label().startswith("$\\sigma^*$")][0]
    assert star.get_xdata()[0] == pytest.approx(res.sigma_star / MM)
    assert star.get_ydata()[0] == pytest.approx(res.force)
    labels = " ".join(ln.get_label() for ln in ax.lines)
    assert "\\sigma_L" in labels and f"{res.sigma_L / MM:.4g}" in labels
    assert ax.get_ylabel() == "grip force F (N)" and "σ (mm)" in ax.get_xlabel()


@pytest.mark.parametrize("case", ["notched", "rhombus"])
def test_escape_strip_energies(case, request):
    """The strip's panels are axes of the escape path solved at σ*: the first is the start
    (the grasp's own energy), the saddle's energy exceeds it by U_A (closing and opening
    pads)."""
    res = request.getfixturevalue(case)["res"]
    states = pp.escape_states(res, n=4)
    idx = [i for i, _, _ in states]
    assert idx[0] == 0 and idx[-1] == len(res.escape_path) - 1 and len(states) <= 4
    U = {i: st.energy for i, _, st in states}
    assert U[0] == pytest.approx(res.start_curve.energy_at(res.sigma_star), rel=1e-12)
    sad = [i for i, c, _ in states if np.isclose(c.axis.angle, res.saddle.angle)
           and np.isclose(c.axis.offset, res.saddle.offset)]
    assert len(sad) == 1
    assert U[sad[0]] - U[0] == pytest.approx(res.U_A, rel=1e-9)
    fig = pp.plot_escape_strip(res, n=4)
    panels = [a for a in fig.axes if a.get_title()]
    assert len(panels) == len(states)
    red = [a for a in panels if "saddle" in a.get_title()]
    assert len(red) == 1 and f"U = {U[sad[0]] * 1e3:.4g} mJ" in red[0].get_title()
    assert "U_A" in fig._suptitle.get_text()
    assert any("(m/m)" in a.get_ylabel() for a in fig.axes)            # the shared colour bar


def test_escape_strip_is_none_without_a_path(notched):
    res = replace(notched["res"], escape_path=[])
    assert pp.plot_escape_strip(res) is None
    assert not pp.escape_states(res)


def test_quality_map_cells_are_the_screened_qualities(notched):
    plan = notched["plan"]
    ax = pp.plot_pad_quality_map(plan).axes[0]
    mesh_col = [c for c in ax.collections if c.get_array() is not None][0]
    M = np.ma.filled(np.asarray(mesh_col.get_array()).reshape(
        plan.grid.j_max - plan.grid.j_min + 1, plan.grid.n_angles).astype(float), np.nan)
    g = plan.grid
    for r in plan.rows:
        i = int(round(r["angle"] / g.d_angle)) % g.n_angles      # angle0 = 0 for a plan
        j = int(round((r["offset"] - g.offset0) / g.d_offset)) - g.j_min
        q = r.get("lattice_quality", r["quality"])
        if q > 0:
            assert M[j, i] == pytest.approx(q * 1e3, rel=1e-12)
    assert ax.get_xlabel() == "axis angle θ (deg)" and "offset" in ax.get_ylabel()
    texts = {t.get_text() for t in ax.get_legend().get_texts()}
    assert "verified: held" in texts
    held = [ln for ln in ax.lines if ln.get_label() == "verified: held"][0]
    best = plan.held[0]
    assert held.get_xdata()[0] == pytest.approx(np.degrees(best["angle"]) % 180)
    assert held.get_ydata()[0] == pytest.approx(best["offset"] / MM)
    assert any(t.get_text() == "#1" for t in ax.texts)
    assert "log scale" in ax.figure.axes[1].get_ylabel()


def test_top_grasps_are_drawn_deformed(notched):
    plan = notched["plan"]
    fig = pp.plot_pad_top_grasps(plan)
    panels = [a for a in fig.axes if a.get_title().startswith("#")]
    verified = [r for r in plan.rows if r["verified"] and r["sigma_star"] is not None]
    assert len(panels) == len(verified) >= 1
    res = plan.top[0]
    colours = np.asarray(_strain_collection(panels[0]).get_array(), float)
    np.testing.assert_allclose(colours, _independent_strains(res), rtol=1e-9, atol=1e-15)
    # the deformed outline, not the rest one, carries the pads
    st = pp.pad_state(res)
    assert np.abs(st.displacement).max() > 0
    assert f"F = {res.force:.3g} N" in panels[0].get_title()


def test_plan_top_axes_draws_no_pads(notched):
    """The overview draws the contact chords on the part at rest — no pads at σ* over the
    undeformed part (issue 24)."""
    ax = pp.plot_pad_plan(notched["plan"], notched["mesh"]).axes[0]
    fills = [p for p in ax.patches if isinstance(p, Polygon)]
    assert len(fills) == 1 + len(notched["mesh"].hole_loops)        # the part's outline only


# ----------------------------------------------------------------------------- finite strain


@pytest.fixture(scope="module")
def neo():
    """The notched bar on 89 nodes, round 2 mm pads, its grasp re-solved neo-Hookean
    (SPEC §8; three σ samples, about 3 s)."""
    from deformclosure.pads.finite_strain_grasp import optimize_finite_strain

    part = dc.notched_part()
    part = replace(part, mesh_options=replace(part.mesh_options, max_area=4e-6))
    mesh = dc.mesh_part(part)
    lin = optimize_pads(mesh, GraspAxis(np.pi / 2, -0.015), Pad(0.0, 2e-3), n_angles=4,
                        n_offsets=4, noise=False)
    fs = optimize_finite_strain(mesh, lin, n_samples=3, rtol=0.2)
    assert fs.sigma_star is not None and lin.sigma_star is not None and lin.escape_path
    # the two models' σ* differ enough for the pictures' titles to tell them apart
    assert f"{fs.sigma_star / MM:.4g}" != f"{lin.sigma_star / MM:.4g}"
    return {"mesh": mesh, "fs": fs, "lin": lin}


def _stretch_magnitudes_by_hand(mesh, u: np.ndarray) -> np.ndarray:
    """``max |λᵢ − 1|`` per element of ``C = FᵀF``, ``F = I + ∇u`` from the triangle's
    own edge vectors, the eigenvalues by numpy (not the library's strain routines)."""
    u = np.asarray(u, float).reshape(-1, 2)
    out = []
    for tri in mesh.triangles:
        X = mesh.nodes[tri]
        x = X + u[tri]
        D = np.column_stack([X[1] - X[0], X[2] - X[0]])
        d = np.column_stack([x[1] - x[0], x[2] - x[0]])
        F = d @ np.linalg.inv(D)
        lam = np.sqrt(np.linalg.eigvalsh(F.T @ F))
        out.append(np.abs(lam - 1.0).max())
    return np.array(out)


@pytest.mark.slow            # about 4 s: the neo-Hookean re-solve
def test_neo_hookean_pictures_draw_the_finite_strain_state(neo):
    """``optimize --elasticity neo-hookean --plot``: the grasp picture is the neo-Hookean
    part at its own σ* (title names the model, σ*, F; outline = rest + finite-strain
    displacement; colours = SPEC §8's stretch measure, whose maximum is the report's
    strain at σ*; pads on the deformed part where the exact contact puts them); curves
    and force are the finite-strain ones; the escape strip says it is the linear twin."""
    fs, lin, mesh = neo["fs"], neo["lin"], neo["mesh"]
    c = fs.start_curve
    ax = pp.plot_pad_grasp(fs).axes[0]
    title = ax.get_title()
    assert title.startswith("neo-Hookean: ") and "max averaged stretch max|λ−1|" in title
    assert f"σ* = {fs.sigma_star / MM:.4g} mm" in title and f"F = {fs.force:.4g} N" in title
    assert f"{lin.sigma_star / MM:.4g} mm" not in title
    # the rest at a separation of the run's curve halfway to σ_L (this σ* is at touch:
    # the seated pads' barrier is largest there), where the two models' states differ
    sig = min((v for v in fs.curve["sigma"] if v is not None),
              key=lambda v: abs(v - 0.5 * (fs.sigma0 + fs.sigma_L)))
    ax = pp.plot_pad_grasp(fs, sigma=sig).axes[0]
    title = ax.get_title()
    assert title.startswith("neo-Hookean: ") and "max averaged stretch max|λ−1|" in title and f"σ = {sig / MM:.4g} mm" in title
    u = fs.state_at(sig, "s").displacement.reshape(-1, 2)
    u_lin = lin.state_at(sig, "s").displacement.reshape(-1, 2)
    assert np.abs(u - u_lin).max() > 0.01 * np.abs(u).max() > 0
    ring = np.append(mesh.loops[0], mesh.loops[0][0])
    drawn = [ln.get_xydata() for ln in ax.lines if ln.get_linestyle() == "-"][0]
    np.testing.assert_allclose(drawn, (mesh.nodes[ring] + u[ring]) / MM, rtol=1e-12)
    colours = np.asarray(_strain_collection(ax).get_array(), float)
    assert colours.max() == pytest.approx(c.strain(sig, fs.limit.critical_distance), rel=1e-9)
    assert pp.pad_state(fs).strain.max() == pytest.approx(fs.strain_at_sigma_star, rel=1e-9)
    np.testing.assert_allclose(c.strain_field(sig, 0.0),
                               _stretch_magnitudes_by_hand(mesh, u), rtol=1e-9, atol=1e-12)
    assert "max|λ−1|" in ax.figure.axes[1].get_ylabel()
    # the pads: pressed nodes of the deformed part on their outlines (exact contact)
    pads = [shapely.Polygon(p.get_xy()) for p in ax.patches if isinstance(p, Polygon)]
    assert len(pads) == 2
    f = fs.state_at(sig, "s").forces
    pressed = np.flatnonzero(np.linalg.norm(f, axis=1) > 0)
    assert len(pressed) >= 2
    pts = shapely.points((mesh.nodes[pressed] + u[pressed]) / MM)
    dist = np.min([shapely.distance(p.exterior, pts) for p in pads], axis=0)
    delta = c.delta(sig)
    assert np.all(dist <= 0.01 * delta / MM), dist / (delta / MM)
    # the curves are the finite-strain run's
    q = pp.plot_pad_quality(fs).axes[0]
    assert q.get_title().startswith("neo-Hookean: ")
    fax = pp.plot_force_squeeze(fs).axes[0]
    assert fax.get_title().startswith("neo-Hookean: ")
    star = [ln for ln in fax.lines if ln.get_label().startswith("$\\sigma^*$")][0]
    assert star.get_xdata()[0] == pytest.approx(fs.sigma_star / MM)
    assert star.get_ydata()[0] == pytest.approx(fs.force)
    # the escape strip: the linear model's path at the linear σ*, and the title says so
    strip = pp.plot_escape_strip(fs, n=3)
    sup = strip._suptitle.get_text()
    assert sup.startswith("linear twin of the neo-Hookean run")
    assert f"σ* = {lin.sigma_star / MM:.4g} mm" in sup


@pytest.mark.slow            # the neo-Hookean fixture (about 4 s, shared)
def test_save_pad_plots_of_a_finite_strain_result(neo, tmp_path):
    """What ``optimize --elasticity neo-hookean --plot dir/fig.svg`` hands the pictures:
    the four figures written, the grasp one titled with the model."""
    written = pp.save_pad_plots(neo["fs"], neo["mesh"], tmp_path / "fig.svg")
    assert [p.name for p in written] == [f"fig_{n}.svg" for n in
                                         ("grasp", "quality", "force", "escape")]
    assert all(_has_magic(p, "svg") for p in written)
    assert "neo-Hookean: " in written[0].read_text()
    # --animate: the linear twin's path, one frame per axis, as the strip
    from deformclosure.plotting.animate import pad_escape_animation

    gif = pad_escape_animation(neo["fs"], tmp_path / "escape.gif")
    assert len(_gif_frames(gif)) == len(neo["lin"].escape_path)


def test_convergence_plot_data():
    rows = [{"nodes": 100, "quality": 0.010, "sigma_star": 0.0050},
            {"nodes": 400, "quality": 0.012, "sigma_star": 0.0052},
            {"nodes": 1600, "quality": 0.0125, "sigma_star": None}]
    fig = pp.plot_convergence(rows)
    ax, twin = fig.axes
    q = ax.lines[0]
    np.testing.assert_allclose(q.get_xdata(), [100, 400, 1600])
    np.testing.assert_allclose(q.get_ydata(), [10.0, 12.0, 12.5])
    s = twin.lines[0]
    np.testing.assert_allclose(s.get_ydata(), [5.0, 5.2, np.nan])
    assert ax.get_xscale() == "log" and twin.get_ylabel() == "σ* (mm)"
    # check's rows: U_A in σ*'s place
    fig = pp.plot_convergence([{"nodes": 10, "quality": 1e-3, "U_A": 2e-3},
                               {"nodes": 40, "quality": 1.1e-3, "U_A": None}])
    assert fig.axes[1].get_ylabel() == "U_A (mJ)"


# ----------------------------------------------------------------------------- formats


def _cli(args, capsys):
    from deformclosure.cli.main import main

    rc = main([str(a) for a in args])
    out = capsys.readouterr()
    return rc, out.out, out.err


MAGIC = {"svg": (b"<?xml", b"<svg"), "pdf": (b"%PDF",), "png": (b"\x89PNG\r\n\x1a\n",)}


def _has_magic(path: Path, fmt: str) -> bool:
    head = path.read_bytes()[:256]
    return any(head.startswith(m) or (fmt == "svg" and m in head) for m in MAGIC[fmt])


@pytest.fixture(scope="module")
def notched_optimize():
    """``optimize examples/notched_bar.json --at 15,0 15,12 --pad-radius 2 --refine 2
    --max-area 4 --grid-angles 8 --grid-offsets 8``, its options parsed by the CLI's table
    and run once (about 3 s): the CLI's ``optimize`` is this run and then
    :meth:`Report.save` of its ``--plot``, which each format's test calls."""
    from deformclosure import reports

    params = reports.parse_argv("optimize", ["--at", "15,0", "15,12", "--pad-radius", "2",
                                             "--refine", "2", "--max-area", "4",
                                             "--grid-angles", "8", "--grid-offsets", "8",
                                             "-q"])
    return reports.run("optimize", ROOT / "examples" / "notched_bar.json", params)


@pytest.mark.parametrize("fmt", ["svg", "pdf"])
def test_plot_file_suffix_sets_every_figures_format(fmt, notched_optimize, tmp_path):
    """``optimize --plot out/fig.<fmt>``: every figure as ``out/fig_<name>.<fmt>`` (the
    folder made), in that format; two uniform levels, so a convergence figure too."""
    from deformclosure.reports.options import options_of

    target = tmp_path / "out" / f"fig.{fmt}"
    opt = next(o for o in options_of("optimize") if o.name == "plot")
    rep = replace(notched_optimize, params={**notched_optimize.params,
                                            "plot": opt.convert(str(target), "--plot")})
    rep.save(report=False)
    written = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert {f"fig_{n}.{fmt}" for n in ("grasp", "quality", "force", "convergence")} \
        <= set(written), written
    assert all(n.startswith("fig_") and n.endswith(f".{fmt}") for n in written), written
    for n in written:
        assert _has_magic(tmp_path / "out" / n, fmt), n


def test_plot_folder_still_writes_pngs(tmp_path):
    from deformclosure.outputs import plot_file

    assert plot_file(tmp_path / "plots", "grasp") == tmp_path / "plots" / "grasp.png"
    (tmp_path / "a.b").mkdir()
    assert plot_file(tmp_path / "a.b", "grasp") == tmp_path / "a.b" / "grasp.png"
    assert plot_file(tmp_path / "c.PDF", "grasp") == tmp_path / "c_grasp.pdf"
    assert plot_file(tmp_path / "c.svg", "check", single=True) == tmp_path / "c.svg"
    # an existing file that is no folder (a device): PNG into it, for a single figure
    assert plot_file("/dev/null", "mesh", single=True) == Path("/dev/null")


def test_plot_to_a_device(capsys):
    rc, out, err = _cli(["mesh", ROOT / "examples" / "rectangle.json", "--plot", "/dev/null",
                         "-q"], capsys)
    assert rc == 0 and not err


@pytest.mark.parametrize("command", ["optimize", "plan", "check", "mesh"])
def test_unknown_plot_suffix_is_one_line_before_any_analysis(command, tmp_path, capsys,
                                                             monkeypatch):
    import importlib

    from deformclosure import reports

    module = importlib.import_module(f"deformclosure.reports.{reports.COMMANDS[command]}")

    def no_analysis(*a, **k):
        raise AssertionError("the analysis ran")

    monkeypatch.setattr(module, "run", no_analysis)
    args = {"optimize": ["--at", "15,0", "15,12"], "plan": [], "mesh": [],
            "check": ["--fingers", ROOT / "examples" / "fingers" / "l_shape.json"]}[command]
    rc, out, err = _cli([command, ROOT / "examples" / "notched_bar.json", *args, "--plot",
                         tmp_path / "fig.jpg"], capsys)
    assert rc == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0] == (f"error: --plot {tmp_path / 'fig.jpg'}: unknown picture format '.jpg'; "
                        "choose .png, .svg or .pdf (or a folder)")
    assert not (tmp_path / "fig.jpg").exists()
    # the library and the batch parser refuse it the same way, before the work
    with pytest.raises(DeformClosureError, match=r"unknown picture format '\.jpg'"):
        reports.run(command, ROOT / "examples" / "notched_bar.json",
                    {"plot": "x.jpg", **({"fingers": "f.json"} if command == "check" else {})})
    with pytest.raises(DeformClosureError, match="choose .png, .svg or .pdf"):
        reports.parse_argv(command, [*map(str, args), "--plot", "x.tiff"])


@pytest.mark.slow
def test_check_plot_without_escape_path_draws_the_check_and_a_note(tmp_path):
    """The README's L-shape is held with U_A = ∞: no empty escape panels, a note instead
    (placement-energy kernels: slow on a cold numba cache)."""
    from deformclosure import reports
    from deformclosure.plotting.escape import escape_note, plot_check_and_escape

    rep = reports.run("check", ROOT / "examples" / "l_shape.json",
                      {"fingers": ROOT / "examples" / "fingers" / "l_shape.json", "refine": 1})
    res, rel, fingers, inp = rep.result
    note = escape_note(rel)
    assert note is not None and "U_A = ∞" in note
    fig = plot_check_and_escape(inp.mesh, res, rel, fingers, units="mm")
    assert len(fig.axes) == 1
    assert note in [t.get_text() for t in fig.axes[0].texts]
    rep.params["plot"] = str(tmp_path / "check.svg")
    written = rep.save(report=False)
    assert written == [str(tmp_path / "check.svg")]
    assert _has_magic(tmp_path / "check.svg", "svg")


@pytest.mark.slow           # about 4 s: the verified row refined on two levels
def test_plan_plot_pdf_and_scale_stays_out_of_the_job_key(tmp_path):
    """``plan --plot dir/plan.pdf``: the map, the axes, the deformed top grasps and (the
    verified row refined on two levels, a loose ``rtol`` met there) the convergence, all
    PDF; ``--scale`` draws only, so a batch job's key ignores it."""
    from deformclosure import reports

    rep = reports.run("plan", ROOT / "examples" / "notched_bar.json",
                      {"pad_radius": 2.0, "grid_angles": 6, "grid_offsets": 16, "verify": 1,
                       "max_area": 4.0, "rtol": 0.5, "max_seconds": 6.0, "scale": 2.0,
                       "plot": str(tmp_path / "out" / "plan.pdf")})
    best = rep.data["axes"][0]
    assert best["verified"] and len(best["convergence"]) == best["n_levels"] >= 2
    written = [Path(p) for p in rep.save(report=False)]
    assert [p.name for p in written] == [f"plan_{n}.pdf" for n in
                                         ("quality_map", "top_axes", "top_grasps", "convergence")]
    assert all(_has_magic(p, "pdf") for p in written)
    key = reports.key_params("plan", rep.params)
    assert "scale" not in key and "plot" not in key


# ----------------------------------------------------------------------------- --animate


def _gif_frames(path: Path) -> list[np.ndarray]:
    """The frames of a GIF as RGB arrays, read back by Pillow."""
    from PIL import Image

    with Image.open(path) as im:
        assert im.format == "GIF" and im.is_animated
        frames = []
        for k in range(im.n_frames):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB")))
        assert im.info.get("loop") == 0
    return frames


def _red_pixels(rgb: np.ndarray) -> int:
    """Pixels of matplotlib's red (C3, tab:red = (214, 39, 40)), within GIF quantisation."""
    r, g, b = (rgb[..., i].astype(int) for i in range(3))
    return int(np.count_nonzero((r > 170) & (g < 90) & (b < 90)))


def test_animate_writes_one_frame_per_escape_axis(notched, tmp_path):
    """The pads' escape path as a GIF: one frame per axis of the path (it is shorter than
    MAX_FRAMES), readable by Pillow, all of one size, 1/FPS s each, looping; the part
    moves between frames; red (the saddle's title) in the saddle's frame only."""
    from deformclosure.plotting.animate import FPS, MAX_FRAMES, pad_escape_animation

    res = notched["res"]
    k = len(res.escape_path)
    assert 3 <= k <= MAX_FRAMES
    path = pad_escape_animation(res, tmp_path / "a" / "escape.gif")
    assert path == tmp_path / "a" / "escape.gif"
    frames = _gif_frames(path)
    assert len(frames) == k
    assert len({f.shape for f in frames}) == 1
    from PIL import Image

    with Image.open(path) as im:
        assert im.info["duration"] == pytest.approx(1000 / FPS, abs=1)
    assert not np.array_equal(frames[0], frames[-1])
    sad = res.saddle
    saddle = next(i for i, a in enumerate(res.escape_path)
                  if np.isclose(a.angle, sad.angle) and np.isclose(a.offset, sad.offset))
    red = [_red_pixels(f) for f in frames]
    assert red[saddle] > 0 and all(r == 0 for i, r in enumerate(red) if i != saddle), red
    # fewer frames asked: the start, the saddle and the end stay
    few = _gif_frames(pad_escape_animation(res, tmp_path / "few.gif", n=3))
    assert len(few) == len({0, saddle, k - 1})
    # no escape path: nothing written
    assert pp.escape_states(replace(res, escape_path=[])) == []
    assert pad_escape_animation(replace(res, escape_path=[]), tmp_path / "none.gif") is None
    assert not (tmp_path / "none.gif").exists()


def test_optimize_animate_writes_the_gif_beside_the_pictures(notched_optimize, tmp_path):
    """``optimize --plot out/fig.pdf --animate``: ``out/fig_escape.gif`` beside the PDFs,
    one frame per escape axis of the report's path; ``--plot out/`` → ``out/escape.gif``."""
    params = {**notched_optimize.params, "plot": str(tmp_path / "out" / "fig.pdf"),
              "animate": True}
    written = replace(notched_optimize, params=params).save(report=False)
    gif = tmp_path / "out" / "fig_escape.gif"
    assert str(gif) in written and written[-1] == str(gif)
    assert len(_gif_frames(gif)) == len(notched_optimize.data["escape_path"])
    from deformclosure import reports
    from deformclosure.outputs import animation_file

    assert animation_file(tmp_path / "folder", "escape") == tmp_path / "folder" / "escape.gif"
    assert "animate" not in reports.key_params("optimize", params)     # draws only: no new job


@pytest.mark.parametrize("command,params,message", [
    ("optimize", {"at": ("15,0", "15,12"), "animate": True}, "--animate: give --plot too"),
    ("check", {"fingers": "f.json", "animate": True}, "--animate: give --plot too"),
    ("optimize", {"at": ("15,0", "15,12"), "animate": True, "plot": "/dev/null"},
     "--animate: --plot /dev/null is a device or a pipe"),
    ("optimize", {"model": "paper", "at": ("15,0", "15,12"), "animate": True, "plot": "x/"},
     "--animate: animates the pads model's escape path"),
])
def test_animate_refusals_are_one_line_before_any_work(command, params, message, monkeypatch):
    """``--animate`` without ``--plot``, with ``--plot`` a device, or on the paper model:
    one line naming the option, before the part is read (the reader would fail first)."""
    import importlib

    from deformclosure import reports

    def no_reading(*a, **k):
        raise AssertionError("the part was read")

    module = importlib.import_module(f"deformclosure.reports.{reports.COMMANDS[command]}")
    for m in (module, importlib.import_module("deformclosure.reports.inputs")):
        if hasattr(m, "read_inputs"):
            monkeypatch.setattr(m, "read_inputs", no_reading)
    with pytest.raises(DeformClosureError) as err:
        reports.run(command, ROOT / "examples" / "notched_bar.json", params)
    assert str(err.value).startswith(message) and "\n" not in str(err.value)


@pytest.mark.slow            # the placement-energy kernels (compiled on a cold numba cache)
def test_check_animate_draws_the_placements_of_the_release(tmp_path):
    """``check --plot d/check.png --animate`` on the rectangle among its fingers (released
    through the gap): ``d/check_escape.gif``, one frame per placement of the escape path,
    the part's filled outline moving; the saddle's frame alone red."""
    from deformclosure import reports

    rep = reports.run("check", ROOT / "examples" / "rectangle.json",
                      {"fingers": ROOT / "examples" / "fingers" / "rectangle.json",
                       "refine": 1, "grid_steps": 12, "saddle_levels": 1,
                       "plot": str(tmp_path / "d" / "check.png"), "animate": True})
    written = rep.save(report=False)
    gif = tmp_path / "d" / "check_escape.gif"
    assert written[-1] == str(gif)
    rel = rep.result[1]
    P = np.asarray(rel.path)
    assert 2 <= len(P) <= 48
    frames = _gif_frames(gif)
    assert len(frames) == len(P)
    assert not np.array_equal(frames[0], frames[-1])
    red = [_red_pixels(f) for f in frames]
    assert red[rel.saddle] > 0 and all(r == 0 for i, r in enumerate(red) if i != rel.saddle)
