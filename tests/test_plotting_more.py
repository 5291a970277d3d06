"""Every public plot function: a matplotlib Figure with the expected axes and artists,
legends off the data, and the ``save_*`` writers (complements ``test_plotting.py``;
figure objects, not pixels, Agg backend)."""

from __future__ import annotations

import importlib
from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

import deformclosure as dc  # noqa: E402
from deformclosure.errors import DeformClosureError  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PLOT_MODULES = ["mesh", "part", "dspace", "escape", "grasp", "pads"]


def _mod(name):
    return importlib.import_module(f"deformclosure.plotting.{name}")


def public_plot_functions() -> list[str]:
    out = []
    for m in PLOT_MODULES:
        try:
            mod = _mod(m)
        except ImportError:
            continue
        out += [f"{m}.{n}" for n in getattr(mod, "__all__", ()) if n.startswith("plot_")]
    return sorted(out)


@pytest.fixture(scope="module")
def cases():
    from deformclosure.dspace import deform_closure, dfree_slice, load_fingers
    from deformclosure.pads import GraspAxis, Pad, pad_grasp
    from deformclosure.pads.optimize import optimize_pads
    from deformclosure.planning.pads import plan_pads

    part = dc.Part.from_file(ROOT / "examples" / "rectangle.json")
    mesh = dc.mesh_part(part)
    notched_part = dc.notched_part()
    notched_part = replace(notched_part, mesh_options=replace(notched_part.mesh_options,
                                                              max_area=1e-6))
    notched = dc.mesh_part(notched_part)
    refined = pad_grasp(part, GraspAxis.at([0.006, 0.010], 0.0), Pad(0.0, 0.001), mesh=mesh,
                        n_angles=8, n_offsets=8, refine=2)
    fingers = load_fingers(ROOT / "examples" / "fingers" / "rectangle.json")
    jaws = (mesh.find_node([0, 0.010]), mesh.find_node([0.012, 0.010]))
    return {
        "part": part, "mesh": mesh, "fingers": fingers,
        "paper": dc.optimize_separation(mesh, jaws),
        "plan": dc.plan_grasps(mesh, top=3, n_sigma=40),
        "pads": refined.finest,
        "pads_refined": refined,
        # round pads in the notched bar's notches: a finite barrier, an escape path
        "pads_escape": optimize_pads(notched,
                                     GraspAxis(np.pi / 2, -0.015), Pad(0.0, 2e-3), n_angles=8,
                                     n_offsets=8, noise=False),
        "pad_plan": plan_pads(mesh, Pad(0.0, 1e-3), n_angles=4, n_offsets=4, n_sigma=12, top=2),
        # the notched bar: a verified held row (about 1 s), and one verified on two mesh
        # levels (its convergence rows; about 2 s)
        "pad_plan_held": plan_pads(notched, Pad(0.0, 2e-3), n_angles=6, n_offsets=16, n_sigma=16,
                                   top=1),
        "pad_plan_refined": plan_pads(notched, Pad(0.0, 2e-3), n_angles=6, n_offsets=16,
                                      n_sigma=16, top=1, part=notched_part, rtol=1e-3,
                                      max_seconds=6.0),
        "closure": deform_closure(mesh, fingers),
        "slice": dfree_slice(mesh, None, int(mesh.outer_loop[3]), fingers, resolution=16),
    }


@pytest.fixture(scope="module")
def release(cases):
    """An escape of the rectangle among its fingers (compiles the placement-energy kernels
    on a cold numba cache)."""
    from deformclosure.dspace import release_energy_fingers

    return release_energy_fingers(cases["mesh"], cases["fingers"], n_translation=12, levels=1,
                                  noise=False)


