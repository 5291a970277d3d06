"""The axis landscape refined around its saddles (SPEC §6 "Accuracy by default").

A barrier read off the ``(θ, c)`` grid is not the continuum saddle: the minimax path
passes through grid vertices only. The saddle is where the grid's spacing matters — away
from it the path runs below the barrier — so refinement adds vertices there only.

:class:`SaddleRefinedGrid` lays a grid ``factor`` times finer (in θ and in c) over the
coarse :class:`~deformclosure.pads.landscape.AxisGrid` and uses it inside *patches*: boxes
of half-width one coarse cell around given centre axes (the saddles found on the previous,
coarser level). Its vertices are the coarse vertices everywhere and every fine vertex in a
patch; edges join fine neighbours inside a patch and coarse neighbours (``factor`` fine
steps apart) unless both ends lie in one patch (there the fine path replaces the edge). A
patch's boundary runs along coarse grid lines, so the two resolutions meet at coarse
vertices and the graph is symmetric. The start axis' strictness test keeps the coarse
neighbours: refining the grid there would only shrink the differences the noise floor
compares (SPEC §6 "Noise floor").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .geometry import GraspAxis
from .landscape import AxisGrid

__all__ = ["SaddleRefinedGrid"]


@dataclass(frozen=True)
class SaddleRefinedGrid:
    """A coarse axis grid refined ``factor`` times inside patches around ``centres``.

    Vertex ids are those of the fine grid (:attr:`fine`); ``vertex(i, j)`` takes *coarse*
    cell indices, as :class:`AxisGrid` does, so callers address the start the same way.
    """

    base: AxisGrid
    factor: int
    centres: tuple[tuple[int, int], ...]       # fine cells of the patch centres
    fine: AxisGrid = field(init=False, repr=False)
    patch: frozenset = field(init=False, repr=False)

    def __post_init__(self) -> None:
        b, f = self.base, int(self.factor)
        fine = AxisGrid(b.angle0, b.offset0, b.d_angle / f, b.d_offset / f, b.n_angles * f,
                        b.j_min * f, b.j_max * f, b.wrap * f, b.origin)
        object.__setattr__(self, "fine", fine)
        cells = set()
        for ci, cj in self.centres:
            for di in range(-f, f + 1):
                for dj in range(-f, f + 1):
                    v = self._cell_vertex(ci + di, cj + dj)
                    if v is not None:
                        cells.add(v)
        object.__setattr__(self, "patch", frozenset(cells))

    @classmethod
    def around(cls, base: AxisGrid, factor: int, saddles) -> "SaddleRefinedGrid":
        """``base`` refined ``factor`` times around the axes ``saddles`` (GraspAxis, each
        moved to the nearest coarse vertex, so that patches end on coarse lines)."""
        f = int(factor)
        centres = []
        for ax in saddles:
            i, j = cls._nearest_cell(base, ax)
            centres.append((i * f, j * f))
        return cls(base, f, tuple(dict.fromkeys(centres)))

    @staticmethod
    def _nearest_cell(grid: AxisGrid, ax: GraspAxis) -> tuple[int, int]:
        """Cell ``(i, j)`` of ``grid`` nearest to axis ``ax`` (with the wrap (θ+π, −c))."""
        rel = (ax.angle - grid.angle0) / math.pi
        turns = math.floor(rel)
        theta = (rel - turns) * math.pi
        c = (ax.offset if tuple(ax.origin) == tuple(grid.origin)
             else GraspAxis.at(ax.point, ax.angle, grid.origin).offset)   # about the grid's origin
        if turns % 2:
            c = -c                                                        # (θ + π, −c)
        i = int(round(theta / grid.d_angle)) % grid.n_angles
        j = int(round((c - grid.offset0) / grid.d_offset))
        return i, min(max(j, grid.j_min), grid.j_max)

    def _cell_vertex(self, i: int, j: int) -> int | None:
        """Fine vertex of fine cell ``(i, j)`` with the periodic wrap; None off the grid."""
        g = self.fine
        while i < 0 or i >= g.n_angles:
            if i < 0:
                i, j = i + g.n_angles, -j - g.wrap
            else:
                i, j = i - g.n_angles, -j - g.wrap
        if not g.j_min <= j <= g.j_max:
            return None
        return g.vertex(i, j)

    # --- the AxisGrid interface the landscape uses ------------------------------------
    @property
    def d_angle(self) -> float:
        """Coarse angle step (rad): the noise floor's sub-cell moves keep it."""
        return self.base.d_angle

    @property
    def d_offset(self) -> float:
        """Coarse offset step (m)."""
        return self.base.d_offset

    @property
    def n_angles(self) -> int:
        return self.base.n_angles

    @property
    def n_offsets(self) -> int:
        return self.base.n_offsets

    @property
    def size(self) -> int:
        """Number of fine vertex ids (most are not vertices of this graph)."""
        return self.fine.size

    @property
    def n_patch(self) -> int:
        """Number of fine vertices in the patches."""
        return len(self.patch)

    def vertex(self, i: int, j: int) -> int:
        """Vertex id of *coarse* cell ``(i, j)``."""
        return self.fine.vertex(i * self.factor, j * self.factor)

    def cell(self, v: int) -> tuple[int, int]:
        """Fine cell of vertex ``v``."""
        return self.fine.cell(v)

    def axis(self, v: int) -> GraspAxis:
        """The grasp axis of vertex ``v``."""
        return self.fine.axis(v)

    def contains(self, ax: GraspAxis) -> bool:
        """Whether axis ``ax`` is a fine vertex inside a patch (not on its boundary): a
        saddle there is resolved at this grid's finest spacing."""
        i, j = self._nearest_cell(self.fine, ax)
        v = self._cell_vertex(i, j)
        if v is None or v not in self.patch:
            return False
        return all(w in self.patch for w in self.fine.neighbours(v))

    def is_coarse(self, v: int) -> bool:
        i, j = self.fine.cell(v)
        return i % self.factor == 0 and j % self.factor == 0

    def neighbours(self, v: int) -> list[int]:
        """Fine neighbours inside a patch, coarse ones across (module docstring)."""
        out = []
        inside = v in self.patch
        if inside:
            out.extend(w for w in self.fine.neighbours(v) if w in self.patch)
        if self.is_coarse(v):
            out.extend(w for w in self.start_neighbours(v)
                       if not (inside and w in self.patch))
        return out

    def start_neighbours(self, v: int) -> list[int]:
        """The coarse neighbours of ``v``: the start's strictness test (module docstring)."""
        f, out = self.factor, []
        i, j = self.fine.cell(v)
        for di, dj in ((f, 0), (-f, 0), (0, f), (0, -f)):
            w = self._cell_vertex(i + di, j + dj)
            if w is not None:
                out.append(w)
        return out

    def to_dict(self) -> dict:
        return {"d_angle": self.base.d_angle, "d_offset": self.base.d_offset,
                "n_angles": self.base.n_angles, "n_offsets": self.base.n_offsets,
                "refinement": self.factor, "patches": len(self.centres),
                "patch_vertices": self.n_patch}
