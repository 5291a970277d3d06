"""Picture of a part's outline (what ``deformclosure import`` read from a drawing)."""

from __future__ import annotations

__all__ = ["plot_outline"]


def plot_outline(part, ax=None):
    """Draw the outer ring (filled) and the holes of ``part`` in its own units.

    Returns
    -------
    matplotlib.figure.Figure
        The figure of the axes drawn into.

    Examples
    --------
    >>> from deformclosure import Part
    >>> part = Part.from_dict({"units": "mm", "outer": [[0, 0], [4, 0], [4, 2], [0, 2]],
    ...     "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1,
    ...                  "elastic_limit_strain": 0.8}})
    >>> len(plot_outline(part).axes)
    1
    """
    from ..units import length_scale
    from .mesh import new_figure

    if ax is None:
        _, ax = new_figure(figsize=(6, 5))
    s = length_scale(part.units)
    for ring in (part.outer, *part.holes):
        xy = ring / s
        outer = ring is part.outer
        ax.fill(xy[:, 0], xy[:, 1], alpha=0.25 if outer else 1.0,
                fc="tab:blue" if outer else "white", ec="k", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({part.units})")
    ax.set_ylabel(f"y ({part.units})")
    ax.set_title(part.name)
    return ax.figure
