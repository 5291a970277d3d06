"""Pictures of pad grasps (SPEC §6): the quality curve, the gripper on the part, plans."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..units import length_scale
from .grasp import quality_lines, sigma_marks
from .mesh import figure_axes, save_plots, legend_outside

__all__ = ["plot_pad_quality", "plot_pad_grasp", "plot_pad_plan", "draw_pads", "save_pad_plots"]


def _nan(v) -> np.ndarray:
    return np.array([np.nan if x is None else x for x in v], float)


def _outline(ax, mesh, s: float) -> None:
    """The part's boundary loops, lightly filled, in plot units (``s`` per metre)."""
    for lp in mesh.loops:
        P = mesh.nodes[np.append(lp, lp[0])] * s
        ax.plot(P[:, 0], P[:, 1], color="k", lw=1)
    ax.fill(*(mesh.nodes[mesh.outer_loop] * s).T, color="C0", alpha=0.15, lw=0)
    for lp in mesh.hole_loops:
        ax.fill(*(mesh.nodes[lp] * s).T, color="white", lw=0)


def plot_pad_quality(result, ax=None, units: str = "mm"):
    """``U``, ``U_A``, ``U_L`` and ``Q`` (mJ) against the pad separation σ: the picture of
    :func:`deformclosure.plotting.grasp.plot_quality_curve` with the grasp energy ``U``.

    Parameters
    ----------
    result : PadGraspResult
    ax : matplotlib Axes, optional
    units : str
        Length unit of σ; energies are drawn in mJ.

    Returns
    -------
    matplotlib.figure.Figure
        ``ax.figure``, to compose with others or save.
    """
    ax, s = figure_axes(ax, (7, 4.5), units)
    c = result.curve
    sig = _nan(c["sigma"]) * s
    quality_lines(ax, sig, _nan(c["Q"]) * 1e3, _nan(c["U_A"]) * 1e3, _nan(c["U_L"]) * 1e3)
    ax.plot(sig, _nan(c["U"]) * 1e3, color="k", lw=0.8, ls="--", label="$U$ (grasp energy)")
    sigma_marks(ax, result.sigma_star, result.quality, result.sigma_L, s, units)
    ax.set_xlabel(f"pad separation σ ({units})")
    ax.set_ylabel("energy (mJ)")
    ax.set_title(f"pads W = {result.pad.width * s:.3g}, ρ = {result.pad.radius * s:.3g} {units}: "
                 f"{result.verdict}")
    legend_outside(ax)
    return ax.figure


def _capsule(pad, axis, z: float, side: int, s: float, depth: float) -> np.ndarray:
    """Outline (in plot units) of a pad whose face is at axial position ``z``."""
    a, n = axis.direction, axis.normal
    h, r = 0.5 * pad.width, pad.radius
    t = np.linspace(0, np.pi / 2, 24)
    # Face side of the capsule in (x, s) with s measured from the face towards the part.
    right = np.column_stack([h + r * np.sin(t), r - r * np.cos(t)])
    prof = np.vstack([right[::-1] * [-1, 1], right])
    back = np.array([[h + r, r + depth], [-h - r, r + depth]])
    pts = np.vstack([prof, back])
    x, sd = pts[:, 0], pts[:, 1]
    o = np.asarray(axis.origin) + axis.offset * n
    P = o[None] + x[:, None] * n[None] + (z - side * sd)[:, None] * a[None]
    return P * s


