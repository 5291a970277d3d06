"""Pictures of a two-jaw grasp analysis (paper Figs. 5 and 6, and the energy landscape)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .mesh import figure_axes, legend_below, legend_outside, plot_mesh, save_plots

__all__ = ["plot_quality_curve", "plot_deformed_grasp", "plot_energy_landscape",
           "save_grasp_plots", "plot_quality_map", "plot_top_grasps", "save_plan_plots",
           "quality_color_range"]


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
    matplotlib.figure.Figure
        The figure holding ``ax`` (compose it with others, or save it).
    """
    ax, s = figure_axes(ax, (7, 4.5), units)
    c = analysis.separation.curve
    sig = np.asarray(c["sigma"], float) * s
    conv = lambda v: np.array([np.nan if x is None else x for x in v], float) * 1e3  # noqa: E731
    UA, UL, Q = conv(c["U_A"]), conv(c["U_L"]), conv(c["Q"])
    order = np.argsort(sig, kind="stable")
    quality_lines(ax, sig[order], Q[order], UA[order], UL[order])
    finite = np.isfinite(UA)
    if finite.any() and np.nanmax(UA[finite]) < 0.2 * np.nanmax(UL):
        ax.set_yscale("symlog", linthresh=max(np.nanmax(UA[finite]) / 10, 1e-12))
    sep = analysis.separation
    sigma_marks(ax, sep.sigma_star, sep.quality, analysis.limit.sigma_L, s, units)
    ax.set_xlabel(f"jaw separation σ ({units})")
    ax.set_ylabel("energy (mJ)")
    ax.set_title(f"jaws at nodes {analysis.jaws[0]}, {analysis.jaws[1]} ({sep.method})")
    legend_outside(ax)
    return ax.figure


def quality_lines(ax, sig: np.ndarray, Q: np.ndarray, UA: np.ndarray, UL: np.ndarray) -> None:
    """``Q`` (wide grey), ``U_A`` and ``U_L`` against σ (plot units, mJ)."""
    ax.plot(sig, Q, label="$Q = \\min(U_A, U_L)$", color="0.6", lw=5, alpha=0.6)
    ax.plot(sig, UA, label="$U_A$ (release energy)", color="C0", lw=1.2)
    ax.plot(sig, UL, label="$U_L$ (to elastic limit)", color="C1", lw=1.2)


def sigma_marks(ax, sigma_star: float | None, quality: float, sigma_L: float, s: float, units: str) -> None:
    """The optimal separation σ* with its quality (when there is one) and the elastic
    limit σ_L, as vertical lines (``s`` plot units per metre)."""
    if sigma_star is not None:
        ax.axvline(sigma_star * s, color="C3", ls="--", lw=1)
        ax.plot([sigma_star * s], [quality * 1e3], "o", color="C3",
                label=f"$\\sigma^*$ = {sigma_star * s:.4g} {units}")
    ax.axvline(sigma_L * s, color="C1", ls=":", lw=1, label=f"$\\sigma_L$ = {sigma_L * s:.4g} {units}")


def plot_deformed_grasp(analysis, ax=None, units: str = "mm"):
    """The part deformed at σ*, coloured by strain magnitude, jaws drawn (paper Fig. 6).

    The linear displacement field for the jaw distance change ``σ0 − σ*`` is drawn to
    scale (it is exact for the linear model; large squeezes are only indicative).
    """
    ax, s = figure_axes(ax, (6, 6), units)
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
    xy = (mesh.nodes + u.reshape(-1, 2))[list(analysis.jaws)] * s
    ax.plot(xy[:, 0], xy[:, 1], "v", color="C2", markersize=11, markeredgecolor="k",
            label="jaws")
    ax.plot(xy[:, 0], xy[:, 1], "--", color="C2", lw=1)
    ax.set_title(f"deformed at σ = {sigma * s:.4g} {units}, max strain "
                 f"{strain.max():.3g} (e_L = {mesh.material.elastic_limit_strain:g})"
                 if mesh.material is not None else f"deformed at σ = {sigma * s:.4g} {units}")
    legend_below(ax)   # the colour bar is on the right
    return ax.figure


def plot_energy_landscape(analysis, ax=None, units: str = "mm", sigma: float | None = None):
    """Vertex energies over pairs of jaw positions (arclength × arclength) at σ.

    Start, saddle and the minimax escape path at σ* are marked.
    """
    ax, s = figure_axes(ax, (6, 5.5), units)
    model = analysis.model
    mesh = model.mesh
    sep = analysis.separation
    if sigma is None:
        sigma = sep.sigma_star if sep.sigma_star is not None else analysis.limit.sigma0
    loop_ids = (0,) if model.mode == "contracting" else range(len(mesh.loops))
    nodes_on = np.concatenate([mesh.loops[i] for i in loop_ids])
    arc, off = _arclength(mesh, loop_ids, fill=0.0)   # along the concatenated loops
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
    legend_below(ax)   # the colour bar is on the right
    return ax.figure


