"""Local mesh sizes: where a mesh must be finer than the part's ``max_area`` (SPEC §6
"Accuracy by default").

A :class:`Sizing` is a field of largest triangle areas (m²) over the part, in the part
frame: a default area, discs of smaller area (under the pads, in the critical-distance
disc of a strain maximum, at re-entrant corners) and, after an adaptive step, the areas a
previous mesh asked for element by element (looked up at the nearest element centroid).
The mesher (:func:`deformclosure.mesh.mesh_part`) refines until every triangle meets the
field at its centroid, so the same field meshes the twin realisation (rotated frame) and
the next level alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Sizing", "area_of_size"]


def area_of_size(h: float) -> float:
    """Area (m²) of the equilateral triangle of side ``h`` (m): the area bound that gives
    element sizes of about ``h``."""
    return math.sqrt(3.0) / 4.0 * h * h


@dataclass(frozen=True)
class Sizing:
    """Largest triangle area (m²) at each point of the part.

    Attributes
    ----------
    default : float
        Area (m²) where nothing finer is asked for.
    discs : tuple of (x, y, radius, area)
        Discs (m) inside which triangles are at most ``area`` (m²).
    points, areas : ndarray, optional
        Element centroids (m) of an earlier mesh and the area (m²) each asked for; a point
        takes the request of its nearest centroid (never above ``default``).
    """

    default: float
    discs: tuple[tuple[float, float, float, float], ...] = ()
    points: np.ndarray | None = field(default=None, repr=False)
    areas: np.ndarray | None = field(default=None, repr=False)

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        """Largest area (m²) at the points ``xy`` (shape (k, 2), m)."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        out = np.full(len(xy), float(self.default))
        if self.points is not None and len(self.points):
            from scipy.spatial import cKDTree  # lazy: scipy.spatial is slow to import

            _, idx = cKDTree(self.points).query(xy)
            out = np.minimum(out, self.areas[idx])
        for x, y, r, a in self.discs:
            inside = np.hypot(xy[:, 0] - x, xy[:, 1] - y) <= r
            out[inside] = np.minimum(out[inside], a)
        return out

    @property
    def smallest(self) -> float:
        """The smallest area (m²) the field asks for anywhere."""
        a = [self.default] + [d[3] for d in self.discs]
        if self.areas is not None and len(self.areas):
            a.append(float(self.areas.min()))
        return float(min(a))

    def with_discs(self, discs) -> "Sizing":
        """This field with more discs ``(x, y, radius, area)`` (m, m²)."""
        extra = tuple((float(x), float(y), float(r), float(a)) for x, y, r, a in discs)
        return Sizing(self.default, self.discs + extra, self.points, self.areas)

    @classmethod
    def refining(cls, mesh, marked: np.ndarray, default: float, factor: float = 4.0,
                 discs=()) -> "Sizing":
        """The field of the next adaptive level: every element of ``mesh`` keeps its area,
        marked elements (bool, per triangle) ask for ``1/factor`` of it (``h`` halved for
        4), plus ``discs`` (m, m²); nowhere above ``default`` (m²)."""
        A = np.asarray(mesh.areas, float)
        # Slack on unmarked elements: the mesher's areas vary, and asking for exactly the
        # present area would make it split elements nobody marked.
        want = np.where(np.asarray(marked, bool), A / factor, 1.5 * A)
        c = mesh.nodes[mesh.triangles].mean(axis=1)
        return cls(float(default), tuple((float(x), float(y), float(r), float(a))
                                         for x, y, r, a in discs), c, np.minimum(want, default))
