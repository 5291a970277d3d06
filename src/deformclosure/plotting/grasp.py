"""Pictures of a two-jaw grasp analysis (paper Figs. 5 and 6, and the energy landscape)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..units import length_scale
from .mesh import new_figure, plot_mesh, save_figure

__all__ = ["plot_quality_curve", "plot_deformed_grasp", "plot_energy_landscape",
           "save_grasp_plots", "plot_quality_map", "plot_top_grasps", "save_plan_plots"]


def plot_quality_curve(analysis, ax=None, units: str = "mm"):
    """``U_A``, ``U_L`` and ``Q`` against the jaw separation σ (paper Fig. 5).

    Parameters
    ----------
    analysis : GraspAnalysis
    ax : matplotlib Axes, optional
    units : str
        Length unit of the σ axis.

    Returns
    -------
    Axes
    """
    if ax is None:
        _, ax = new_figure((7, 4.5))
    s = 1.0 / length_scale(units)
    c = analysis.separation.curve
    sig = np.asarray(c["sigma"], float) * s
    conv = lambda v: np.array([np.nan if x is None else x for x in v], float) * 1e3  # noqa: E731
    UA, UL, Q = conv(c["U_A"]), conv(c["U_L"]), conv(c["Q"])
    order = np.argsort(sig, kind="stable")
    ax.plot(sig[order], Q[order], label="$Q = \\min(U_A, U_L)$", color="0.6", lw=5, alpha=0.6)
    ax.plot(sig[order], UA[order], label="$U_A$ (release energy)", color="C0", lw=1.2)
    ax.plot(sig[order], UL[order], label="$U_L$ (to elastic limit)", color="C1", lw=1.2)
    finite = np.isfinite(UA)
    if finite.any() and np.nanmax(UA[finite]) < 0.2 * np.nanmax(UL):
        ax.set_yscale("symlog", linthresh=max(np.nanmax(UA[finite]) / 10, 1e-12))
    sep = analysis.separation
    if sep.sigma_star is not None:
        ax.axvline(sep.sigma_star * s, color="C3", ls="--", lw=1)
        ax.plot([sep.sigma_star * s], [sep.quality * 1e3], "o", color="C3",
                label=f"$\\sigma^*$ = {sep.sigma_star * s:.4g} {units}")
    ax.axvline(analysis.limit.sigma_L * s, color="C1", ls=":", lw=1,
               label=f"$\\sigma_L$ = {analysis.limit.sigma_L * s:.4g} {units}")
    ax.set_xlabel(f"jaw separation σ ({units})")
    ax.set_ylabel("energy (mJ)")
    ax.set_title(f"jaws at nodes {analysis.jaws[0]}, {analysis.jaws[1]} ({sep.method})")
    ax.legend(fontsize=8)
    return ax


def plot_deformed_grasp(analysis, ax=None, units: str = "mm"):
    """The part deformed at σ*, coloured by strain magnitude, jaws drawn (paper Fig. 6).

    The linear displacement field for the jaw distance change ``σ0 − σ*`` is drawn to
    scale (it is exact for the linear model; large squeezes are only indicative).
    """
    if ax is None:
        _, ax = new_figure((6, 6))
    mesh = analysis.model.mesh
    sep = analysis.separation
    sigma = sep.sigma_star if sep.sigma_star is not None else analysis.limit.sigma0
    delta = abs(analysis.limit.sigma0 - sigma)
    lim = analysis.limit
    u = lim.displacement_per_length * delta
    if analysis.model.mode == "expanding":
        u = -u
    strain = lim.strain_per_length * delta
    plot_mesh(mesh, ax=ax, units=units, values=strain, displacement=u, cmap="magma",
              colorbar_label="strain magnitude")
    s = 1.0 / length_scale(units)
    xy = (mesh.nodes + u.reshape(-1, 2))[list(analysis.jaws)] * s
    ax.plot(xy[:, 0], xy[:, 1], "v", color="C2", markersize=11, markeredgecolor="k",
            label="jaws")
    ax.plot(xy[:, 0], xy[:, 1], "--", color="C2", lw=1)
    ax.set_title(f"deformed at σ = {sigma * s:.4g} {units}, max strain "
                 f"{strain.max():.3g} (e_L = {mesh.material.elastic_limit_strain:g})"
                 if mesh.material is not None else f"deformed at σ = {sigma * s:.4g} {units}")
    ax.legend(loc="upper right", fontsize=8)
    return ax


def plot_energy_landscape(analysis, ax=None, units: str = "mm", sigma: float | None = None):
    """Vertex energies over pairs of jaw positions (arclength × arclength) at σ.

    Start, saddle and the minimax escape path at σ* are marked.
    """
    if ax is None:
        _, ax = new_figure((6, 5.5))
    model = analysis.model
    mesh = model.mesh
    sep = analysis.separation
    if sigma is None:
        sigma = sep.sigma_star if sep.sigma_star is not None else analysis.limit.sigma0
    s = 1.0 / length_scale(units)
    nodes_on = np.concatenate([mesh.loops[i] for i in
                               ((0,) if model.mode == "contracting" else range(len(mesh.loops)))])
    # Arclength coordinate along the concatenated loops.
    arc = np.zeros(mesh.n_nodes)
    off = 0.0
    for i in ((0,) if model.mode == "contracting" else range(len(mesh.loops))):
        lp = mesh.loops[i]
        seg = np.linalg.norm(np.diff(mesh.nodes[np.append(lp, lp[0])], axis=0), axis=1)
        arc[lp] = off + np.concatenate([[0.0], np.cumsum(seg[:-1])])
        off += seg.sum()
    U = model.energies(sigma)
    pairs = model.graph.pairs
    order = np.argsort(arc[nodes_on])
    ids = nodes_on[order]
    pos = np.full(mesh.n_nodes, -1)
    pos[ids] = np.arange(len(ids))
    M = np.full((len(ids), len(ids)), np.nan)
    M[pos[pairs[:, 0]], pos[pairs[:, 1]]] = U
    M[pos[pairs[:, 1]], pos[pairs[:, 0]]] = U
    edges = np.append(arc[ids], off) * s
    pc = ax.pcolormesh(edges, edges, M * 1e3, cmap="viridis", shading="flat")
    ax.figure.colorbar(pc, ax=ax, label="vertex energy U (mJ)")
    # Each unordered pair is drawn above the diagonal: x = smaller arclength.
    def xy(pp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ar = arc[np.atleast_2d(pp)]
        return ar.min(axis=1) * s, ar.max(axis=1) * s

    ax.plot(*xy(np.array(analysis.jaws)), "o", color="w", markeredgecolor="k", ms=8, label="start")
    if sep.escape_path is not None and len(sep.escape_path) > 1:
        ax.plot(*xy(pairs[np.asarray(sep.escape_path)]), ".-", color="C3", lw=1, ms=4,
                label="escape path")
    if sep.saddle is not None:
        ax.plot(*xy(pairs[sep.saddle]), "X", color="C1", ms=10, markeredgecolor="k",
                label="saddle")
    ax.set_xlabel(f"jaw 1 arclength ({units})")
    ax.set_ylabel(f"jaw 2 arclength ({units})")
    ax.set_aspect("equal")
    ax.set_title(f"energy landscape at σ = {sigma * s:.4g} {units}")
    ax.legend(fontsize=8, loc="upper left")
    return ax


def save_grasp_plots(analysis, out_dir: str | Path, units: str = "mm") -> list[Path]:
    """Write ``quality.png``, ``deformed.png`` and ``landscape.png`` into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fn, size in (("quality.png", plot_quality_curve, (7, 4.5)),
                           ("deformed.png", plot_deformed_grasp, (6, 6)),
                           ("landscape.png", plot_energy_landscape, (6.5, 5.5))):
        fig, ax = new_figure(size)
        fn(analysis, ax=ax, units=units)
        save_figure(fig, out / name)
        paths.append(out / name)
    return paths