def draw_pads(ax, result, sigma: float | None = None, units: str = "mm", **kw):
    """Draw both pads of ``result`` at separation ``sigma`` (default: first touch)."""
    s = 1.0 / length_scale(units)
    curve = result.start_curve
    touch = curve.touch
    sigma = result.sigma0 if sigma is None else sigma
    # Pad A moves along +a and pad B along −a as the squeeze δ grows (both modes).
    delta = float(curve.delta(sigma))
    za, zb = touch.z_a + 0.5 * delta, touch.z_b - 0.5 * delta
    depth = 0.15 * max(result.sigma0, result.pad.half_span)
    if touch.expanding:                     # back to back inside the hole
        depth = min(depth, 0.45 * max(za - zb, 1e-12))
    for z, side in ((za, 1), (zb, -1)):
        P = _capsule(result.pad, result.axis, z, side, s, depth)
        ax.fill(P[:, 0], P[:, 1], color=kw.get("color", "0.35"), alpha=kw.get("alpha", 0.8), lw=0)
    return ax


def plot_pad_grasp(result, mesh, ax=None, units: str = "mm"):
    """The part with the closing axis, the pads at σ*, the contact points and the escape.

    Parameters
    ----------
    result : PadGraspResult
    mesh : Mesh
    ax : matplotlib Axes, optional
    units : str

    Returns
    -------
    matplotlib.figure.Figure
        The figure holding ``ax`` (compose it with others, or save it).
    """
    ax, s = figure_axes(ax, (6, 6), units)
    _outline(ax, mesh, s)
    a = result.axis.direction
    c = result.contacts * s
    mid = c.mean(axis=0)
    L = 0.75 * mesh.diameter * s
    ax.plot([mid[0] - L * a[0], mid[0] + L * a[0]], [mid[1] - L * a[1], mid[1] + L * a[1]],
            color="C3", lw=0.8, ls="-.")
    draw_pads(ax, result, result.sigma_star, units)
    ax.plot(c[:, 0], c[:, 1], "o", color="C3", ms=4)
    for ax_i in result.escape_path[1:]:
        p = ax_i.point * s
        d = ax_i.direction
        ax.plot([p[0] - L * d[0], p[0] + L * d[0]], [p[1] - L * d[1], p[1] + L * d[1]],
                color="C2", lw=0.5, alpha=0.6)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({units})")
    ax.set_ylabel(f"y ({units})")
    sig = "-" if result.sigma_star is None else f"{result.sigma_star * s:.4g} {units}"
    ax.set_title(f"{result.verdict}: σ* = {sig}, Q* = {result.quality * 1e3:.4g} mJ")
    return ax.figure


def plot_pad_plan(plan, mesh, ax=None, units: str = "mm", n: int = 5):
    """The best ``n`` grasp axes of a pad plan drawn on the part, ranked."""
    ax, s = figure_axes(ax, (6, 6), units)
    _outline(ax, mesh, s)
    for k, row in enumerate(plan.rows[:n]):
        if row["quality"] <= 0:
            break
        c = np.asarray(row["contacts"]) * s
        col = f"C{k % 10}"
        ax.plot(c[:, 0], c[:, 1], "--o", color=col, lw=1, ms=4,
                label=f"#{k + 1}: {np.degrees(row['angle']) % 180:.0f}°, Q* = {row['quality'] * 1e3:.3g} mJ"
                      f" ({row['verdict']})")
        res = next((r for r in plan.top if np.allclose(r.contacts * s, c)), None)
        if res is not None and res.sigma_star is not None:   # the gripper pose at σ*
            draw_pads(ax, res, res.sigma_star, units, color=col, alpha=0.55)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({units})")
    ax.set_ylabel(f"y ({units})")
    ax.set_title("best grasp axes (pads at σ* for the verified ones)")
    if ax.get_legend_handles_labels()[0]:
        legend_outside(ax)
    return ax.figure


def save_pad_plots(result, mesh, out_dir: str | Path, units: str = "mm") -> list[Path]:
    """Write ``quality.png`` and ``grasp.png`` into ``out_dir``; return the paths."""
    def grasp(res, ax, units):
        return plot_pad_grasp(res, mesh, ax=ax, units=units)

    return save_plots(result, out_dir, units, (("quality.png", plot_pad_quality, (7, 4.5)),
                                               ("grasp.png", grasp, (6, 6))))
