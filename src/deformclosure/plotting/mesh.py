"""Pictures of meshes and scalar fields on them."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..units import length_scale

__all__ = ["plot_mesh", "save_mesh_plot", "new_figure", "save_figure", "figure_axes", "save_plots",
           "save_figures", "figure_path", "legend_outside", "legend_below", "side_colorbar"]


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


def save_plots(obj, target: str | Path, units: str, specs) -> list[Path]:
    """Draw ``fn(obj, ax=ax, units=units)`` on a new figure of ``size`` and save it as
    figure ``name`` of ``--plot target`` (:func:`figure_path`) for every ``(name, fn,
    size)`` of ``specs`` (a suffix on ``name`` is dropped: the target sets the format);
    return the paths."""
    figs = []
    for name, fn, size in specs:
        fig, ax = new_figure(size)
        fn(obj, ax=ax, units=units)
        figs.append((Path(name).stem, fig))
    return save_figures(figs, target)


def save_figures(figs, target: str | Path) -> list[Path]:
    """Save (and close) each drawn ``(name, figure)`` of ``figs`` as figure ``name`` of
    ``--plot target`` (:func:`figure_path`); return the paths, in order."""
    paths = []
    for name, fig in figs:
        path = figure_path(target, name)
        save_figure(fig, path)
        paths.append(path)
    return paths


def figure_path(target: str | Path, name: str, single: bool = False) -> Path:
    """The file of figure ``name`` for ``--plot target``
    (:func:`deformclosure.outputs.plot_file`: a folder of PNGs, or ``dir/stem.svg`` →
    ``dir/stem_<name>.svg``), its folder created."""
    from ..outputs import plot_file

    path = plot_file(target, name, single)
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def legend_outside(ax, **kw):
    """The axes' legend to the right of the axes, so it never hides the data (saved
    figures use a tight bounding box, so it stays in the picture)."""
    kw.setdefault("fontsize", 8)
    return ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, **kw)


def legend_below(ax, **kw):
    """The axes' legend centred below the axes (and their x label), for axes with a
    colour bar on their right, where :func:`legend_outside` would sit behind the bar."""
    kw.setdefault("fontsize", 8)
    handles, labels = ax.get_legend_handles_labels()
    kw.setdefault("ncol", max(1, min(3, len(labels))))
    # its top 4.5 font sizes below the axes: under the tick labels and the x label
    return ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), borderaxespad=4.5,
                     frameon=False, **kw)


def side_colorbar(ax, mappable, label: str):
    """A colour bar as tall as ``ax`` on its right (also for equal-aspect axes), labelled."""
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    cax = make_axes_locatable(ax).append_axes("right", size="4%", pad=0.12)
    cb = ax.figure.colorbar(mappable, cax=cax)
    cb.set_label(label)
    return cb


def save_figure(fig, path: str | Path) -> None:
    """Save and close ``fig``."""
    import matplotlib.pyplot as plt

    from ..errors import DeformClosureError

    from ..outputs import atomic_path

    try:
        with atomic_path(path, "plot") as tmp:
            fig.savefig(tmp, dpi=150, bbox_inches="tight", format=Path(path).suffix[1:].lower() or "png")
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
