"""Strain averaged over a critical distance: a mesh-converged elastic-limit measure (SPEC §6).

At a re-entrant corner (a notch root, the inside corner of an L) the strain of the linear
solution is singular, so the largest *element* strain grows without bound as the mesh is
refined (like ``h^(λ-1)``, ``λ ≈ 0.544`` for a 270° corner). Following the theory of
critical distances for notched parts, the elastic limit is instead checked on the strain
averaged over a disc of radius ``ℓ`` (the material's critical distance):

- for every element ``i``, the disc is the set of elements whose centroids lie within
  ``ℓ`` of the centroid of ``i`` (``i`` itself always belongs to it);
- the engineering strain *tensor* ``[exx, eyy, gamma_xy]`` is averaged over the disc with
  the element areas as weights (components averaged, not magnitudes);
- its *strain magnitude* is the largest absolute in-plane principal value of that average
  (SPEC §1), and the grasp's ``e`` is its maximum over the elements.

The averaging is a sparse row-stochastic matrix ``W`` (:func:`averaging_operator`). Its
number of non-zeros is about ``m`` times the number of elements per disc — ``m² π ℓ² / A``,
quadratic in the mesh size at a fixed ``ℓ`` — so the package never builds it in full:
:class:`DiscAverage` (one per mesh and ``ℓ``, :func:`disc_average`) builds the rows it needs
in chunks of at most :data:`CHUNK_PAIRS` element pairs, and the elastic limit needs few
rows. The measure is a norm of the tensor, so the average over a disc cannot exceed the
largest element magnitude in it; a grid of cells ``ℓ / CELLS_PER_ELL`` wide bounds that per
element in ``O(m)``, and only the rows whose bound reaches the largest exact average found
so far are averaged (:meth:`DiscAverage.maxima`, :func:`averaged_strain_maximum`: the one
home of the maximum over the elements). The numbers are those of ``W``, up to the
summation order of the disc areas (a few units in the last place).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import scipy.sparse as sp

from ..errors import GraspError, MeshError
from ..limits import DISC_ROW_POOL_BYTES
from .strain import principal_strains

__all__ = [
    "default_critical_distance",
    "critical_distance_of",
    "averaging_operator",
    "averaged_strains",
    "averaged_strain_magnitude",
    "averaged_strain_maximum",
    "DiscAverage",
    "disc_average",
    "CHUNK_PAIRS",
]

#: Default critical distance as a fraction of the part's diameter (SPEC §6).
DEFAULT_CRITICAL_FRACTION = 0.02

#: Largest number of element pairs (an element and one element of its disc) whose weights
#: :class:`DiscAverage` holds at once: a chunk of rows of ``W`` takes about
#: ``DISC_BYTES_PER_PAIR`` bytes per pair while it is built and applied.
CHUNK_PAIRS = 400_000

#: Peak bytes per element pair of one chunk (the KD-tree's pair list, the CSR rows, the
#: products), measured by ``benchmarks/bench_critical_distance.py``.
DISC_BYTES_PER_PAIR = 100.0

#: Largest memory (bytes) of the per-field grid arrays of :meth:`DiscAverage.maxima` at
#: once (cell maxima, their filtered bounds and the masks made from them, about
#: :data:`FIELD_BYTES_PER_CELL` per cell and field): more fields are taken in groups. A
#: tiny ℓ has up to 4 cells per element, so ``k`` fields at once held ~160 k·m bytes —
#: 3 GB for the 100 breakpoints of a 50 000-node part (issue 25).
FIELD_CHUNK_BYTES = 40e6
FIELD_BYTES_PER_CELL = 48.0

#: Bytes a pair of a row of ``W`` kept by :meth:`DiscAverage.reusing_rows` (a weight and a
#: column). The elastic limit's scan along a path averages the same hot discs for every
#: group of breakpoints: at 80 000 nodes 96 000 rows were built for 12 000 distinct ones
#: (53 M pairs, 2.8 s of a 29 s ``optimize``). Its cap is ``limits.DISC_ROW_POOL_BYTES``.
ROW_POOL_BYTES_PER_PAIR = 12

#: Grid cells per critical distance of the bound on each disc's largest element strain
#: (finer: a tighter bound, more cells to scan).
CELLS_PER_ELL = 4

#: Exact rows averaged first, per field: those of its largest element strains; the largest
#: of their averages is the first lower bound of the maximum.
SEED_ROWS = 4

#: Relative margin of the pruning: a row is averaged when its bound reaches
#: ``(1 - PRUNE_MARGIN)`` times the largest average found, so rounding in a sum over a disc
#: (``d ε`` for ``d`` elements, below 1e-10 for a disc of 10⁶ elements) cannot hide the
#: maximum.
PRUNE_MARGIN = 1e-9


def critical_distance_of(mesh) -> float:
    """The critical distance ``ℓ`` (m) of a mesh's material: its ``critical_distance``,
    else :func:`default_critical_distance` of the mesh's diameter (SPEC §6). The one
    home of the default, for every model."""
    mat = getattr(mesh, "material", None)
    cd = getattr(mat, "critical_distance", None) if mat is not None else None
    return default_critical_distance(mesh.diameter) if cd is None else float(cd)


def _check_ell(ell: float) -> float:
    try:
        value = float(ell)
    except (TypeError, ValueError):
        raise GraspError(f"critical_distance = {ell!r}: must be a finite length >= 0 (m)") from None
    if not (math.isfinite(value) and value >= 0.0):
        raise GraspError(f"critical_distance = {ell!r}: must be a finite length >= 0 (m); "
                         "use 0 for the element strains themselves")
    return value


def default_critical_distance(diameter: float) -> float:
    """Default critical distance: 2 % of the part's diameter (SPEC §6).

    Parameters
    ----------
    diameter : float
        Largest distance between two points of the part (m), finite and > 0.

    Returns
    -------
    float
        ``0.02 * diameter`` (m).

    Raises
    ------
    GraspError
        If ``diameter`` is not a finite length > 0.
    """
    d = float(diameter)
    if not (math.isfinite(d) and d > 0.0):
        raise GraspError(f"diameter = {diameter!r}: must be a finite length > 0 (m) to set the "
                         "default critical_distance")
    return DEFAULT_CRITICAL_FRACTION * d


def _centroids_and_areas(mesh) -> tuple[np.ndarray, np.ndarray]:
    """Element centroids (m), shape (m, 2), and areas (m²), shape (m,): the disc centres
    and the weights of every average."""
    tri = np.asarray(mesh.triangles)
    nodes = np.asarray(mesh.nodes, float)
    centroids = nodes[tri].mean(axis=1)
    d1 = nodes[tri[:, 1]] - nodes[tri[:, 0]]
    d2 = nodes[tri[:, 2]] - nodes[tri[:, 0]]
    areas = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])       # m²
    return centroids, areas


def _check_operator_fits(mesh, ell: float) -> None:
    """Refuse a full averaging operator whose construction would exceed the memory budget
    (``AVERAGING_BYTES_PER_NONZERO`` per non-zero): the grid's bound first, the exact pair
    count (a KD-tree count, no pair list) when the bound is too large."""
    from ..limits import AVERAGING_BYTES_PER_NONZERO, GB, MEMORY_BUDGET, format_count

    disc = disc_average(mesh, ell)
    if AVERAGING_BYTES_PER_NONZERO * float(disc.disc_size_bound.sum()) <= MEMORY_BUDGET:
        return
    nnz = float(disc._tree.count_neighbors(disc._tree, ell))
    need = AVERAGING_BYTES_PER_NONZERO * nnz
    if need > MEMORY_BUDGET:
        raise GraspError(f"critical_distance = {ell:.3g} m: the full averaging operator of this "
                         f"{disc.m:,}-triangle mesh has {format_count(nnz)} non-zeros (about "
                         f"{need / GB:.1f} GB, more than {MEMORY_BUDGET / GB:.0f} GB); use "
                         "averaged_strains or DiscAverage, which average in chunks")


def averaging_operator(mesh, ell: float) -> sp.csr_matrix:
    """Area-weighted averaging over discs of radius ``ell`` around element centroids.

    Row ``i`` holds, for every element ``j`` whose centroid lies within ``ell`` of the
    centroid of element ``i`` (distance ``<= ell``; ``j = i`` always included),
    the weight ``A_j / sum_k A_k`` (sum over the same disc), so every row sums to 1 and
    ``W @ f`` is the area-weighted mean of an element field ``f`` over each disc.

    It holds ``m`` times the elements per disc (about ``m² π ℓ² / A`` non-zeros, 60 bytes
    each while it is built); the package's analyses use :class:`DiscAverage` instead, which
    builds the rows it needs in chunks. An operator that would not fit in the memory budget
    (:data:`deformclosure.limits.MEMORY_BUDGET`) is refused.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh (nodes in m).
    ell : float
        Critical distance ``ℓ`` (m), finite and >= 0. ``ell = 0`` gives the identity.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (m, m)
        Row-stochastic averaging matrix (dimensionless), ``m`` = number of triangles.

    Raises
    ------
    GraspError
        If ``ell`` is negative or not finite (the message names ``critical_distance``), or
        the operator would not fit in the memory budget.
    """
    from scipy.spatial import cKDTree  # lazy: scipy.spatial is slow to import

    ell = _check_ell(ell)
    centroids, areas = _centroids_and_areas(mesh)
    m = len(areas)
    diag = np.arange(m)
    if ell > 0.0:
        _check_operator_fits(mesh, ell)
        pairs = cKDTree(centroids).query_pairs(ell, output_type="ndarray")  # i < j, d <= ell
        rows = np.concatenate([diag, pairs[:, 0], pairs[:, 1]])
        cols = np.concatenate([diag, pairs[:, 1], pairs[:, 0]])
    else:
        rows = cols = diag
    # Every (row, col) pair occurs once: normalise the weights per row before assembly.
    weights = areas[cols]
    weights /= np.bincount(rows, weights=weights, minlength=m)[rows]
    return sp.csr_matrix((weights, (rows, cols)), shape=(m, m))


def _operator(mesh, operator) -> sp.spmatrix:
    m = len(mesh.triangles)
    if operator.shape != (m, m):
        raise MeshError(f"operator: shape {operator.shape} does not fit this mesh of {m} "
                        "triangles; build it with averaging_operator(mesh, ell)")
    return operator


def averaged_strains(mesh, strains: np.ndarray, ell: float | None,
                     operator: sp.spmatrix | None = None) -> np.ndarray:
    """Strain tensor averaged (area-weighted) over the critical-distance disc of each element.

    Parameters
    ----------
    mesh : Mesh
    strains : ndarray, shape (m, 3) or (k, m, 3)
        Engineering element strains ``[exx, eyy, gamma_xy]`` (dimensionless), one field or
        a stack of ``k`` fields.
    ell : float or None
        Critical distance (m), finite and >= 0; ignored (may be ``None``) when
        ``operator`` is given.
    operator : sparse matrix, shape (m, m), optional
        A precomputed :func:`averaging_operator` of this mesh, to reuse for many fields;
        by default the rows are built in chunks (:meth:`DiscAverage.averaged`), never the
        whole operator.

    Returns
    -------
    ndarray, same shape as ``strains``
        Averaged ``[exx, eyy, gamma_xy]`` per element (dimensionless).

    Raises
    ------
    GraspError
        If ``ell`` is invalid (and no operator is given).
    MeshError
        If ``strains`` or ``operator`` do not match the mesh.
    """
    m = len(mesh.triangles)
    e = _stack(m, strains)
    if operator is None:
        if ell is None:
            raise GraspError("critical_distance = None: give a finite length >= 0 (m) or an "
                             "averaging operator")
        return disc_average(mesh, ell).averaged(e)      # in chunks: W is never held whole
    W = _operator(mesh, operator)
    if e.ndim == 2:
        return np.asarray(W @ e)
    k = e.shape[0]
    flat = np.ascontiguousarray(e.transpose(1, 0, 2)).reshape(m, 3 * k)
    return np.asarray(W @ flat).reshape(m, k, 3).transpose(1, 0, 2)


def averaged_strain_magnitude(mesh, strains: np.ndarray, ell: float | None,
                              operator: sp.spmatrix | None = None) -> np.ndarray:
    """Largest absolute in-plane principal value of the disc-averaged strain tensor.

    This is the critical-distance strain magnitude of SPEC §6; its maximum over the
    elements is compared with the elastic-limit strain ``e_L``. With ``ell = 0`` it is the
    element strain magnitude of SPEC §1.

    Parameters
    ----------
    mesh : Mesh
    strains : ndarray, shape (m, 3) or (k, m, 3)
        Engineering element strains ``[exx, eyy, gamma_xy]`` (dimensionless).
    ell : float or None
        Critical distance (m), finite and >= 0; ignored when ``operator`` is given.
    operator : sparse matrix, shape (m, m), optional
        A precomputed :func:`averaging_operator` of this mesh.

    Returns
    -------
    ndarray, shape (m,) or (k, m)
        Averaged strain magnitude per element (dimensionless).
    """
    avg = averaged_strains(mesh, strains, ell, operator)
    mag = np.abs(principal_strains(avg.reshape(-1, 3))).max(axis=1)
    return mag.reshape(avg.shape[:-1])


def _magnitudes(T: np.ndarray) -> np.ndarray:
    """Largest absolute principal value of engineering strain tensors ``T (..., 3)``:
    ``|c| + r`` (centre and radius of Mohr's circle), bit for bit the
    ``max(|c + r|, |c - r|)`` of :func:`~deformclosure.elasticity.strain.principal_strains`
    (``r >= 0``, rounding is monotone), with no ``(..., 2)`` temporaries."""
    T = np.asarray(T, float)
    exx, eyy, g = T[..., 0], T[..., 1], T[..., 2]
    out = np.hypot(0.5 * (exx - eyy), 0.5 * g)
    out += np.abs(0.5 * (exx + eyy))
    return out


def _stack(mesh_m: int, strains: np.ndarray) -> np.ndarray:
    e = np.asarray(strains, float)
    if e.ndim not in (2, 3) or e.shape[-2:] != (mesh_m, 3):
        raise MeshError(f"strains: shape {e.shape} does not fit this mesh of {mesh_m} triangles; "
                        f"give ({mesh_m}, 3) or (k, {mesh_m}, 3) [exx, eyy, gamma_xy] per element")
    return e


def _as_stack(mesh_m: int, strains: np.ndarray) -> tuple[np.ndarray, bool]:
    """Checked ``strains`` as a stack ``(k, m, 3)`` and whether one field ``(m, 3)`` was
    given (the caller returns its single result unstacked)."""
    e = _stack(mesh_m, strains)
    return (e, False) if e.ndim == 3 else (e[None], True)


class _RowPool:
    """Rows of ``W`` built so far, their weights and columns in one pair of growing arrays
    (at most ``cap`` pairs); row ``i`` of the mesh is at ``start[i]`` for ``length[i]``."""

    def __init__(self, m: int, cap: int) -> None:
        self.m, self.cap = m, max(int(cap), 0)
        self.start = np.full(m, -1, np.int64)
        self.length = np.zeros(m, np.int64)
        # the whole cap, uninitialised: the pages are mapped only as pairs are written, so
        # memory grows with use and nothing is ever copied to grow
        self.data = np.empty(self.cap)
        self.indices = np.empty(self.cap, np.int32)
        self.size = 0

    def clear(self) -> None:
        self.start[:] = -1
        self.length[:] = 0
        self.size = 0

    def missing(self, rows: np.ndarray) -> np.ndarray:
        """The distinct ``rows`` not held (sorted)."""
        return np.unique(rows[self.start[rows] < 0])

    def fits(self, pairs: int) -> bool:
        return self.size + pairs <= self.cap

    def add(self, rows: np.ndarray, W: sp.csr_matrix) -> None:
        """Keep ``W`` (CSR, row ``k`` = mesh row ``rows[k]``); the caller checked :meth:`fits`."""
        end = self.size + W.nnz
        self.data[self.size:end] = W.data
        self.indices[self.size:end] = W.indices
        self.start[rows] = self.size + W.indptr[:-1]
        self.length[rows] = np.diff(W.indptr)
        self.size = end

    def rows(self, rows: np.ndarray) -> sp.csr_matrix:
        """The held ``rows`` as a CSR matrix ``(len(rows), m)``: the same arrays they were
        built with (a gather of their ranges)."""
        lengths = self.length[rows]
        indptr = np.zeros(len(rows) + 1, np.int64)
        np.cumsum(lengths, out=indptr[1:])
        at = np.repeat(self.start[rows] - indptr[:-1], lengths) + np.arange(indptr[-1])
        if indptr[-1] < np.iinfo(np.int32).max:       # one index type: no upcast copy
            indptr = indptr.astype(np.int32)
        return sp.csr_matrix((self.data[at], self.indices[at], indptr),
                             shape=(len(rows), self.m))


class DiscAverage:
    """The critical-distance averages of one mesh and ``ℓ``, row by row (SPEC §6).

    The same numbers as :func:`averaging_operator` (``W @ strains``) without holding ``W``:
    the rows it needs are built from a KD-tree of the centroids (the same distances as
    ``W``'s) in chunks of at most :data:`CHUNK_PAIRS` element pairs, so its memory is
    ``O(m)`` plus one chunk. A grid of square cells about ``ℓ / CELLS_PER_ELL`` wide bounds
    the elements of each disc: every element within ``ℓ`` of an element of cell ``c`` lies
    in the cells of a fixed footprint around ``c`` (those whose nearest points are at most
    ``ℓ`` apart, with a margin of 1e-6 cell for the rounding of the cell index). That gives,
    in ``O(m)``, an upper bound of each disc's size (to size the chunks) and of each disc's
    largest element strain magnitude, which bounds its average (the magnitude is a norm:
    the average over a disc cannot exceed the largest magnitude in it). Built once per mesh
    and ``ℓ`` by :func:`disc_average`.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh (nodes in m).
    ell : float
        Critical distance ``ℓ`` (m), finite and >= 0 (``0``: the element strains).

    Raises
    ------
    GraspError
        If ``ell`` is negative or not finite.
    """

    def __init__(self, mesh, ell: float) -> None:
        from scipy.spatial import cKDTree  # lazy: scipy.spatial is slow to import

        self.ell = _check_ell(ell)
        self.centroids, self.areas = _centroids_and_areas(mesh)
        self.m = len(self.areas)
        self._tree = cKDTree(self.centroids) if self.ell > 0.0 else None
        #: element pairs (rows' non-zeros of ``W``) built so far, for the benchmarks
        self.pairs_built = 0
        self._pool: _RowPool | None = None
        if self.ell > 0.0:
            self._build_grid()
            # discs holding every element (ℓ beyond the farthest corner of the centroids'
            # box): one average, the part's area-weighted mean, for all of them
            c = self.centroids
            far = np.maximum(c - c.min(axis=0), c.max(axis=0) - c)
            self._whole = np.hypot(far[:, 0], far[:, 1]) <= self.ell * (1.0 - PRUNE_MARGIN)
        else:
            self._whole = np.zeros(self.m, bool)
        self._rep = int(np.argmax(self._whole)) if self._whole.any() else -1

    # ------------------------------------------------------------------ the grid bound
    def _build_grid(self) -> None:
        from scipy import ndimage

        c, m = self.centroids, self.m
        lo = c.min(axis=0)
        span = c.max(axis=0) - lo
        # about 4 cells per element at most (a tiny ℓ): coarser cells, a 3 × 3 footprint
        most = 4.0 * max(m, 16)
        h = max(self.ell / CELLS_PER_ELL, math.sqrt(span[0] * span[1] / most),
                span.max() / most)
        shape = (np.floor(span / h) + 1).astype(np.int64)          # (nx, ny)
        ij = np.minimum(np.floor((c - lo) / h).astype(np.int64), shape - 1)
        self._cell = ij[:, 1] * shape[0] + ij[:, 0]               # row-major (y, x)
        self._grid_shape = (int(shape[1]), int(shape[0]))
        reach = self.ell / h                                        # ℓ in cells
        R = int(math.floor(reach + 1.0 + 1e-6))
        d = np.arange(-R, R + 1)
        gap = np.maximum(np.abs(d) - 1.0 - 1e-6, 0.0)               # nearest points, in cells
        self._footprint = gap[:, None] ** 2 + gap[None, :] ** 2 <= reach * reach
        self._order = np.argsort(self._cell, kind="stable")
        self._cells, self._starts = np.unique(self._cell[self._order], return_index=True)
        count = np.zeros(self._grid_shape).ravel()
        count[self._cells] = np.diff(np.append(self._starts, m))
        within = ndimage.correlate(count.reshape(self._grid_shape),
                                   self._footprint.astype(float), mode="constant", cval=0.0)
        #: upper bound of the number of elements in each element's disc
        self.disc_size_bound = within.ravel()[self._cell].astype(np.int64)

    def _cell_bound(self, cellmax: np.ndarray) -> np.ndarray:
        """``(k, cells)`` largest magnitude per cell -> the largest within each cell's
        footprint: the bound of every element of the cell."""
        from scipy import ndimage

        grid = cellmax.reshape(len(cellmax), *self._grid_shape)
        top = ndimage.maximum_filter(grid, footprint=self._footprint[None], mode="constant",
                                     cval=0.0)
        return top.reshape(len(cellmax), -1)

    def _cell_max(self, magnitudes: np.ndarray) -> np.ndarray:
        """Largest of ``magnitudes (m,)`` in each grid cell, shape (cells,)."""
        out = np.zeros(self._grid_shape[0] * self._grid_shape[1])
        out[self._cells] = np.maximum.reduceat(magnitudes[self._order], self._starts)
        return out

    def bound(self, magnitudes: np.ndarray) -> np.ndarray:
        """Upper bound of the disc-averaged magnitude of every element: the largest element
        magnitude in the cells its disc may reach.

        Parameters
        ----------
        magnitudes : ndarray, shape (m,) or (k, m)
            Element strain magnitudes (dimensionless, >= 0), one field or ``k``.

        Returns
        -------
        ndarray, same shape
            ``bound[i] >= max(magnitudes[j] for j in disc(i))`` (dimensionless).
        """
        mag = np.asarray(magnitudes, float)
        if self.ell == 0.0:
            return mag.copy()
        flat = mag.reshape(-1, self.m)
        cellmax = np.stack([self._cell_max(f) for f in flat])
        return self._cell_bound(cellmax)[:, self._cell].reshape(mag.shape)

    # ------------------------------------------------------------------ rows of W
    def _chunks(self, rows: np.ndarray):
        """Consecutive slices of ``rows`` holding at most :data:`CHUNK_PAIRS` pairs (by
        the disc-size bound; at least one row each)."""
        if self.ell == 0.0:
            size = np.ones(len(rows))
        else:
            size = self.disc_size_bound[rows]
        ends = np.cumsum(size)
        start = 0
        while start < len(rows):
            base = ends[start - 1] if start else 0
            stop = int(np.searchsorted(ends, base + CHUNK_PAIRS, side="right"))
            stop = max(stop, start + 1)
            yield slice(start, stop)
            start = stop

    def operator_rows(self, rows: np.ndarray) -> sp.csr_matrix:
        """Rows ``rows`` of the averaging operator ``W`` (:func:`averaging_operator`).

        Parameters
        ----------
        rows : ndarray of int, shape (r,)
            Element indices; their discs should hold about :data:`CHUNK_PAIRS` pairs at
            most (:meth:`averaged` splits larger requests).

        Returns
        -------
        scipy.sparse.csr_matrix, shape (r, m)
            Row-stochastic (dimensionless), columns sorted within each row.
        """
        rows = np.asarray(rows, dtype=np.int64).ravel()
        r = len(rows)
        if self.ell == 0.0:
            return sp.csr_matrix((np.ones(r), (np.arange(r), rows)), shape=(r, self.m))
        pool = self._pool
        if pool is None:
            return self._build_rows(rows)
        miss = pool.missing(rows)
        if len(miss):
            W = self._build_rows(miss)
            if not pool.fits(W.nnz):
                # full: start again with this request's rows (all of them, when they fit)
                pool.clear()
                if len(miss) < len(np.unique(rows)):
                    miss = np.unique(rows)
                    W = self._build_rows(miss)
                if not pool.fits(W.nnz):
                    return W[np.searchsorted(miss, rows)]
            pool.add(miss, W)
        return pool.rows(rows)

    @contextmanager
    def reusing_rows(self, max_bytes: float = DISC_ROW_POOL_BYTES) -> Iterator[None]:
        """Keep the rows of ``W`` built inside the block (up to ``max_bytes``) and reuse
        them: for a sequence of fields whose maxima lie in the same discs (the breakpoints
        of one path). The same numbers as without; the pool is dropped at the end."""
        if self._pool is not None or self.ell == 0.0:      # nested, or nothing to keep
            yield
            return
        self._pool = _RowPool(self.m, int(max_bytes // ROW_POOL_BYTES_PER_PAIR))
        try:
            yield
        finally:
            self._pool = None

    def _build_rows(self, rows: np.ndarray) -> sp.csr_matrix:
        """Rows ``rows`` of ``W`` from the KD-trees (:meth:`operator_rows`)."""
        from scipy.spatial import cKDTree

        r = len(rows)
        # the distances of query_pairs: d <= ℓ with the same squared-distance arithmetic
        pairs = cKDTree(self.centroids[rows]).sparse_distance_matrix(
            self._tree, self.ell, output_type="ndarray")
        i, j = pairs["i"], pairs["j"]
        del pairs
        self.pairs_built += len(i)
        weights = self.areas[j]
        weights /= np.bincount(i, weights=weights, minlength=r)[i]
        return sp.csr_matrix((weights, (i, j)), shape=(r, self.m))

    def averaged(self, strains: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """Disc-averaged strain tensors at ``rows`` (default: every element).

        Parameters
        ----------
        strains : ndarray, shape (m, 3) or (k, m, 3)
            Engineering element strains ``[exx, eyy, gamma_xy]`` (dimensionless).
        rows : ndarray of int, shape (r,), optional
            Elements whose averages are wanted.

        Returns
        -------
        ndarray, shape (r, 3) or (k, r, 3)
            ``(W @ strains)[rows]`` (dimensionless).

        Raises
        ------
        MeshError
            If ``strains`` do not fit the mesh.
        """
        E, single = _as_stack(self.m, strains)
        rows = np.arange(self.m) if rows is None else np.asarray(rows, np.int64).ravel()
        out = np.empty((len(E), len(rows), 3))
        if self.ell == 0.0:
            out[:] = E[:, rows]
        else:
            every = np.arange(len(E))
            whole = self._whole[rows]
            if whole.any():             # one row for every disc that holds the whole part
                out[:, whole] = self._products(self.operator_rows([self._rep]), E, every)
            rest = np.flatnonzero(~whole)
            for part in self._chunks(rows[rest]):
                out[:, rest[part]] = self._products(self.operator_rows(rows[rest[part]]), E,
                                                    every)
        return out[0] if single else out

    def _products(self, W: sp.csr_matrix, E: np.ndarray, fields: np.ndarray) -> np.ndarray:
        """``W @ E[f]`` for every ``f`` in ``fields``, shape ``(len(fields), r, 3)``.

        One product per batch of fields on the columns ``W`` uses (the few elements of
        its discs), so no ``(m, 3k)`` copy of the stack is made; each entry is the same sum,
        in the same order, as ``W @ E[f]``.
        """
        # the used columns, sorted, and each index's place among them: np.unique's answer
        # without its sort (a mark per element: O(m + nnz); the sort was ~40 % of the
        # elastic limit's time at 80k nodes)
        used = np.zeros(W.shape[1], bool)
        used[W.indices] = True
        cols = np.flatnonzero(used)
        slot = np.empty(W.shape[1], W.indices.dtype)
        slot[cols] = np.arange(len(cols), dtype=W.indices.dtype)
        Wl = sp.csr_matrix((W.data, slot[W.indices], W.indptr),
                           shape=(W.shape[0], len(cols)))
        out = np.empty((len(fields), W.shape[0], 3))
        step = max(1, CHUNK_PAIRS // max(3 * len(cols), 1))       # values of X at once
        for b in range(0, len(fields), step):
            fb = fields[b:b + step]
            X = E[fb[:, None], cols[None, :]]                      # (f, c, 3)
            X = np.ascontiguousarray(X.transpose(1, 0, 2)).reshape(len(cols), 3 * len(fb))
            out[b:b + len(fb)] = (Wl @ X).reshape(W.shape[0], len(fb), 3).transpose(1, 0, 2)
        return out

    # ------------------------------------------------------------------ maxima
    def maxima(self, strains: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Largest disc-averaged strain magnitude over the elements, and where.

        The maximum over ``i`` of the largest absolute principal value of
        ``(W @ strains)[i]`` — :func:`averaged_strain_magnitude` maximised over the
        elements — averaging only the rows that can hold it: first the rows of each field's
        :data:`SEED_ROWS` largest element magnitudes, then, by decreasing bound
        (:meth:`bound`, per grid cell), every row whose bound reaches the largest average
        found so far. Besides ``strains`` it holds ``O(k × cells + m)`` numbers and one
        chunk of rows.

        Parameters
        ----------
        strains : ndarray, shape (m, 3) or (k, m, 3)
            Engineering element strains (dimensionless), one field or ``k``.

        Returns
        -------
        values : float or ndarray, shape (k,)
            The maxima (dimensionless).
        elements : int or ndarray of int, shape (k,)
            An element attaining each (the first of equal averages, as ``numpy.argmax``).

        Raises
        ------
        MeshError
            If ``strains`` do not fit the mesh.
        """
        E, single = _as_stack(self.m, strains)
        k = len(E)
        cells = self._grid_shape[0] * self._grid_shape[1] if self.ell > 0.0 else 1
        group = max(1, int(FIELD_CHUNK_BYTES // (FIELD_BYTES_PER_CELL * cells)))
        if self.ell > 0.0 and k > group:
            # each field's maximum is its own (the pruning only skips rows that cannot
            # reach it; ties go to the first element): groups of fields, bounded memory
            parts = [self.maxima(E[a:a + group]) for a in range(0, k, group)]
            return (np.concatenate([v for v, _ in parts]),
                    np.concatenate([i for _, i in parts]))
        best = np.full(k, -1.0)
        arg = np.zeros(k, np.int64)
        if self.ell == 0.0:
            for f in range(k):
                v = _magnitudes(E[f])
                best[f], arg[f] = v.max(), v.argmax()
            return (float(best[0]), int(arg[0])) if single else (best, arg)
        s = min(SEED_ROWS, self.m)
        ncells = self._grid_shape[0] * self._grid_shape[1]
        cellmax = np.zeros((k, ncells))
        seeds, finite = [], np.ones(k, bool)
        # the fields' magnitudes in one pass when they fit: a stack solved together is laid
        # out field-fastest, so one field at a time reads every field's cache lines
        mags = _magnitudes(E) if 8.0 * k * self.m <= FIELD_CHUNK_BYTES else None
        for f in range(k):          # else one field at a time: O(m) temporaries
            mag = _magnitudes(E[f]) if mags is None else mags[f]
            if not np.isfinite(mag).all():      # NaN or inf: every row, as W @ strains does
                finite[f] = False
                v = _magnitudes(self.averaged(E[f]))
                best[f], arg[f] = v.max(), v.argmax()
                continue
            cellmax[f] = self._cell_max(mag)
            seeds.append(np.argpartition(-mag, s - 1)[:s])
        fin = np.flatnonzero(finite)

        def take(rows: np.ndarray, need: np.ndarray) -> None:
            """Average ``rows`` for the fields ``fin`` that ``need (len(fin), r)`` them;
            update the maxima."""
            for part in self._chunks(rows):
                r, nd = rows[part], need[:, part]
                use = nd.any(axis=1)
                if not use.any():
                    continue
                fields, nd = fin[use], nd[use]
                v = np.where(nd, _magnitudes(self._products(self.operator_rows(r), E, fields)),
                             -np.inf)                              # (f, r)
                top = v.max(axis=1)
                at = np.where(v == top[:, None], r[None, :], self.m).min(axis=1)
                better = (top > best[fields]) | ((top == best[fields]) & (at < arg[fields]))
                best[fields[better]], arg[fields[better]] = top[better], at[better]

        if len(fin):
            seeds = np.concatenate(seeds)
            if self._rep >= 0:          # whole-part discs: one stands for all (equal means)
                seeds = np.append(np.where(self._whole[seeds], self._rep, seeds), self._rep)
            seeds = np.unique(seeds)
            take(seeds, np.ones((len(fin), len(seeds)), bool))
            ub = self._cell_bound(cellmax[fin])                    # (f, cells)
            del cellmax

            def needed(cells: np.ndarray) -> np.ndarray:
                thr = np.where(best[fin] > 0, best[fin] * (1.0 - PRUNE_MARGIN), 0.0)
                u = ub[:, cells]
                return (u >= thr[:, None]) & (u > 0)

            hot = np.flatnonzero(needed(np.arange(ncells)).any(axis=0))
            if len(hot):
                # rows of the hot cells, largest bound relative to the maximum so far first
                thr0 = np.where(best[fin] > 0, best[fin], np.inf)[:, None]
                with np.errstate(invalid="ignore"):
                    rank = np.nan_to_num((ub[:, hot] / thr0), nan=np.inf).max(axis=0)
                counts = np.bincount(self._cell, minlength=ncells)
                order = hot[np.argsort(-rank, kind="stable")]
                starts = np.searchsorted(self._cell[self._order], order)
                rows = np.concatenate([self._order[a:a + n] for a, n in
                                       zip(starts, counts[order])])
                seen = self._whole.copy()
                seen[seeds] = True
                rows = rows[~seen[rows]]
                for part in self._chunks(rows):
                    r = rows[part]
                    nd = needed(self._cell[r])                     # with the maxima so far
                    keep = nd.any(axis=0)
                    if keep.any():
                        take(r[keep], nd[:, keep])
        # an all-zero average: numpy's argmax is the first element
        zero = finite & (best <= 0)
        arg[zero], best[zero] = 0, 0.0
        return (float(best[0]), int(arg[0])) if single else (best, arg)

    def candidates(self, magnitudes: np.ndarray, level: float) -> np.ndarray:
        """Elements whose disc average may reach ``level``: those whose :meth:`bound` of
        ``magnitudes (m,)`` is at least ``(1 - PRUNE_MARGIN) · level``; sorted (int)."""
        ub = self.bound(np.asarray(magnitudes, float).reshape(self.m))
        return np.flatnonzero(ub >= level * (1.0 - PRUNE_MARGIN))


def disc_average(mesh, ell: float) -> DiscAverage:
    """The :class:`DiscAverage` of ``mesh`` and ``ell`` (m), built once and kept with the
    mesh (its ``O(m)`` arrays: centroids, areas, KD-tree, grid).

    Raises
    ------
    GraspError
        If ``ell`` is negative or not finite.
    """
    ell = _check_ell(ell)
    cache = getattr(mesh, "_cache", None)
    key = ("disc_average", ell)
    if cache is not None and key in cache:
        return cache[key]
    disc = DiscAverage(mesh, ell)
    if cache is not None:
        cache[key] = disc
    return disc


def averaged_strain_maximum(mesh, strains: np.ndarray, ell: float) -> float | np.ndarray:
    """Largest critical-distance strain magnitude over the elements (SPEC §6): the strain
    measure compared with ``e_L``, for one field or each of a stack.

    ``averaged_strain_magnitude(mesh, strains, ell).max(axis=-1)``, computed from the few
    discs that can hold the maximum (:meth:`DiscAverage.maxima`); the one home of the
    maximum for every elastic-limit caller.

    Parameters
    ----------
    mesh : Mesh
    strains : ndarray, shape (m, 3) or (k, m, 3)
        Engineering element strains ``[exx, eyy, gamma_xy]`` (dimensionless).
    ell : float
        Critical distance (m), finite and >= 0.

    Returns
    -------
    float or ndarray, shape (k,)
        The maximum (dimensionless).

    Raises
    ------
    GraspError
        If ``ell`` is invalid.
    MeshError
        If ``strains`` do not fit the mesh.
    """
    return disc_average(mesh, ell).maxima(strains)[0]