def save_grasp_plots(analysis, out_dir: str | Path, units: str = "mm") -> list[Path]:
    """Write ``quality``, ``deformed`` and ``landscape`` for ``--plot out_dir`` (a folder of
    PNGs, or a .png/.svg/.pdf file setting the format and the names' stem,
    :func:`~deformclosure.plotting.mesh.figure_path`)."""
    return save_plots(analysis, out_dir, units, (("quality.png", plot_quality_curve, (7, 4.5)),
                                                 ("deformed.png", plot_deformed_grasp, (6, 6)),
                                                 ("landscape.png", plot_energy_landscape, (6.5, 5.5))))


def _arclength(mesh, loop_ids, fill: float = np.nan) -> tuple[np.ndarray, float]:
    """Arclength (m) of every node along the loops ``loop_ids`` one after the other
    (``fill`` elsewhere), and their total length."""
    arc = np.full(mesh.n_nodes, fill)
    off = 0.0
    for i in loop_ids:
        lp = mesh.loops[i]
        seg = np.linalg.norm(np.diff(mesh.nodes[np.append(lp, lp[0])], axis=0), axis=1)
        arc[lp] = off + np.concatenate([[0.0], np.cumsum(seg[:-1])])
        off += seg.sum()
    return arc, off


def _shown_pairs(plan, n: int) -> list[tuple[int, int, float, bool]]:
    """The pairs a plan proposes, best first: its exact ``top`` list (``refined``), or
    without one the best rows, pulling pairs left out unless the plan allows them.
    ``(a, b, quality (J), pulls)`` each."""
    pulls = getattr(plan, "pulls", np.zeros(len(plan.pairs), bool))
    if plan.refined:
        g = plan.model.graph
        return [(int(r.jaws[0]), int(r.jaws[1]), float(r.quality),
                 bool(plan.model.pulls[g.vertex_index(int(r.jaws[0]), int(r.jaws[1]))]))
                for r in plan.refined[:n]]
    allow = getattr(plan, "allow_pulling", False)
    out = []
    for i in range(len(plan.pairs)):
        if len(out) >= n or plan.quality[i] <= 0:
            break
        if pulls[i] and not allow:
            continue
        out.append((int(plan.pairs[i, 0]), int(plan.pairs[i, 1]), float(plan.quality[i]),
                    bool(pulls[i])))
    return out


def quality_color_range(quality: np.ndarray, percentile: float = 5.0,
                        decades: float = 4.0) -> tuple[float, float] | None:
    """Colour range (J) of a plan's quality map: from the ``percentile``-th percentile of
    the positive qualities, but at most ``decades`` below the best, to the best.

    Most pairs of a part cannot hold it (``Q = 0``) and the positive qualities span many
    decades, so a linear scale from 0 shows one bright cell; this range, on a log scale,
    shows the pairs that can hold. ``None`` when no quality is positive.
    """
    q = np.asarray(quality, float)
    q = q[np.isfinite(q) & (q > 0)]
    if not q.size:
        return None
    hi = float(q.max())
    lo = max(float(np.percentile(q, percentile)), hi * 10.0 ** -decades)
    return (min(lo, hi / 10.0) if lo >= hi else lo), hi