def _arclength(mesh, loop_ids) -> tuple[np.ndarray, float]:
    arc = np.full(mesh.n_nodes, np.nan)
    off = 0.0
    for i in loop_ids:
        lp = mesh.loops[i]
        seg = np.linalg.norm(np.diff(mesh.nodes[np.append(lp, lp[0])], axis=0), axis=1)
        arc[lp] = off + np.concatenate([[0.0], np.cumsum(seg[:-1])])
        off += seg.sum()
    return arc, off


def plot_quality_map(plan, ax=None, units: str = "mm"):
    """Quality of every jaw pair over (arclength of jaw 1) × (arclength of jaw 2)."""
    if ax is None:
        _, ax = new_figure((6.5, 5.5))
    mesh = plan.model.mesh
    loops = (0,) if plan.mode == "contracting" else range(len(mesh.loops))
    arc, total = _arclength(mesh, loops)
    ids = np.concatenate([mesh.loops[i] for i in loops])
    ids = ids[np.argsort(arc[ids])]
    pos = np.full(mesh.n_nodes, -1)
    pos[ids] = np.arange(len(ids))
    M = np.full((len(ids), len(ids)), np.nan)
    M[pos[plan.pairs[:, 0]], pos[plan.pairs[:, 1]]] = plan.quality
    M[pos[plan.pairs[:, 1]], pos[plan.pairs[:, 0]]] = plan.quality
    s = 1.0 / length_scale(units)
    edges = np.append(arc[ids], total) * s
    pc = ax.pcolormesh(edges, edges, M * 1e3, cmap="magma", shading="flat")
    ax.figure.colorbar(pc, ax=ax, label="quality Q (mJ)")
    top = plan.pairs[: min(5, len(plan.pairs))]
    if len(top):
        ar = arc[top]
        ax.plot(ar.min(1) * s, ar.max(1) * s, "o", mfc="none", mec="c", ms=9, label="top pairs")
        ax.legend(fontsize=8, loc="upper left")
    ax.set_xlabel(f"jaw 1 arclength ({units})")
    ax.set_ylabel(f"jaw 2 arclength ({units})")
    ax.set_aspect("equal")
    ax.set_title(f"grasp quality over jaw pairs (ε = {plan.epsilon:.3g} J)")
    return ax