#: name -> (call(cases, release, ax), number of axes the figure has when ax is None)
CALLS = {
    "mesh.plot_mesh": (lambda c, r, ax: _mod("mesh").plot_mesh(c["mesh"], ax=ax), 1),
    "part.plot_outline": (lambda c, r, ax: _mod("part").plot_outline(c["part"], ax=ax), 1),
    "dspace.plot_fingers": (lambda c, r, ax: _mod("dspace").plot_fingers(c["fingers"], ax=ax), 1),
    "dspace.plot_configuration": (lambda c, r, ax: _mod("dspace").plot_configuration(
        c["mesh"], ax=ax), 1),
    "dspace.plot_slice": (lambda c, r, ax: _mod("dspace").plot_slice(
        c["slice"], mesh=c["mesh"], fingers=c["fingers"], ax=ax), 1),
    "dspace.plot_check": (lambda c, r, ax: _mod("dspace").plot_check(
        c["mesh"], c["closure"], c["fingers"], ax=ax), 1),
    "escape.plot_escape_path": (lambda c, r, ax: _mod("escape").plot_escape_path(
        c["mesh"], r, c["fingers"], ax=ax), 1),
    "escape.plot_escape_energy": (lambda c, r, ax: _mod("escape").plot_escape_energy(r, ax=ax), 1),
    "escape.plot_check_and_escape": (lambda c, r, ax: _mod("escape").plot_check_and_escape(
        c["mesh"], c["closure"], r, c["fingers"]), 3),
    "grasp.plot_quality_curve": (lambda c, r, ax: _mod("grasp").plot_quality_curve(
        c["paper"], ax=ax), 1),
    "grasp.plot_deformed_grasp": (lambda c, r, ax: _mod("grasp").plot_deformed_grasp(
        c["paper"], ax=ax), 2),                                     # and the strain colour bar
    "grasp.plot_energy_landscape": (lambda c, r, ax: _mod("grasp").plot_energy_landscape(
        c["paper"], ax=ax), 2),                                     # and the energy colour bar
    "grasp.plot_quality_map": (lambda c, r, ax: _mod("grasp").plot_quality_map(c["plan"], ax=ax),
                               2),                                  # the map and its colour bar
    "grasp.plot_top_grasps": (lambda c, r, ax: _mod("grasp").plot_top_grasps(c["plan"], ax=ax), 1),
    "pads.plot_pad_quality": (lambda c, r, ax: _mod("pads").plot_pad_quality(c["pads"], ax=ax), 1),
    "pads.plot_pad_grasp": (lambda c, r, ax: _mod("pads").plot_pad_grasp(
        c["pads"], c["mesh"], ax=ax), 2),                           # and the strain colour bar
    "pads.plot_pad_plan": (lambda c, r, ax: _mod("pads").plot_pad_plan(
        c["pad_plan"], c["mesh"], ax=ax), 1),
    "pads.plot_force_squeeze": (lambda c, r, ax: _mod("pads").plot_force_squeeze(
        c["pads"], ax=ax), 1),
    "pads.plot_convergence": (lambda c, r, ax: _mod("pads").plot_convergence(
        c["pads_refined"].convergence(), ax=ax), 2),                # Q* and its twin σ* axis
    "pads.plot_pad_quality_map": (lambda c, r, ax: _mod("pads").plot_pad_quality_map(
        c["pad_plan_held"], ax=ax), 2),                                 # the map and its colour bar
    "pads.plot_plan_convergence": (lambda c, r, ax: _mod("pads").plot_plan_convergence(
        c["pad_plan_refined"], ax=ax), 2),
    # figures of their own (small multiples): no ax
    "pads.plot_escape_strip": (lambda c, r, ax: _mod("pads").plot_escape_strip(
        c["pads_escape"]), None),
    "pads.plot_pad_top_grasps": (lambda c, r, ax: _mod("pads").plot_pad_top_grasps(
        c["pad_plan_held"]), None),
}
#: Figures of small multiples: they make their own figure (no ``ax``).
OWN_FIGURE = {"escape.plot_check_and_escape", "pads.plot_escape_strip",
              "pads.plot_pad_top_grasps"}
#: These need an escape, which compiles the placement-energy kernels (about a minute of CPU
#: on a cold numba cache): in the slow set.
NEEDS_RELEASE = {"escape.plot_escape_path", "escape.plot_escape_energy",
                 "escape.plot_check_and_escape"}


def _params(names):
    return [pytest.param(n, marks=pytest.mark.slow) if n in NEEDS_RELEASE else n
            for n in sorted(names)]


@pytest.fixture(autouse=True)
def _no_figures_left():
    plt.close("all")
    yield
    plt.close("all")


def _overlap_px(a, b) -> float:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return max(w, 0.0) * max(h, 0.0)


def _draw(name, cases, request, ax=None):
    rel = request.getfixturevalue("release") if name in NEEDS_RELEASE else None
    return CALLS[name][0](cases, rel, ax)


def test_every_public_plot_function_is_checked_here():
    assert sorted(CALLS) == public_plot_functions()


@pytest.mark.parametrize("name", _params(CALLS))
def test_plot_returns_a_figure_with_its_axes(name, cases, request):
    fig = _draw(name, cases, request)
    assert isinstance(fig, Figure), type(fig)
    assert plt.get_fignums() == [fig.number], "exactly one new figure"
    if CALLS[name][1] is not None:
        assert len(fig.axes) == CALLS[name][1], [a.get_label() for a in fig.axes]
    for ax in fig.axes[:1]:
        assert ax.get_children() and (ax.lines or ax.collections or ax.patches or ax.images)