def plot_quality_map(plan, ax=None, units: str = "mm"):
    """Quality of every jaw pair over (arclength of jaw 1) × (arclength of jaw 2).

    Colour: ``Q`` in mJ on a log scale over :func:`quality_color_range` (the 5th
    percentile of the positive qualities, at most four decades below the best, to the
    best); pairs that cannot hold (``Q = 0``) light grey, pairs flagged ``pulls`` (a jaw
    would have to pull) hatched, the proposed (``top``) pairs numbered in cyan circles.
    The legend sits below the axes, off the map.
    """
    from matplotlib.colors import LogNorm
    from matplotlib.patches import Patch

    ax, s = figure_axes(ax, (6.5, 6.5), units)
    mesh = plan.model.mesh
    loops = (0,) if plan.mode == "contracting" else range(len(mesh.loops))
    arc, total = _arclength(mesh, loops)
    ids = np.concatenate([mesh.loops[i] for i in loops])
    ids = ids[np.argsort(arc[ids])]
    pos = np.full(mesh.n_nodes, -1)
    pos[ids] = np.arange(len(ids))
    ia, ib = pos[plan.pairs[:, 0]], pos[plan.pairs[:, 1]]
    M = np.full((len(ids), len(ids)), np.nan)
    M[ia, ib] = M[ib, ia] = plan.quality * 1e3
    edges = np.append(arc[ids], total) * s
    rng = quality_color_range(plan.quality)
    import matplotlib

    cmap = matplotlib.colormaps["magma"].with_extremes(under="0.85", bad="white")
    if rng is None:
        pc = ax.pcolormesh(edges, edges, M, cmap=cmap, shading="flat", vmin=0.0, vmax=1.0)
    else:
        lo, hi = rng[0] * 1e3, rng[1] * 1e3
        Mc = np.where(M > 0, M, np.where(np.isnan(M), np.nan, lo * 1e-3))   # zeros: "under"
        pc = ax.pcolormesh(edges, edges, Mc, cmap=cmap, shading="flat",
                           norm=LogNorm(vmin=lo, vmax=hi))
    ax.figure.colorbar(pc, ax=ax, label="quality Q (mJ, log scale)", extend="min",
                       shrink=0.85)
    handles = [Patch(facecolor="0.85", edgecolor="0.5", label="Q = 0 (cannot hold)")]
    pulls = getattr(plan, "pulls", None)
    if pulls is not None and np.any(pulls):
        P = np.zeros_like(M)
        P[ia[pulls], ib[pulls]] = P[ib[pulls], ia[pulls]] = 1.0
        centres = 0.5 * (edges[:-1] + edges[1:])
        ax.contourf(centres, centres, P, levels=[0.5, 1.5], colors="none", hatches=["////"])
        handles.append(Patch(facecolor="none", edgecolor="0.3", hatch="////",
                             label="pulls: a jaw would have to pull"))
    shown = _shown_pairs(plan, 5)
    if shown:
        for r, (a, b, _q, _p) in enumerate(shown):
            u, v = sorted((arc[a] * s, arc[b] * s))
            ax.plot([u], [v], "o", mfc="none", mec="c", ms=11, mew=1.5)
            ax.annotate(str(r + 1), (u, v), color="c", fontsize=8, ha="center", va="center")
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], marker="o", ls="none", mfc="none", mec="c", ms=9,
                              label="top pairs (rank)"))
    ax.legend(handles=handles, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.12),
              ncol=min(3, len(handles)), frameon=False)
    ax.set_xlabel(f"jaw 1 arclength ({units})")
    ax.set_ylabel(f"jaw 2 arclength ({units})")
    ax.set_aspect("equal")
    ax.set_title(f"quality of every jaw pair (each within ε = {plan.epsilon:.2g} J)")
    return ax.figure


def plot_top_grasps(plan, ax=None, units: str = "mm", n: int = 5):
    """The proposed jaw pairs (the plan's ``top`` list) drawn on the part, by rank.

    Pairs flagged ``pulls`` are drawn dashed and labelled (they are proposed only when
    the plan allows pulling). The legend sits to the right of the axes, off the part.
    """
    ax, s = figure_axes(ax, (8, 6), units)
    mesh = plan.model.mesh
    plot_mesh(mesh, ax=ax, units=units)
    shown = _shown_pairs(plan, n)
    for r, (a, b, q, pulls) in enumerate(shown):
        xy = mesh.nodes[[a, b]] * s
        ax.plot(xy[:, 0], xy[:, 1], "--o" if pulls else "-o", color=f"C{r % 10}", lw=2, ms=6,
                label=f"#{r + 1}: nodes {a}–{b}, Q = {q * 1e3:.3g} mJ"
                      + (" (pulls)" if pulls else ""))
        mid = xy.mean(axis=0)
        ax.annotate(f"#{r + 1}", mid, color=f"C{r % 10}", fontsize=8, fontweight="bold",
                    xytext=(3, 3), textcoords="offset points")
    if shown:
        legend_outside(ax)
    ax.set_title(f"top {len(shown)} jaw pairs" + ("" if getattr(plan, "allow_pulling", False)
                                                  else " (pulling pairs left out)"))
    return ax.figure


def save_plan_plots(plan, out_dir: str | Path, units: str = "mm") -> list[Path]:
    """Write ``quality_map`` and ``top_grasps`` for ``--plot out_dir`` (see
    :func:`save_grasp_plots`)."""
    return save_plots(plan, out_dir, units, (("quality_map.png", plot_quality_map, (6.5, 6.5)),
                                             ("top_grasps.png", plot_top_grasps, (8, 6))))