def plot_top_grasps(plan, ax=None, units: str = "mm", n: int = 5):
    """The best ``n`` jaw pairs drawn on the part, numbered by rank."""
    if ax is None:
        _, ax = new_figure((6, 6))
    mesh = plan.model.mesh
    plot_mesh(mesh, ax=ax, units=units)
    s = 1.0 / length_scale(units)
    for r, (a, b) in enumerate(plan.pairs[:n]):
        xy = mesh.nodes[[a, b]] * s
        ax.plot(xy[:, 0], xy[:, 1], "-o", color=f"C{r % 10}", lw=2, ms=6,
                label=f"#{r + 1}: Q = {plan.quality[r] * 1e3:.3g} mJ")
    ax.legend(fontsize=8, loc="upper right")
    ax.set_title(f"top {min(n, len(plan.pairs))} jaw pairs")
    return ax


def save_plan_plots(plan, out_dir: str | Path, units: str = "mm") -> list[Path]:
    """Write ``quality_map.png`` and ``top_grasps.png`` into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fn, size in (("quality_map.png", plot_quality_map, (6.5, 5.5)),
                           ("top_grasps.png", plot_top_grasps, (6, 6))):
        fig, ax = new_figure(size)
        fn(plan, ax=ax, units=units)
        save_figure(fig, out / name)
        paths.append(out / name)
    return paths
