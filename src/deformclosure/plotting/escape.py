"""Pictures of the release of a part among fixed fingers: the escape path (part outlines
along it) and the energy profile (SPEC §7).

matplotlib is imported lazily; coordinates are drawn in ``units`` (default metres),
energies in joules.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..units import length_scale

__all__ = ["plot_escape_path", "plot_escape_energy", "plot_check_and_escape", "escape_note"]


def _path_length(rel: Any) -> np.ndarray:
    """Cumulative path parameter: translation (m) plus rotation × the part's radius."""
    P = np.asarray(rel.path, float)
    if len(P) < 2:
        return np.zeros(len(P))
    R = float(rel.grid.h / rel.grid.h_phi)       # metres per radian of the lattice
    d = np.diff(P, axis=0)
    d[:, 2] = (d[:, 2] + np.pi) % (2 * np.pi) - np.pi
    step = np.hypot(np.hypot(d[:, 0], d[:, 1]), R * d[:, 2])
    return np.r_[0.0, np.cumsum(step)]


def plot_escape_path(mesh: Any, rel: Any, fingers: Sequence[Any], ax: Any = None, units: str = "m",
                     n_outlines: int = 8) -> Any:
    """Draw the part's outline at placements along the escape path (light to dark from
    the equilibrium to the end; the saddle in red) among the fingers.

    Parameters
    ----------
    mesh : Mesh
    rel : FingerRelease
    fingers : sequence of Finger
    ax : matplotlib Axes, optional
    units : str
        Axis length unit.
    n_outlines : int
        Outlines drawn along the path (plus the equilibrium, the saddle and the end).
    """
    from .dspace import _axes, fingers_in_frame

    ax = _axes(ax)
    s = length_scale(units)
    loops = [np.asarray(mesh.nodes, float)[np.asarray(lp)] for lp in mesh.loops]
    P = np.asarray(rel.path, float)
    if len(P) == 0:
        P = np.asarray(rel.equilibrium, float)[None]
    idx = sorted(set(np.linspace(0, len(P) - 1, min(n_outlines, len(P))).round().astype(int).tolist())
                 | ({rel.saddle} if rel.saddle is not None else set()) | {0, len(P) - 1})
    import matplotlib.cm as cm

    pts = []
    for k in idx:
        frac = k / max(len(P) - 1, 1)
        colour = "tab:red" if k == rel.saddle else cm.Blues(0.35 + 0.6 * frac)
        lw = 1.6 if k in (0, rel.saddle, len(P) - 1) else 0.8
        for lp in loops:
            q = rel.place(P[k], lp) / s
            q = np.vstack([q, q[:1]])
            ax.plot(q[:, 0], q[:, 1], color=colour, lw=lw, zorder=3)
            pts.append(q)
    C = np.array([rel.place(g, rel.centroid[None])[0] for g in P]) / s
    ax.plot(C[:, 0], C[:, 1], "-", color="k", lw=0.8, zorder=4, label="centroid path")
    ax.plot(*C[0], "o", color="k", ms=4, zorder=5)
    allp = np.vstack(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.1 * float(np.max(hi - lo))
    bounds = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    fingers_in_frame(ax, fingers, units, bounds, f"x ({units})", f"y ({units})")
    end = {"released": "released", "equilibrium": "another equilibrium"}.get(rel.target, "no release")
    ax.set_title(f"escape path ({len(P)} placements, to {end}); saddle in red", fontsize=9)
    return ax.figure


def plot_escape_energy(rel: Any, ax: Any = None, units: str = "m") -> Any:
    """Energy (J) along the escape path against its length (translation plus rotation ×
    the lattice's radius), with ``U_A`` marked."""
    from .dspace import _axes

    ax = _axes(ax)
    s = length_scale(units)
    t = _path_length(rel) / s
    E = np.asarray(rel.path_energy, float)
    if len(E):
        ax.plot(t, E, "-o", ms=2.5, color="tab:blue", lw=1.2)
        if rel.saddle is not None:
            ax.plot(t[rel.saddle], E[rel.saddle], "o", color="tab:red", ms=6, zorder=5)
        ax.axhline(rel.energy, color="0.5", lw=0.8, ls="--", label="equilibrium")
        if np.isfinite(rel.U_A) and rel.U_A > 0:
            ax.annotate("", xy=(t[rel.saddle], rel.energy + rel.U_A), xytext=(t[rel.saddle], rel.energy),
                        arrowprops=dict(arrowstyle="<->", color="tab:red"))
    ua = "∞" if not np.isfinite(rel.U_A) else f"{rel.U_A:.4g} ± {rel.U_A_error:.2g} J"
    verdict = "held" if rel.deform_closure else "caged" if rel.caged else "not held"
    ax.set_title(f"U_A = {ua} ({verdict})", fontsize=9)
    ax.set_xlabel(f"path length ({units}; rotation × {rel.grid.h / rel.grid.h_phi / s:.3g} {units}/rad)")
    ax.set_ylabel("energy (J)")
    ax.grid(alpha=0.3)
    return ax.figure


def escape_note(rel: Any) -> str | None:
    """Why a release result has no escape path to draw (``None`` when it has one): the
    escape path and energy panels of :func:`plot_check_and_escape` are then left out and
    this note is printed under the check."""
    if len(np.asarray(rel.path)) >= 2:
        return None
    if not np.isfinite(rel.U_A):
        why = ("no placement within the fingers' reach releases the part" +
               (" (a cage)" if rel.caged else ""))
        return f"no escape path: U_A = ∞, {why}; the part is held"
    if not rel.complete:
        return "no escape path: the search stopped before a release (U_A is a lower bound)"
    return "no escape path: the part is released at its start (U_A = 0)"


def plot_check_and_escape(mesh: Any, closure: Any, rel: Any, fingers: Sequence[Any], units: str = "m") -> Any:
    """One figure: the deform-closure check at rest (:func:`.dspace.plot_check`), the escape
    path and its energy profile — or, when there is no escape path to draw (``U_A``
    infinite, a release at the start), the check alone with a note saying why
    (:func:`escape_note`). Returns the figure."""
    from .dspace import plot_check
    from .mesh import new_figure

    note = escape_note(rel)
    if note is not None:
        fig, ax = new_figure(figsize=(7, 6))
        plot_check(mesh, closure, fingers, ax=ax, units=units)
        ax.set_title("rigid test: " + ax.get_title(), fontsize=9)
        ax.text(0.5, -0.12, note, transform=ax.transAxes, ha="center", va="top", fontsize=9,
                wrap=True)
        return fig
    fig, _ = new_figure(figsize=(16, 5.5))
    fig.clf()
    axes = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1, 1, 1.1]})
    plot_check(mesh, closure, fingers, ax=axes[0], units=units)
    axes[0].set_title("rigid test: " + axes[0].get_title(), fontsize=9)
    plot_escape_path(mesh, rel, fingers, ax=axes[1], units=units)
    plot_escape_energy(rel, ax=axes[2], units=units)
    fig.tight_layout()
    return fig
