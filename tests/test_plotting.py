"""Plot functions draw into the axes they are given and return its figure, so users can
compose them (issue 13, item 4). Checked on figure objects, not pixels."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import deformclosure as dc  # noqa: E402
from deformclosure.dspace import deform_closure, dfree_slice, load_fingers  # noqa: E402
from deformclosure.pads import GraspAxis, Pad, pad_grasp  # noqa: E402
from deformclosure.plotting import dspace as pd, grasp as pg, mesh as pm, pads as pp  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def cases():
    part = dc.Part.from_file(ROOT / "examples" / "rectangle.json")
    mesh = dc.mesh_part(part)
    fingers = load_fingers(ROOT / "examples" / "fingers" / "rectangle.json")
    paper = dc.optimize_separation(mesh, (mesh.find_node([0, 0.010]), mesh.find_node([0.012, 0.010])))
    pads = pad_grasp(part, GraspAxis.at([0.006, 0.010], 0.0), Pad(0.0, 0.001), mesh=mesh,
                     n_angles=8, n_offsets=8).finest
    node = int(mesh.outer_loop[3])
    return {"mesh": mesh, "fingers": fingers, "paper": paper, "pads": pads,
            "closure": deform_closure(mesh, fingers),
            "slice": dfree_slice(mesh, None, node, fingers, resolution=16)}


def _calls(c):
    m, f = c["mesh"], c["fingers"]
    return [
        ("plot_mesh", lambda ax: pm.plot_mesh(m, ax=ax)),
        ("plot_fingers", lambda ax: pd.plot_fingers(f, ax=ax)),
        ("plot_configuration", lambda ax: pd.plot_configuration(m, ax=ax)),
        ("plot_slice", lambda ax: pd.plot_slice(c["slice"], mesh=m, fingers=f, ax=ax)),
        ("plot_check", lambda ax: pd.plot_check(m, c["closure"], f, ax=ax)),
        ("plot_quality_curve", lambda ax: pg.plot_quality_curve(c["paper"], ax=ax)),
        ("plot_deformed_grasp", lambda ax: pg.plot_deformed_grasp(c["paper"], ax=ax)),
        ("plot_energy_landscape", lambda ax: pg.plot_energy_landscape(c["paper"], ax=ax)),
        ("plot_pad_quality", lambda ax: pp.plot_pad_quality(c["pads"], ax=ax)),
        ("plot_pad_grasp", lambda ax: pp.plot_pad_grasp(c["pads"], m, ax=ax)),
    ]


def test_plots_compose_in_one_figure_and_return_it(cases):
    calls = _calls(cases)
    fig, axes = plt.subplots(2, 5, figsize=(20, 8))
    for ax, (name, call) in zip(axes.ravel(), calls):
        before = len(ax.get_children())
        assert call(ax) is fig, name
        assert len(ax.get_children()) > before, f"{name} drew nothing into its axes"
    assert len(fig.axes) >= len(calls)         # colour bars may add axes, never figures
    assert plt.get_fignums() == [fig.number]
    plt.close(fig)


def test_without_axes_each_makes_its_own_figure(cases):
    for name, call in _calls(cases)[:3]:
        fig = call(None)
        assert isinstance(fig, matplotlib.figure.Figure) and fig.axes, name
        plt.close(fig)
    assert not plt.get_fignums()
    assert np.isfinite(cases["pads"].sigma0)
