"""Pictures of fingers, D-space slices and deform-closure checks (paper Figs. 2-3).

matplotlib is imported lazily; every function takes ``ax=None`` (a new figure is made)
and returns the axes. Coordinates are drawn in ``units`` (default metres).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..units import length_scale
from .mesh import legend_outside

__all__ = ["plot_fingers", "plot_configuration", "plot_slice", "plot_check"]


def _axes(ax: Any) -> Any:
    if ax is None:
        from .mesh import new_figure

        _, ax = new_figure()
    return ax


def plot_fingers(fingers: Sequence[Any], ax: Any = None, units: str = "m",
                 bounds: tuple[float, float, float, float] | None = None, labels: bool = True,
                 color: str = "0.35") -> Any:
    """Draw finger bodies (points as crosses, half-planes clipped to ``bounds``); each
    finger draws itself (:meth:`deformclosure.contact.bodies.Finger.plot`).

    Parameters
    ----------
    fingers : sequence of Finger
    ax : matplotlib Axes, optional
    units : str
        Axis length unit.
    bounds : (xmin, xmax, ymin, ymax), optional
        Region (in ``units``) used to clip half-planes; default the current axes limits.
    labels : bool
        Number the fingers.
    color : str
    """
    ax = _axes(ax)
    s = length_scale(units)
    if bounds is None:
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        bounds = (x0, x1, y0, y1)
    for i, f in enumerate(fingers):
        anchor = f.plot(ax, scale=s, bounds=bounds, facecolor=color, edgecolor="k", alpha=0.45, lw=0.8, zorder=3)
        if labels:
            ax.annotate(f"F{i}", anchor, textcoords="offset points", xytext=(4, 4), fontsize=8, zorder=6)
    return ax.figure


def fingers_in_frame(ax: Any, fingers: Sequence[Any], units: str, bounds: Sequence[float], xlabel: str,
                     ylabel: str) -> None:
    """Draw ``fingers`` clipped to ``bounds`` (in ``units``), show exactly ``bounds`` at
    equal aspect and label the axes."""
    if len(fingers):
        plot_fingers(fingers, ax=ax, units=units, bounds=bounds)
    ax.set_xlim(bounds[0], bounds[1])
    ax.set_ylim(bounds[2], bounds[3])
    ax.set_aspect("equal")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)


def _outline(ax: Any, mesh: Any, x: np.ndarray, s: float, **kw: Any) -> None:
    for lp in mesh.loops:
        p = x[np.r_[lp, lp[:1]]] / s
        ax.plot(p[:, 0], p[:, 1], **kw)


def plot_configuration(mesh: Any, q: Any = None, ax: Any = None, units: str = "m", triangles: bool = True,
                       highlight_inverted: bool = True) -> Any:
    """Draw a configuration of the mesh (rest outline dashed), inverted triangles in red.

    Parameters
    ----------
    mesh : Mesh
    q : array_like (n, 2), optional
        Configuration (m); default the rest configuration.
    ax, units :
        See :func:`plot_fingers`.
    triangles : bool
        Draw the triangle edges.
    highlight_inverted : bool
        Fill triangles that violate ``D_T`` orientation in red.
    """
    from ..dspace.topology import inverted_triangles

    ax = _axes(ax)
    s = length_scale(units)
    x0 = np.asarray(mesh.nodes, float)
    x = x0 if q is None else np.asarray(q, float).reshape(-1, 2)
    if triangles:
        ax.triplot(x[:, 0] / s, x[:, 1] / s, mesh.triangles, color="0.6", lw=0.4)
    if highlight_inverted:
        bad = inverted_triangles(mesh, x)
        for t in np.asarray(mesh.triangles)[bad]:
            ax.fill(x[t, 0] / s, x[t, 1] / s, color="tab:red", alpha=0.6, zorder=2)
    if q is not None:
        _outline(ax, mesh, x0, s, color="0.5", lw=0.8, ls="--")
    _outline(ax, mesh, x, s, color="k", lw=1.2)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({units})")
    ax.set_ylabel(f"y ({units})")
    return ax.figure


def plot_slice(result: Any, mesh: Any = None, fingers: Sequence[Any] = (), ax: Any = None, units: str = "m",
               show_energy: bool = True) -> Any:
    """Draw a D-space slice (paper Fig. 3): ``D_free`` light, ``D_T`` violations dark grey,
    D-obstacles hatched red, energy contours (J), the moving node's neighbourhood.

    Parameters
    ----------
    result : SliceResult
    mesh : Mesh, optional
        Draw the edges at the moving node and the fixed part around it.
    fingers : sequence of Finger
        Draw them.
    ax, units :
        See :func:`plot_fingers`.
    show_energy : bool
        Draw energy contour lines.
    """
    from matplotlib.colors import ListedColormap

    ax = _axes(ax)
    s = length_scale(units)
    xs, ys = result.xs / s, result.ys / s
    dx = (xs[1] - xs[0]) / 2 if len(xs) > 1 else 0.5
    dy = (ys[1] - ys[0]) / 2 if len(ys) > 1 else 0.5
    ext = (xs[0] - dx, xs[-1] + dx, ys[0] - dy, ys[-1] + dy)
    code = np.where(result.free, 2, np.where(result.in_dt, 1, 0))  # 0 not D_T, 1 obstacle, 2 free
    cmap = ListedColormap(["0.35", "#e8a0a0", "#eef5ff"])
    ax.imshow(code, origin="lower", extent=ext, cmap=cmap, vmin=0, vmax=2, interpolation="nearest", zorder=0)
    if show_energy and np.ptp(result.energy) > 0:
        E = np.where(result.in_dt, result.energy, np.nan)
        cs = ax.contour(xs, ys, E, levels=10, colors="tab:blue", linewidths=0.6, zorder=1)
        ax.clabel(cs, fontsize=6, fmt="%.2g")
    if mesh is not None:
        x = result.q
        v = result.node
        tri = np.asarray(mesh.triangles)
        inc = tri[np.any(tri == v, axis=1)]
        nb = np.unique(inc[inc != v])
        for u in nb:
            ax.plot([x[u, 0] / s, x[v, 0] / s], [x[u, 1] / s, x[v, 1] / s], color="0.2", lw=0.6, ls=":")
        ax.triplot(x[:, 0] / s, x[:, 1] / s, tri, color="0.5", lw=0.3, zorder=1)
        _outline(ax, mesh, x, s, color="k", lw=1.0)
        ax.plot(x[v, 0] / s, x[v, 1] / s, "o", color="tab:orange", ms=5, zorder=6, label=f"node {v} (base)")
    fingers_in_frame(ax, fingers, units, ext, f"x of node {result.node} ({units})",
                     f"y of node {result.node} ({units})")
    ax.set_title(f"D-space slice: D_free (light), D-obstacles (red), not D_T (grey); {result.energy_kind} U (J)",
                 fontsize=8)
    return ax.figure


def plot_check(mesh: Any, result: Any, fingers: Sequence[Any], ax: Any = None, units: str = "m") -> Any:
    """Draw a deform-closure check: the part at equilibrium (rest outline dashed), the
    fingers, contact forces as arrows and, when the part escapes, its escaping motion
    (velocity arrows on the boundary and the instantaneous centre of rotation).

    Parameters
    ----------
    mesh : Mesh
    result : ClosureResult
    fingers : sequence of Finger
    ax, units :
        See :func:`plot_fingers`.
    """
    ax = _axes(ax)
    s = length_scale(units)
    eq = result.equilibrium
    x = eq.q
    plot_configuration(mesh, x, ax=ax, units=units, triangles=False, highlight_inverted=False)
    lo, hi = x.min(axis=0) / s, x.max(axis=0) / s
    pad = 0.25 * float(np.max(hi - lo))
    bounds = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    plot_fingers(fingers, ax=ax, units=units, bounds=bounds)
    L = float(mesh.diameter) / s
    F = np.linalg.norm(eq.forces, axis=1)
    if F.max(initial=0.0) > 0:
        scale = 0.25 * L / F.max()
        for i in np.flatnonzero(F > 0):
            p = eq.points[i] / s
            d = eq.forces[i] * scale
            ax.annotate("", xy=p, xytext=p - d, zorder=7,
                        arrowprops=dict(arrowstyle="-|>", color="tab:green", lw=1.6))
            ax.annotate(f"{F[i]:.3g} N", p - d, fontsize=7, color="tab:green", zorder=7)
    for g in result.groups:
        for pr in g.primitives:
            ax.plot(pr.point[0] / s, pr.point[1] / s, "o", color="tab:green", ms=3, zorder=7)
    c = result.centroid / s
    ax.plot(*c, "+", color="k", ms=8)
    if result.twist is not None:
        tw = np.asarray(result.twist)
        b = np.unique(np.concatenate(mesh.loops))
        step = max(1, len(b) // 24)
        pts = x[b[::step]]
        vel = tw[:2] + tw[2] * np.c_[-(pts[:, 1] - result.centroid[1]), pts[:, 0] - result.centroid[0]]
        vmax = np.linalg.norm(vel, axis=1).max()
        if vmax > 0:
            vel = vel / vmax * 0.15 * L
            ax.quiver(pts[:, 0] / s, pts[:, 1] / s, vel[:, 0], vel[:, 1], color="tab:red", angles="xy",
                      scale_units="xy", scale=1, width=0.004, zorder=8, label="escaping motion")
        if abs(tw[2]) > 1e-12:
            icr = result.centroid + np.array([-tw[1], tw[0]]) / tw[2]
            if np.all(np.abs(icr / s - c) < 3 * L):
                ax.plot(*(icr / s), "*", color="tab:red", ms=10, zorder=8, label="centre of rotation")
        legend_outside(ax, fontsize=7)
    verdict = "held (deform closure)" if result.deform_closure else "NOT held (escapes)"
    ax.set_title(f"{verdict}, order {result.order}; U = {result.energy:.3g} J (linear)", fontsize=9)
    ax.set_xlim(bounds[0], bounds[1])
    ax.set_ylim(bounds[2], bounds[3])
    return ax.figure