@pytest.mark.parametrize("name", _params(CALLS))
def test_legends_are_off_the_data(name, cases, request):
    """A legend must not cover any axes of its figure — its own plotting area or a colour
    bar beside it (issue 24: landscape.png's legend sat behind its colour bar)."""
    fig = _draw(name, cases, request)
    fig.canvas.draw()
    inside = []
    legends = [(ax, ax.get_legend()) for ax in fig.axes] + [(None, lg) for lg in fig.legends]
    for owner, leg in legends:
        if leg is None:
            continue
        for ax in fig.axes:
            px = _overlap_px(leg.get_window_extent(), ax.get_window_extent())
            if px > 1.0:
                inside.append(f"{ax.get_title() or ax.get_label()!r}: {px:.0f} px²")
    assert not inside, f"{name}: legend over the axes: {inside}"


@pytest.mark.parametrize("name", _params(n for n in CALLS if n not in OWN_FIGURE))
def test_plot_draws_into_given_axes(name, cases, request):
    fig, (left, ax) = plt.subplots(1, 2)
    before = len(ax.get_children())
    assert _draw(name, cases, request, ax=ax) is fig
    assert len(ax.get_children()) > before
    assert not left.lines and not left.collections and not left.patches
    assert plt.get_fignums() == [fig.number]


def _labelled_lines(ax, prefix="#"):
    return [ln for ln in ax.lines if isinstance(ln, Line2D) and ln.get_label().startswith(prefix)]


def test_top_grasps_draws_one_labelled_line_per_proposed_pair(cases):
    plan = cases["plan"]
    assert len(plan.refined) == 3               # top=3
    for n in (1, 2, 5):
        fig = _mod("grasp").plot_top_grasps(plan, n=n)
        lines = _labelled_lines(fig.axes[0])
        assert len(lines) == min(n, len(plan.refined))
        a, b = plan.refined[0].jaws
        xy = cases["mesh"].nodes[[a, b]] / 1e-3
        np.testing.assert_allclose(lines[0].get_xydata(), xy)     # rank 1 first, in mm
        plt.close(fig)


def test_pad_plan_draws_its_best_axes(cases):
    plan = cases["pad_plan"]
    fig = _mod("pads").plot_pad_plan(plan, cases["mesh"], n=5)
    held = 0
    for row in plan.rows[:5]:
        if row["quality"] <= 0:
            break
        held += 1
    assert len(_labelled_lines(fig.axes[0])) == held


@pytest.mark.slow
def test_escape_path_outlines_and_energy_profile(cases, release):
    rel = release
    fig = _mod("escape").plot_escape_energy(rel)
    ax = fig.axes[0]
    prof = [ln for ln in ax.lines if len(ln.get_xdata()) == len(rel.path_energy)]
    assert prof, "the energy profile has one point per placement of the path"
    np.testing.assert_allclose(prof[0].get_ydata(), rel.path_energy)
    assert np.all(np.diff(prof[0].get_xdata()) >= 0), "path length never decreases"
    plt.close(fig)
    fig = _mod("escape").plot_escape_path(cases["mesh"], rel, cases["fingers"], n_outlines=4)
    n_loops = len(cases["mesh"].loops)
    outlines = [ln for ln in fig.axes[0].lines if ln.get_label() != "centroid path"
                and len(ln.get_xdata()) > 2]
    assert len(outlines) >= n_loops and len(outlines) % n_loops == 0
    assert len(outlines) <= (4 + 3) * n_loops


def test_save_writers_write_pngs_and_close_their_figures(cases, tmp_path):
    g, p, m = _mod("grasp"), _mod("pads"), _mod("mesh")
    files = [*g.save_grasp_plots(cases["paper"], tmp_path / "paper"),
             *g.save_plan_plots(cases["plan"], tmp_path / "plan"),
             *p.save_pad_plots(cases["pads"], cases["mesh"], tmp_path / "pads")]
    m.save_mesh_plot(cases["mesh"], tmp_path / "mesh.png")
    files.append(tmp_path / "mesh.png")
    pads = {Path(f).stem for f in files if "pads" in Path(f).parts}
    assert pads == {"grasp", "quality", "force"} | ({"escape"} if cases["pads"].escape_path
                                                    else set()), pads
    assert len(files) == 3 + 2 + len(pads) + 1
    for f in files:
        assert Path(f).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f
        assert Path(f).stat().st_size > 1000
    assert plt.get_fignums() == []
    leftovers = [q.name for q in tmp_path.rglob(".*")]
    assert not leftovers, leftovers


def test_save_figure_failure_is_one_line_and_closes_the_figure(tmp_path):
    fig, ax = _mod("mesh").new_figure()
    ax.plot([0, 1], [0, 1])
    with pytest.raises(DeformClosureError) as info:
        _mod("mesh").save_figure(fig, tmp_path / "missing" / "x.png")
    assert "\n" not in str(info.value) and "x.png" in str(info.value)
    assert plt.get_fignums() == []
