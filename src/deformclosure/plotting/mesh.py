"""Pictures of meshes and scalar fields on them."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..units import length_scale

__all__ = ["plot_mesh", "save_mesh_plot", "new_figure", "save_figure", "figure_axes", "save_plots"]


def new_figure(figsize=(6, 6)):
    """A figure and axes with the non-interactive Agg backend."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt.subplots(figsize=figsize)


def figure_axes(ax, figsize, units: str):
    """``ax``, or the axes of a new figure of ``figsize`` when ``None``, and the scale
    (plot units per metre) of ``units``."""
    if ax is None:
        _, ax = new_figure(figsize)
    return ax, 1.0 / length_scale(units)


def save_plots(obj, out_dir: str | Path, units: str, specs) -> list[Path]:
    """Draw ``fn(obj, ax=ax, units=units)`` on a new figure of ``size`` and save it as
    ``out_dir / name`` for every ``(name, fn, size)`` of ``specs``; return the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, fn, size in specs:
        fig, ax = new_figure(size)
        fn(obj, ax=ax, units=units)
        save_figure(fig, out / name)
        paths.append(out / name)
    return paths


def legend_outside(ax, **kw):
    """The axes' legend to the right of the axes, so it never hides the data (saved
    figures use a tight bounding box, so it stays in the picture)."""
    kw.setdefault("fontsize", 8)
    return ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, **kw)


def save_figure(fig, path: str | Path) -> None:
    """Save and close ``fig``."""
    import matplotlib.pyplot as plt

    from ..errors import DeformClosureError

    from ..outputs import atomic_path

    try:
        with atomic_path(path, "plot") as tmp:
            fig.savefig(tmp, dpi=150, bbox_inches="tight", format=Path(path).suffix[1:] or "png")
    except DeformClosureError:              # the target itself (outputs.atomic_path), one line
        raise
    except (OSError, ValueError) as err:
        raise DeformClosureError(f"{path}: cannot write plot ({err})") from None
    finally:
        plt.close(fig)


def plot_mesh(mesh, ax=None, units: str = "mm", values: np.ndarray | None = None,
              displacement: np.ndarray | None = None, highlight: np.ndarray | None = None,
              cmap: str = "viridis", colorbar_label: str | None = None):
    """Draw the triangles of ``mesh`` (optionally deformed and coloured per element).

    Parameters
    ----------
    mesh : Mesh
    ax : matplotlib Axes, optional
    units : str
        Length unit of the axes.
    values : ndarray, shape (m,), optional
        Per-element values to colour the triangles with.
    displacement : ndarray, shape (n, 2) or (2n,), optional
        Nodal displacement (m) to draw the deformed mesh.
    highlight : ndarray of int, optional
        Node ids to mark.

    Returns
    -------
    matplotlib.figure.Figure
        The figure holding ``ax`` (compose it with others, or save it).
    """
    import matplotlib.tri as mtri

    if ax is None:
        _, ax = new_figure()
    s = 1.0 / length_scale(units)
    xy = mesh.nodes.copy()
    if displacement is not None:
        xy = xy + np.asarray(displacement, float).reshape(-1, 2)
    tri = mtri.Triangulation(xy[:, 0] * s, xy[:, 1] * s, mesh.triangles)
    if values is not None:
        pc = ax.tripcolor(tri, facecolors=np.asarray(values), cmap=cmap, edgecolors="k",
                          linewidth=0.15)
        cb = ax.figure.colorbar(pc, ax=ax, shrink=0.8)
        if colorbar_label:
            cb.set_label(colorbar_label)
    else:
        ax.triplot(tri, color="0.35", linewidth=0.4)
    for i, lp in enumerate(mesh.loops):
        ring = np.append(lp, lp[0])
        ax.plot(xy[ring, 0] * s, xy[ring, 1] * s, color="C0" if i == 0 else "C1", linewidth=1.2)
    if highlight is not None and len(highlight):
        h = np.asarray(highlight)
        ax.plot(xy[h, 0] * s, xy[h, 1] * s, "o", color="C3", markersize=5)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({units})")
    ax.set_ylabel(f"y ({units})")
    return ax.figure


def save_mesh_plot(mesh, path: str | Path, units: str = "mm") -> None:
    """Write a picture of ``mesh`` to ``path``."""
    fig, ax = new_figure()
    plot_mesh(mesh, ax=ax, units=units)
    ax.set_title(f"{mesh.name}: {mesh.n_nodes} nodes, {mesh.n_triangles} triangles")
    save_figure(fig, path)
