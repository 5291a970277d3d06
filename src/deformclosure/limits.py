"""Resource limits: refuse early, from a size estimate, what cannot finish or fit in memory.

Every heavy step of the package has a cost that follows from sizes known before it
starts: the number of triangles a part will mesh into (its area over ``max_area``, its
boundary and its narrow features), the number of boundary nodes ``p`` of a mesh (the
paper model's contact graph has ``p²/2`` vertices; both models condense the stiffness
onto dense ``2p × 2p`` boundary matrices), the number of nodes ``n`` (the sparse
factorisation of ``K``), the pixels of a slice. This module holds, in one place, the
maximum of each, what it protects, the measured cost per unit it is derived from, and the
checks that compare a request against it before the work begins. Each check raises the
package's usual one-line error (:class:`~deformclosure.errors.PartError`,
:class:`~deformclosure.errors.GraspError`, …) naming the field or option and the fix.

The maxima are set for a machine with :data:`MEMORY_BUDGET` = 4 GB; the costs were
measured with ``benchmarks/bench_limits.py``, which runs every command at (or near) its
documented maximum and prints its peak resident memory and time.

The module is part of the foundation layer (``docs/architecture.md``): it imports only
:mod:`~deformclosure.choices` and :mod:`~deformclosure.errors`, and its checks take plain
sizes and rings, so every layer may call them (``part`` and ``mesh`` on reading and
meshing a part). What needs a model — the size of a mesh's analysis under that model —
is estimated beside the model and passed here as numbers:
:func:`deformclosure.grasp.size_limits.check_paper_size` and
:func:`deformclosure.pads.size_limits.check_pads_size` call :func:`check_plan_size`.

The CLI builds its ``--help`` texts from the maxima (:func:`limits_help`), so importing
this module loads no numpy or shapely: the functions that need them import them.

CPU threads are a resource too: :func:`blas_threads` caps the BLAS threads of the dense
steps (:data:`BLAS_THREADS`), the one place the package sets them (threadpoolctl,
imported on first use).
"""

from __future__ import annotations

import math
import os
import threading
from contextlib import contextmanager
from dataclasses import dataclass
from numbers import Integral
from typing import TYPE_CHECKING, Iterator, Sequence

from .choices import MODELS, choose
from .errors import DeformClosureError, GraspError, PartError

if TYPE_CHECKING:
    import numpy as np

__all__ = [
    "MEMORY_BUDGET",
    "MAX_COORDINATE",
    "MAX_BODY_FRACTION",
    "MIN_PAD_RADIUS_FRACTION",
    "MIN_DISC_RADIUS_FRACTION",
    "check_body_size",
    "MAX_TRIANGLES",
    "MAX_THIN_ELEMENTS",
    "MIN_GAP_FRACTION",
    "MAX_MESH_POINTS",
    "MAX_BOUNDARY_NODES_PAPER",
    "MAX_BOUNDARY_NODES_PADS",
    "MAX_AVERAGING_NONZEROS",
    "MAX_SLICE_RESOLUTION",
    "MeshEstimate",
    "estimate_triangles",
    "check_mesh_size",
    "check_mesh_result",
    "check_ring_gaps",
    "ring_gap_pairs",
    "local_feature_sizes",
    "points_within",
    "check_strain_responses",
    "steiner_cap",
    "check_mesh_points",
    "estimate_model_bytes",
    "check_plan_size",
    "check_slice_size",
    "format_count",
    "limits_help",
    "holding",
    "kept_bytes",
    "BLAS_THREADS",
    "blas_threads",
    "usable_cpus",
]

GB = 1e9

#: Memory every documented maximum must fit in (bytes): 4 GB, including the Python
#: interpreter and the imported libraries (about 0.15 GB).
MEMORY_BUDGET = 4.0 * GB

#: Resident memory of the interpreter with numpy, scipy, shapely, numba and the package
#: imported (bytes), measured: 0.15-0.17 GB at a command's first factorisation
#: (``benchmarks/bench_memory.py``).
BASE_BYTES = 0.16 * GB

#: Largest coordinate magnitude accepted in a part file or a drawing (in its units);
#: beyond it, areas overflow and the geometry checks are meaningless.
MAX_COORDINATE = 1e12

#: Largest finger or pad size (disc radius, pad radius, pad width) as a multiple of the
#: part's diameter: beyond it the body is a wall (use a half-plane finger) and its gaps
#: lose the part's digits to cancellation (``|p − c| − r`` with ``r`` ≫ the part).
MAX_BODY_FRACTION = 100.0

#: Smallest pad radius as a fraction of the part's diameter: a thousand times the SPEC §3
#: touching tolerance; below it the pad's round end is a point at every mesh the limits
#: allow (a 1e-300 mm pad was solved, meaninglessly, as one).
MIN_PAD_RADIUS_FRACTION = 1e-6

#: Smallest disc-finger radius for ``check`` as a fraction of the part's diameter. The
#: release landscape's lattice step is at most half the smallest disc radius (so a move
#: cannot jump over a disc) and at least D/1000 (the finest ``--grid-steps``); a smaller
#: disc shrinks the step without bound (a 1e-300 mm disc ran past 60 s and 16,300
#: placements). Use a point finger for a disc smaller than this.
MIN_DISC_RADIUS_FRACTION = 2e-3

# --------------------------------------------------------------------------- meshing
#: Largest mesh (triangles) a part may be meshed into. Protects the sparse factorisation
#: of ``K`` that every analysis (optimize, plan, check) starts with: its fill grows like
#: ``n log n`` (:data:`FACTOR_BYTES_PER_NLOGN`): measured 5.2 GB at 400 000 nodes
#: (800 000 triangles), estimated 2.5 GB at 200 000 nodes, which leaves room for the rest
#: of an analysis in 4 GB (the analyses add their own estimate: a pads optimize with its
#: twin on a 190 000-triangle block measured 3.7 GB). ``mesh`` at the limit: 0.65 GB,
#: 12 s. The count is estimated before meshing
#: (:func:`estimate_triangles`) and enforced after it (the mesher's Steiner points are
#: capped, so a wrong estimate cannot run away).
MAX_TRIANGLES = 400_000

#: Largest number of boundary elements that narrow features of a part may force
#: (:attr:`MeshEstimate.thin_elements`). Protects the mesher's *time*: in a long narrow
#: strip the quality mesher is super-linear (measured: a 10 × 1e-4 mm strip, 2e5 boundary
#: elements, 144 000 triangles in 2.4 s; 10 × 3e-5 mm, 420 000 triangles in 78 s;
#: 10 × 1e-5 mm, 1.2 million triangles in 123 s).
MAX_THIN_ELEMENTS = 100_000

#: Smallest gap between two rings of a part (a hole and the outer ring, or two holes), as
#: a fraction of the part's diameter. Protects the mesher: a hole 1e-7 mm from the outer
#: ring was refused only after 49 s and 3.75 GB; now it is refused on reading the part.
MIN_GAP_FRACTION = 1e-6

#: Largest number of extra points (``mesh.points`` and ``--at``) inserted as mesh nodes.
#: Each becomes a node with its own graded neighbourhood, which the triangle estimate
#: counts; inserting them takes an R-tree query each (10 000 points on a 20 000-vertex
#: ring used to build a 10 000 × 20 000 table).
MAX_MESH_POINTS = 50_000

# Triangles per unit, measured with Triangle (20250106) at min angles 10..34 degrees:
# area-driven triangles per area/max_area, per boundary vertex (its graded neighbourhood),
# per boundary element forced by a narrow feature.
_ANGLES = (0.0, 10.0, 20.0, 25.0, 30.0, 33.0, 34.0)
_PER_AREA = (1.6, 1.6, 1.6, 1.6, 1.6, 1.75, 1.9)
_PER_VERTEX = (1.9, 1.9, 3.0, 4.1, 4.9, 8.0, 9.3)
_PER_THIN = (0.26, 0.26, 0.41, 0.54, 0.7, 0.8, 0.8)
# At 30 degrees a vertex's neighbourhood is about 2.8 + 0.36 log2(h / lfs) triangles (h: the
# element size of max_area, lfs: the vertex's local feature size), fitted on circles of
# 1000 to 20 000 vertices; other angles scale it like _PER_VERTEX.
_VERTEX_30 = 4.9
_VERTEX_BASE = 2.8
_VERTEX_PER_HALVING = 0.36

# --------------------------------------------------------------------------- analyses
#: Sparse LU of ``K`` (METIS nested dissection, SuperLU without pivoting) and the
#: factorised solver's other per-node arrays: bytes per ``n log2 n`` (n = mesh nodes).
#: Measured (``benchmarks/bench_memory.py``, issue 25) as a solver's resident memory less
#: its mesh and boundary terms: 300 at 5 000 nodes, 310 at 20 000, 340 at 40 000 (12 × 20
#: mm block); counted 360.
FACTOR_BYTES_PER_NLOGN = 360.0

#: Bytes per mesh triangle held by a mesh, its stiffness matrix and their temporaries.
MESH_BYTES_PER_TRIANGLE = 1_000.0

#: Dense boundary matrices of a condensation (compliance, its Cholesky factor and the
#: copies made while forming it): bytes per ``p²`` (p = boundary nodes) — five
#: ``2p × 2p`` float arrays.
CONDENSE_BYTES_PER_P2 = 5 * 4 * 8.0

#: Largest number of jaw nodes (outer-loop nodes; every loop's for expanding grasps) for
#: ``--model paper``. Protects the contact graph over all ``p(p−1)/2`` node pairs: building
#: it takes :data:`PAPER_GRAPH_BYTES_PER_P2` bytes per ``p²`` (measured 2.0 GB at p = 1000,
#: 4.3 GB at p = 1400 — a 3000-vertex circle needed about 19 GB). Measured at the limit
#: (a 1200-vertex circle): plan 3.1 GB (122 s with --top 0), optimize 3.1 GB.
MAX_BOUNDARY_NODES_PAPER = 1_200

#: Peak bytes per ``p²`` of building the paper model's contact graph (measured).
PAPER_GRAPH_BYTES_PER_P2 = 2_100.0

#: Largest number of boundary nodes (all loops) for the pads model (optimize, plan) and
#: for ``check``. Protects the dense ``2p × 2p`` condensed and axis-constrained
#: compliances of the solver and of its noise-floor twin (:data:`PADS_SOLVER_BYTES_PER_P2`
#: each; ``check`` holds three) and the contact curves of the release landscape
#: (:data:`PADS_AXIS_BYTES_PER_NODE` per axis and node). Measured on a 2000-vertex circle:
#: plan 2.9 GB (345 s; screening only, ``--verify 0``: verifying beside the plan's
#: solvers and curves is estimated at 5.1 GB and refused), optimize 1.9 GB, check 1.9 GB.
MAX_BOUNDARY_NODES_PADS = 2_000

#: Bytes per ``p²`` kept by one pads solver (condensed and gauged compliances), and the
#: transient of building one: measured 167 and 95 (a solver of a 2000-vertex circle,
#: 5 900 nodes: 0.67 GB kept, 1.05 GB at its peak; 165 and 100 at 1000 vertices; issue 25,
#: earlier 215 and 55 with the previous condensation). The transient is gone once the
#: solver is built: it is one of the estimate's transients (``condensing``), not kept.
PADS_SOLVER_BYTES_PER_P2 = 170.0
PADS_WORK_BYTES_PER_P2 = 100.0

#: Bytes per grasp axis and boundary node of the release landscape's contact curves and
#: their caches, measured 310-350 (plans of the notched bar at 3 600 and 10 600 nodes,
#: 1440 axes; earlier 180-210 on 500- and 1000-node circles); counted 360.
PADS_AXIS_BYTES_PER_NODE = 360.0

#: Bytes per triangle of a pads analysis' transient on one mesh besides its elastic-limit
#: fields: the averages' grid, the strain-displacement matrices, the noise floor's twin
#: curves; fitted with the fields below to optimize on the notched bar at 2 500, 10 000
#: and 20 000 nodes (transients of 2.5-4.5 kB per triangle in all before the limit's
#: groups, ~2 kB after).
PADS_LEVEL_BYTES_PER_TRIANGLE = 1_000.0

#: The elastic limit holds the loads, displacements and strains of every breakpoint of the
#: start axis' path at once (``pads.limit.pad_elastic_limit``): bytes per breakpoint and
#: triangle, measured 51-58 (12 × 20 mm block, 20 000 and 40 000 nodes), counted 60; and
#: breakpoints per boundary node, measured 0.059-0.075 (the default pad, 5 000 to 40 000
#: nodes), counted 0.075. Before the averages' grid was taken in groups of fields
#: (``critical_distance.FIELD_CHUNK_BYTES``) a tiny ℓ cost 160 bytes per breakpoint and
#: triangle more: a 120 000-node block accepted at 3.9 GB used 10 GB (issue 25).
PADS_LIMIT_BYTES_PER_BREAKPOINT_TRIANGLE = 60.0
PADS_BREAKPOINTS_PER_BOUNDARY_NODE = 0.075

#: Most bytes of breakpoint loads, displacements and strains the pads' elastic limit holds
#: at once (``pads.limit.pad_elastic_limit`` takes a longer path in groups of
#: breakpoints): refined meshes put many more contacts, so breakpoints, under the pads
#: than the boundary count predicts (a 53 000-node adaptive level: ~200 breakpoints,
#: 1.5 GB before the groups).
PADS_LIMIT_CHUNK_BYTES = 200e6
#: Largest memory (bytes) of the rows of the averaging operator that the elastic limit's
#: scan keeps for reuse across its groups of breakpoints
#: (``critical_distance.DiscAverage.reusing_rows``; 12 bytes a pair). They grow like the
#: square of the triangles at a fixed ℓ (a disc's size and the number of hot discs both
#: ∝ m): measured 10.3 M pairs, 124 MB, at 80 000 nodes of the notched bar (160 000
#: triangles) — counted ``DISC_ROW_POOL_BYTES_PER_TRIANGLE2 · m²`` up to this cap.
DISC_ROW_POOL_BYTES = 160e6
DISC_ROW_POOL_BYTES_PER_TRIANGLE2 = 124e6 / 160_000.0 ** 2
#: Most breakpoints the pads' elastic limit solves together as it scans the path in order
#: for the crossing (``pads.limit.SCAN_GROUP``; none past the crossing is solved).
PADS_LIMIT_GROUP = 16

#: The placement landscape's compiled kernels (numba, loaded from the cache) and their
#: per-part arrays, held by ``check`` beside its solvers: measured 41-50 MB at 2 500 to
#: 20 000 nodes (``benchmarks/bench_memory.py``).
PLACEMENT_KERNEL_BYTES = 0.05 * GB

#: Share of the coarse grid's axes whose curves the release search of one pads
#: ``optimize`` level solves and keeps: measured 12.3-13.5 % (295-376 axes of the 48 × 50
#: grid of optimize and the 72 × 40 of a plan's verification: the notched bar held in its
#: notches, the first two levels at 1 800 to 20 600 nodes, ``bench_memory.py``); counted a
#: fifth. A plan solves every axis of its grid. Deeper levels search the saddle patches
#: too (:data:`PADS_SEARCH_PATCH_FRACTION`): the 589 of 2400 axes once counted here, and
#: 449, 1 099 and 3 187 axes at levels 3 to 5 (issue 25).
PADS_SEARCH_AXES_FRACTION = 0.2

#: Share of the fine vertices of the saddle patches (``(2f + 1)²`` a patch, ``f = 2^k`` at
#: level ``k + 1``, ``pads.saddle_grid``) that a refined level's release search solves
#: beyond the coarse grid's: measured 0.61-0.69 (levels 3 to 5 of the notched bar to
#: ``--rtol 0.005``, 1 800 to 13 300 nodes: 149 of 243, 799 of 1 156, 2 887 of 4 356, the
#: coarse part taken as level 1's 300 axes); counted three quarters.
PADS_SEARCH_PATCH_FRACTION = 0.75

#: Largest number of element pairs of the critical-distance averages (pads model, SPEC §6):
#: every element times the elements whose centroids lie within the critical distance ℓ
#: of its own — about ``m² π ℓ² / A``, the non-zeros of the averaging operator. The
#: analyses never hold that operator (``DiscAverage`` builds rows in chunks of bounded
#: memory, :data:`AVERAGING_CHUNK_BYTES`), so this protects the *work*: an evaluation whose
#: bound prunes nothing (a field export averages every element) visits every pair, about
#: 0.1 µs each (``benchmarks/bench_critical_distance.py``), 40 s at the limit.
MAX_AVERAGING_NONZEROS = 400_000_000

#: Peak bytes per non-zero of building the full averaging operator
#: (``averaging_operator``: pair list, COO, CSR); it refuses an operator above the budget.
AVERAGING_BYTES_PER_NONZERO = 60.0

#: Memory of the critical-distance averages as the analyses compute them: one chunk of
#: rows (``CHUNK_PAIRS`` = 400 000 pairs at about 100 bytes) plus, per triangle, the
#: centroids, areas, KD-tree and grid of ``DiscAverage`` (measured ~100 bytes, counted 150).
AVERAGING_CHUNK_BYTES = 40e6
AVERAGING_BYTES_PER_TRIANGLE = 150.0

#: Strain responses of the paper planner (``pair_elastic_limits``): bytes per perimeter
#: node and triangle (6 strain rows of 8 bytes) plus per perimeter node and node.
STRAIN_BYTES_PER_PM = 48.0
STRAIN_BYTES_PER_PN = 32.0

# --------------------------------------------------------------------------- slices
#: Largest ``--resolution`` (pixels per axis) of a D-space slice. The slice is computed
#: in blocks of pixels, so only its images grow with the resolution: per pixel 8 bytes of
#: energy, 1 byte per image (D_free, D_T, one per finger), and about
#: :data:`SLICE_JSON_BYTES_PER_VALUE` per value when written as JSON (measured: 2000 x
#: 2000 pixels, 4 fingers, JSON: 0.9 GB, 17 s; 4000 x 4000 took 3.3 GB before the blocks).
MAX_SLICE_RESOLUTION = 2_000

#: Peak bytes per image value while a slice is written as JSON (Python lists, text).
SLICE_JSON_BYTES_PER_VALUE = 60.0


def check_body_size(field: str, value: float, diameter: float, lo: float, *,
                    scale: float = 1.0, units: str = "m", hint: str = "") -> None:
    """Refuse a finger or pad size outside ``lo``..:data:`MAX_BODY_FRACTION` times the
    part's ``diameter`` (m); ``value`` in ``units`` of ``scale`` m each (``lo = 0`` admits
    0). One line naming ``field`` and the range.

    Raises
    ------
    DeformClosureError

    Examples
    --------
    >>> check_body_size("--pad-radius", 1e-300, 0.02, MIN_PAD_RADIUS_FRACTION, scale=1e-3,
    ...                 units="mm")                       # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    deformclosure.errors.DeformClosureError: --pad-radius = 1e-300 mm: give a size from 2e-05 to 2e+03 mm ...
    """
    v = float(value) * scale
    if not (math.isfinite(v) and lo * diameter <= v <= MAX_BODY_FRACTION * diameter
            and (lo > 0 or v >= 0)):
        D = diameter / scale
        raise DeformClosureError(f"{field} = {value:g} {units}: give a size from {lo * D:.3g} to "
                                 f"{MAX_BODY_FRACTION * D:.3g} {units} ({lo:g} to "
                                 f"{MAX_BODY_FRACTION:g} times the part's diameter, {D:.4g} "
                                 f"{units}){hint}")


# --------------------------------------------------------------------------- threads
#: BLAS threads of the package's dense steps: the loops over many small problems (one
#: contact path per grasp axis, the planner's screening, a landscape's placements), the
#: condensation's boundary inverse and the gauged compliance. Their matrices have a few
#: hundred to a few thousand rows; more threads gain nothing there and lose badly to the
#: machine's other processes (OpenBLAS threads spin while they wait). Measured on a 2-core
#: machine under load: LAPACK ``dpotri`` of a 2000 × 2000 factor 0.18 s on one thread and
#: 6-7 s on the default two; the pads ``optimize`` of a 5 600-node notched bar 8.5 s with
#: the default threads and 3.4 s with one (``benchmarks/bench_threads.py``). ``None``
#: leaves the threads as they are (e.g. a large idle machine running one job). More cores
#: pay off across jobs instead: batch workers or a Dask cluster (README "Using more
#: cores").
BLAS_THREADS: int | None = 1

_CONTROLLER = None
_OPEN_BLOCKS = 0        # blas_threads blocks entered and not left, in all threads
_LIMITER = None         # the threadpoolctl limit held while any block is open
_BLOCKS_LOCK = threading.Lock()


def _controller():
    """The process's threadpoolctl controller, made once (it scans the loaded libraries,
    so numpy's and scipy's BLAS are loaded before it)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        import numpy  # noqa: F401  (their BLAS libraries, before the scan)
        import scipy.linalg  # noqa: F401
        from threadpoolctl import ThreadpoolController

        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def usable_cpus() -> int:
    """The CPUs this process may run on (its affinity; ``os.cpu_count()`` off Linux), >= 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


@contextmanager
def blas_threads() -> Iterator[None]:
    """Run the block with at most :data:`BLAS_THREADS` BLAS threads (restored after).

    Put it around a loop over many small solves, or inside one dense step. The limit is
    the process's (BLAS has no other), so it is counted across threads: the first block
    entered in any thread sets it (about 30 µs), blocks entered while one is open cost
    nothing, and only the last block left, in whichever thread, restores the threads. A
    thread leaving its block therefore never changes the thread count under another
    thread's solve, whose sums would then be added in another order (plans run on threads
    as jobs on one Dask worker are bit-identical to one plan alone).

    Examples
    --------
    >>> import numpy as np
    >>> with blas_threads():
    ...     float(np.ones((3, 3)) @ np.ones(3) @ np.ones(3))
    9.0
    """
    global _OPEN_BLOCKS, _LIMITER
    if BLAS_THREADS is None:
        yield
        return
    with _BLOCKS_LOCK:
        if _OPEN_BLOCKS == 0:
            _release_openblas_control()
            _LIMITER = _controller().limit(limits=int(BLAS_THREADS), user_api="blas")
            _release_openblas_control()
        _OPEN_BLOCKS += 1
    try:
        yield
    finally:
        with _BLOCKS_LOCK:
            _OPEN_BLOCKS -= 1
            if _OPEN_BLOCKS == 0:
                _release_openblas_control()
                _LIMITER.restore_original_limits()
                _release_openblas_control()
                _LIMITER = None


def _release_openblas_control() -> None:
    """Let any thread set OpenBLAS's threads next.

    threadpoolctl ≥ 3.6 lets only one "controlling" thread change a pthreads OpenBLAS
    pool and silently ignores the others; a limit set without its ``with`` statement
    keeps that control in the thread that set it, so a block entered later in a worker
    thread would change nothing. :func:`blas_threads` serialises the changes itself (its
    lock), so it hands the control back after each one.
    """
    from threadpoolctl import OpenBLASController

    release = getattr(OpenBLASController, "clear_controlling_thread", None)
    if release is not None:              # older threadpoolctl: no controlling thread
        release(force=True)


def format_count(n: float) -> str:
    """A count for messages: ``1,200`` or ``3.9e+06``."""
    return f"{int(n):,}" if n < 1e7 else f"{n:.2g}"


def _rate(table: Sequence[float], min_angle: float) -> float:
    """A measured rate of :data:`_ANGLES` at ``min_angle`` (degrees, clipped to 0..34)."""
    import numpy as np

    return float(np.interp(float(min(max(min_angle, 0.0), 34.0)), _ANGLES, table))


def _part_area(rings: Sequence[np.ndarray]) -> float:
    """Area (m²) of the polygon with outer ring ``rings[0]`` and holes ``rings[1:]``."""
    import shapely

    return float(shapely.Polygon(rings[0], list(rings[1:])).area)


# --------------------------------------------------------------------------- rings
def _ring_arrays(rings: Sequence[np.ndarray]):
    import numpy as np

    sizes = np.array([len(r) for r in rings], dtype=np.int64)
    P = np.concatenate([np.asarray(r, float) for r in rings])
    start = np.repeat(np.cumsum(sizes) - sizes, sizes)
    size = np.repeat(sizes, sizes)
    loc = np.arange(len(P)) - start
    nxt = start + (loc + 1) % size
    prv = start + (loc - 1) % size
    ring = np.repeat(np.arange(len(rings)), sizes)
    return P, nxt, prv, ring


def local_feature_sizes(rings: Sequence[np.ndarray]) -> np.ndarray:
    """Distance from every ring vertex, through the part, to the nearest edge not incident
    to it (m), in ring order (outer first): the size of the smallest triangles a quality
    mesher must put there.

    It never exceeds the shorter incident edge (the next edge starts at the neighbour), so
    only edges within that distance are examined (a bounding-box query); an edge counts
    when the segment to its closest point passes through the part (a narrow slot of the
    exterior does not force small triangles). O((k + pairs) log k) for k vertices.
    """
    import numpy as np
    import shapely

    P, nxt, prv, _ = _ring_arrays(rings)
    Q = P[nxt]
    L = np.hypot(Q[:, 0] - P[:, 0], Q[:, 1] - P[:, 1])
    r = np.minimum(L, L[prv])
    lo, hi = np.minimum(P, Q), np.maximum(P, Q)
    tree = shapely.STRtree(shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1]))
    vi, ei = tree.query(shapely.box(P[:, 0] - r, P[:, 1] - r, P[:, 0] + r, P[:, 1] + r))
    keep = (ei != vi) & (ei != prv[vi])
    vi, ei = vi[keep], ei[keep]
    c, d = _closest_on_segments(P[vi], P[ei], Q[ei])
    lfs = r.copy()
    close = d < r[vi]
    if close.any():
        vi, c, d = vi[close], c[close], d[close]
        poly = shapely.Polygon(rings[0], list(rings[1:]))
        shapely.prepare(poly)
        mid = 0.5 * (P[vi] + c)
        inside = shapely.contains_xy(poly, mid[:, 0], mid[:, 1])
        np.minimum.at(lfs, vi[inside], d[inside])
    return lfs


def _closest_on_segments(p: np.ndarray, a: np.ndarray, b: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Closest points ``c`` (k, 2) of segments ``a``–``b`` to points ``p`` and the distances
    ``|p − c|`` (m), row by row (a degenerate segment is its end ``a``)."""
    import numpy as np

    ab = b - a
    t = np.clip(((p - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0.0, 1.0)
    c = a + t[:, None] * ab
    return c, np.hypot(p[:, 0] - c[:, 0], p[:, 1] - c[:, 1])


def points_within(polygon, points: np.ndarray, tol: float) -> np.ndarray:
    """Which ``points`` (q, 2) lie in ``polygon`` or within ``tol`` of it (m).

    The same as ``shapely.distance(points, polygon) <= tol`` but indexed: a prepared
    point-in-polygon test, then an R-tree of the boundary edges for the points outside —
    O((q + k) log k) instead of q × k segment distances (10 000 points on a 20 000-vertex
    ring: milliseconds instead of seconds).
    """
    import numpy as np
    import shapely

    pts = np.asarray(points, float).reshape(-1, 2)
    if not len(pts):
        return np.zeros(0, bool)
    shapely.prepare(polygon)
    inside = np.asarray(shapely.contains_xy(polygon, pts[:, 0], pts[:, 1]), bool)
    out = np.flatnonzero(~inside)
    if len(out):
        rings = [np.asarray(polygon.exterior.coords)] + [np.asarray(r.coords) for r in polygon.interiors]
        segs = np.concatenate([np.stack([r[:-1], r[1:]], axis=1) for r in rings])
        tree = shapely.STRtree(shapely.linestrings(segs))
        pi, _ = tree.query(shapely.points(pts[out]), predicate="dwithin", distance=tol)
        inside[out[np.unique(pi)]] = True
    return inside


@dataclass(frozen=True)
class MeshEstimate:
    """Estimated size of a quality mesh of a part, before meshing.

    Attributes
    ----------
    triangles : float
        Estimated number of triangles: area-driven (``area / max_area``), plus the graded
        neighbourhood of every boundary vertex and inserted point, plus the boundary
        elements forced by narrow features — each times its measured rate at the min angle.
    area_triangles : float
        ``area / max_area`` (a lower bound of the count).
    thin_elements : float
        Boundary elements that narrow features force beyond one per edge: ``∫ ds / lfs − 1``
        summed over the edges, with the local feature size ``lfs`` interpolated between
        the edge's vertices (a strip ``L`` long and ``w`` wide: about ``2 L / w``).
    narrowest : float
        Smallest local feature size at a vertex of the worst edge (m).
    worst_ring : int
        Ring (0 = outer, i + 1 = holes[i]) of the edge forcing the most elements.
    worst_length : float
        Length of that edge (m).
    """

    triangles: float
    area_triangles: float
    thin_elements: float
    narrowest: float
    worst_ring: int
    worst_length: float


def estimate_triangles(rings: Sequence[np.ndarray], max_area: float, min_angle: float = 30.0,
                       points: np.ndarray | None = None) -> MeshEstimate:
    """Estimate the triangle count of a quality mesh of a polygon with holes.

    Parameters
    ----------
    rings : sequence of ndarray (k, 2)
        Outer ring then holes (m), not closed, with any inserted boundary points.
    max_area : float
        Largest triangle area (m²).
    min_angle : float
        Smallest angle (degrees).
    points : ndarray (q, 2), optional
        Extra points (m) inserted inside the part.

    Returns
    -------
    MeshEstimate
        Within a factor of about 1.5 of Triangle's count on squares, circles with up to
        20 000 vertices, notched bars, thin strips and slots (measured).
    """
    import numpy as np

    points = np.zeros((0, 2)) if points is None else np.asarray(points, float).reshape(-1, 2)
    area = _part_area(rings)
    P, nxt, _, ring = _ring_arrays(rings)
    L = np.hypot(*(P[nxt] - P).T)
    lfs = np.maximum(local_feature_sizes(rings), 1e-300)
    ga, gb = lfs, lfs[nxt]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        integral = np.where(np.abs(gb - ga) <= 1e-9 * ga, L / ga,
                            L * np.log(gb / ga) / (gb - ga))
    integral = np.where(np.isfinite(integral), integral, L / np.minimum(ga, gb))
    thin = np.maximum(integral - 1.0, 0.0)
    per_area = _rate(_PER_AREA, min_angle)
    per_thin = _rate(_PER_THIN, min_angle)
    # Each vertex (and inserted point) is the centre of a graded neighbourhood whose size
    # grows with the number of halvings from the element size of max_area down to its
    # local feature size.
    grade = _rate(_PER_VERTEX, min_angle) / _VERTEX_30
    h = math.sqrt(4.0 * max_area / math.sqrt(3.0))
    depth = np.log2(np.maximum(h / lfs, 1.0))
    vertex = grade * float(np.sum(_VERTEX_BASE + _VERTEX_PER_HALVING * depth))
    if len(points):
        from scipy.spatial import cKDTree

        allp = np.concatenate([P, points])
        d, _ = cKDTree(allp).query(points, k=2)
        dp = np.log2(np.maximum(h / np.maximum(d[:, 1], 1e-300), 1.0))
        vertex += grade * float(np.sum(_VERTEX_BASE + _VERTEX_PER_HALVING * dp))
    n_area = area / max_area
    total = per_area * n_area + vertex + per_thin * float(thin.sum())
    w = int(np.argmax(thin)) if len(thin) else 0
    return MeshEstimate(triangles=total, area_triangles=n_area, thin_elements=float(thin.sum()),
                        narrowest=float(min(ga[w], gb[w])), worst_ring=int(ring[w]),
                        worst_length=float(L[w]))


def _ring_name(i: int) -> str:
    return "outer" if i == 0 else f"holes[{i - 1}]"


def check_mesh_size(rings: Sequence[np.ndarray], max_area: float, min_angle: float = 30.0,
                    points: np.ndarray | None = None, *, units: str = "m", scale: float = 1.0,
                    field: str = "max_area") -> MeshEstimate:
    """Refuse, before meshing, a mesh estimated above :data:`MAX_TRIANGLES` or a part
    whose narrow features force more than :data:`MAX_THIN_ELEMENTS` boundary elements.

    Parameters
    ----------
    rings, max_area, min_angle, points
        As :func:`estimate_triangles` (SI).
    units, scale : str, float
        Unit of lengths in messages and metres per unit.
    field : str
        Name of the max_area setting in messages (``mesh.max_area`` or ``--max-area``).

    Raises
    ------
    PartError
    """
    check_mesh_points(0 if points is None else len(points))
    ma = max_area / scale**2
    # The area alone (a lower bound of the count) refuses absurd requests before the
    # boundary is examined.
    area = _part_area(rings)
    per_area = _rate(_PER_AREA, min_angle)
    if per_area * area / max_area > MAX_TRIANGLES:
        n = per_area * area / max_area
        raise PartError(f"{field} = {ma:.3g} {units}²: the mesh would have about "
                        f"{format_count(n)} triangles (limit {MAX_TRIANGLES:,}); use {field} >= "
                        f"{max_area * n / MAX_TRIANGLES / scale**2:.2g} {units}²")
    est = estimate_triangles(rings, max_area, min_angle, points)
    if est.thin_elements > MAX_THIN_ELEMENTS:
        w = est.narrowest / scale
        ln = est.worst_length / scale
        raise PartError(
            f"{_ring_name(est.worst_ring)}: the part is only {w:.3g} {units} wide along a "
            f"{ln:.3g} {units} edge; meshing such narrow features needs about "
            f"{format_count(est.thin_elements)} boundary elements (limit {MAX_THIN_ELEMENTS:,}); "
            "widen or remove the narrow feature")
    if est.triangles > MAX_TRIANGLES:
        need = max_area * est.triangles / MAX_TRIANGLES / scale**2
        raise PartError(
            f"{field} = {ma:.3g} {units}²: the mesh would have about "
            f"{format_count(est.triangles)} triangles (limit {MAX_TRIANGLES:,}); use {field} >= {need:.2g} {units}² or "
            "simplify the part's boundary")
    return est


def steiner_cap() -> int:
    """Steiner points the mesher may add: enough for :data:`MAX_TRIANGLES` with room to
    spare, so a capped (truncated) mesh always exceeds the maximum and is refused."""
    return MAX_TRIANGLES


def check_mesh_result(n_triangles: int, max_area: float, *, units: str = "m",
                      scale: float = 1.0, field: str = "max_area") -> None:
    """Refuse a mesh that came out above :data:`MAX_TRIANGLES` (the estimate was low, or the
    mesher hit its Steiner-point cap).

    Raises
    ------
    MeshError
    """
    from .errors import MeshError

    if n_triangles > MAX_TRIANGLES:
        ma = max_area / scale**2
        raise MeshError(f"{field} = {ma:.3g} {units}²: the mesh has {n_triangles:,} triangles, "
                        f"more than the limit {MAX_TRIANGLES:,}; increase {field} or lower "
                        "mesh.min_angle")


def check_mesh_points(n_points: int, field: str = "mesh.points") -> None:
    """Refuse more than :data:`MAX_MESH_POINTS` extra mesh nodes.

    Raises
    ------
    PartError
    """
    if n_points > MAX_MESH_POINTS:
        raise PartError(f"{field}: {n_points:,} points, more than the limit {MAX_MESH_POINTS:,}; "
                        "insert only the intended contact locations")


def ring_gap_pairs(rings: Sequence[np.ndarray], min_gap: float
                   ) -> tuple[float, int, int] | None:
    """The closest pair of different rings nearer than ``min_gap`` (m): ``(gap, i, j)`` with
    ring indices ``i < j`` (0 = outer), or ``None``.

    Two segments are nearest at an endpoint of one of them, so it suffices to find, for
    every vertex, the edges of *other* rings within ``min_gap`` — an R-tree query with that
    radius, O(k log k) for k vertices in all, whatever the number of holes.
    """
    import numpy as np
    import shapely

    if len(rings) < 2:
        return None
    P, nxt, _, ring = _ring_arrays(rings)
    tree = shapely.STRtree(shapely.linestrings(np.stack([P, P[nxt]], axis=1)))
    vi, ei = tree.query(shapely.points(P), predicate="dwithin", distance=min_gap)
    other = ring[vi] != ring[ei]
    if not other.any():
        return None
    vi, ei = vi[other], ei[other]
    _, d = _closest_on_segments(P[vi], P[ei], P[nxt[ei]])
    k = int(np.argmin(d))
    i, j = sorted((int(ring[vi[k]]), int(ring[ei[k]])))
    return float(d[k]), i, j


def check_ring_gaps(outer: np.ndarray, holes: Sequence[np.ndarray], diameter: float, *,
                    units: str = "m", scale: float = 1.0) -> None:
    """Refuse a hole closer than :data:`MIN_GAP_FRACTION` × the diameter to the outer ring
    or to another hole (rings and diameter in m; ``scale`` m per ``units`` for the message).

    Raises
    ------
    PartError
        Naming the hole(s) and the gap.
    """
    if not len(holes):
        return
    min_gap = MIN_GAP_FRACTION * diameter
    found = ring_gap_pairs([outer, *holes], min_gap)
    if found is None:
        return
    g, i, j = found
    need = f"at least {min_gap / scale:.3g} {units}, {MIN_GAP_FRACTION:g} of the part's diameter"
    if i == 0:
        raise PartError(f"holes[{j - 1}]: only {g / scale:.3g} {units} from the outer ring ({need}, "
                        "is needed to mesh it); move the hole away from the edge, or open it into "
                        "the outer ring")
    raise PartError(f"holes[{i - 1}] and holes[{j - 1}]: only {g / scale:.3g} {units} apart ({need}, "
                    "is needed to mesh them); move them apart or merge them")


# --------------------------------------------------------------------------- analyses
_HELD: list[float] = []     # bytes held by the enclosing analyses, innermost last (:func:`holding`)


@contextmanager
def holding(nbytes: float) -> Iterator[None]:
    """Count ``nbytes`` (an estimate of what the caller keeps) in every memory estimate
    made inside the block: the estimates of later steps of one analysis see what the
    earlier ones still hold — the solvers of a refinement's coarser levels, a plan's
    solvers and curves while it verifies its best axes.

    Examples
    --------
    >>> with holding(1e9):
    ...     estimate_model_bytes("pads", n_nodes=1000, n_triangles=2000, n_boundary=100)["held"]
    1000000000.0
    """
    _HELD.append(float(nbytes))
    try:
        yield
    finally:
        _HELD.pop()


def kept_bytes(estimate: dict[str, float]) -> float:
    """What an analysis keeps after it ran, of its :func:`estimate_model_bytes`: its
    meshes, factorisations, boundary matrices and landscape curves (not the base, the
    transients — building the solvers, the elastic limit's fields — or what its callers
    hold)."""
    return sum(estimate[k] for k in ("mesh", "factorisation", "boundary", "landscape"))


def _factor_bytes(n_nodes: int) -> float:
    n = max(int(n_nodes), 2)
    return FACTOR_BYTES_PER_NLOGN * n * math.log2(n)


def _averaging_nonzeros(n_triangles: int, area: float, ell: float) -> float:
    """Non-zeros of the critical-distance averaging operator: every element with itself,
    plus the element pairs whose centroids lie within ``ell`` (m) of each other."""
    m = float(n_triangles)
    if area <= 0 or ell <= 0:
        return m
    return m + m * m * math.pi * ell * ell / area


def estimate_model_bytes(model: str, *, n_nodes: int, n_triangles: int, n_boundary: int,
                         n_jaw_nodes: int | None = None, area: float = 0.0, ell: float = 0.0,
                         solvers: int = 1, plan: bool = False, n_axes: int = 0,
                         path_limit: bool = True) -> dict[str, float]:
    """Peak memory (bytes) of an analysis, by part, from the sizes of its mesh.

    Parameters
    ----------
    model : {"paper", "pads"}
    n_nodes, n_triangles : int
        Mesh size.
    n_boundary : int
        Nodes on all boundary loops (the condensation's size ``p``).
    n_jaw_nodes : int, optional
        Paper model: nodes whose pairs are the graph's vertices (outer loop, or every loop
        when expanding). Default ``n_boundary``.
    area : float
        Part area (m²) and ``ell`` the critical distance (m), for the pads model.
    solvers : int
        Pads: number of factorised meshes held at once (2 with the noise-floor twin).
    plan : bool
        Paper model: include the planner's strain responses of every jaw node.
    n_axes : int
        Pads: grasp axes whose contact curves the release landscape keeps.
    path_limit : bool
        Pads: the analysis evaluates the elastic limit along a squeeze path (the fields
        of its breakpoints, the ``level`` term: optimize, plan). ``check`` averages the
        strains of single placements only (the ``averaging`` term).

    Returns
    -------
    dict
        ``{"base", "held", "mesh", "factorisation", "boundary", "landscape", "graph",
        "averaging", "level", "strains", "condensing", "total"}`` (bytes). The total holds
        the base, what enclosing steps hold (:func:`holding`), mesh, factorisation and
        boundary matrices, plus the largest of the transients (graph construction, strain
        responses, building a pads solver, the averages, a pads level's elastic-limit
        fields), which come one after another. The costs per unit are measured with
        ``benchmarks/bench_memory.py`` (every command) and ``benchmarks/bench_limits.py``
        (at the maxima).
    """
    p = int(n_boundary)
    q = int(n_boundary if n_jaw_nodes is None else n_jaw_nodes)
    out = {"base": BASE_BYTES, "held": math.fsum(_HELD), "mesh": MESH_BYTES_PER_TRIANGLE * n_triangles,
           "factorisation": _factor_bytes(n_nodes), "boundary": CONDENSE_BYTES_PER_P2 * p * p,
           "landscape": 0.0, "graph": 0.0, "averaging": 0.0, "level": 0.0, "strains": 0.0,
           "condensing": 0.0}
    if model == "paper":
        out["graph"] = PAPER_GRAPH_BYTES_PER_P2 * q * q
        if plan:
            out["strains"] = STRAIN_BYTES_PER_PM * q * n_triangles + STRAIN_BYTES_PER_PN * q * n_nodes
    elif model == "pads":
        k = max(float(solvers), 1.0)
        out["mesh"] *= k
        out["factorisation"] *= k
        # a twin has fewer nodes, but not always a shorter boundary (a ring's vertices are
        # kept: a 2000-vertex circle's twin has 2000 boundary nodes too): whole solvers here
        out["boundary"] = PADS_SOLVER_BYTES_PER_P2 * math.ceil(k - 1e-9) * p * p
        # the level's solver and its twin's are built side by side (pads.refine.build_solvers)
        out["condensing"] = PADS_WORK_BYTES_PER_P2 * p * p * min(k, 2.0)
        out["landscape"] = PADS_AXIS_BYTES_PER_NODE * int(n_axes) * p
        # rows of the averaging operator in chunks, never the whole operator (SPEC §6)
        out["averaging"] = AVERAGING_CHUNK_BYTES + AVERAGING_BYTES_PER_TRIANGLE * n_triangles
        # the elastic limit's fields, their averages and the noise floor on the finest mesh
        # breakpoints held at once: those the boundary predicts, at most a group's
        group = max(2.0, PADS_LIMIT_CHUNK_BYTES / (16.0 * (4 * n_nodes + 3 * n_triangles)))
        breakpoints = min(PADS_BREAKPOINTS_PER_BOUNDARY_NODE * p, group, PADS_LIMIT_GROUP)
        pool = min(DISC_ROW_POOL_BYTES, DISC_ROW_POOL_BYTES_PER_TRIANGLE2 * n_triangles ** 2)
        out["level"] = 0.0 if not path_limit else AVERAGING_CHUNK_BYTES + pool + (
            PADS_LEVEL_BYTES_PER_TRIANGLE
            + PADS_LIMIT_BYTES_PER_BREAKPOINT_TRIANGLE * breakpoints) * n_triangles
    else:
        choose(model, MODELS, "model", GraspError)
    # The contact graph is built, the strain responses and the averaging operator are used,
    # one after another: the largest of these transients adds to what stays.
    transient = max(out["graph"], out["strains"], out["condensing"], out["averaging"],
                    out["level"])
    out["total"] = (out["base"] + out["held"] + out["mesh"] + out["factorisation"]
                    + out["boundary"] + out["landscape"] + transient)
    return out


def check_plan_size(n_boundary: int, model: str, *, n_nodes: int = 0, n_triangles: int = 0,
                    n_jaw_nodes: int | None = None, area: float = 0.0, ell: float = 0.0,
                    solvers: int = 1, plan: bool = True, n_axes: int = 0,
                    path_limit: bool = True, what: str | None = None) -> dict[str, float]:
    """Refuse an analysis whose boundary or estimated memory exceeds the limits.

    Parameters
    ----------
    n_boundary : int
        Boundary nodes of the mesh (all loops).
    model : {"paper", "pads"}
    n_nodes, n_triangles, n_jaw_nodes, area, ell, solvers, plan, n_axes, path_limit
        See :func:`estimate_model_bytes`.
    what : str, optional
        What the messages start with (default ``--model <model>``).

    Returns
    -------
    dict
        The estimate (bytes), see :func:`estimate_model_bytes`.

    Raises
    ------
    GraspError
        Above :data:`MAX_BOUNDARY_NODES_PAPER` / :data:`MAX_BOUNDARY_NODES_PADS` boundary
        nodes, :data:`MAX_AVERAGING_NONZEROS`, or an estimate above :data:`MEMORY_BUDGET`.
    """
    q = int(n_boundary if n_jaw_nodes is None else n_jaw_nodes)
    what = what or f"--model {model}"
    if model == "paper" and q > MAX_BOUNDARY_NODES_PAPER:
        raise GraspError(f"{what}: the mesh has {q:,} jaw nodes on its boundary, more than "
                         f"the limit {MAX_BOUNDARY_NODES_PAPER:,} (the contact graph of all "
                         f"{format_count(q * (q - 1) / 2)} node pairs would need about "
                         f"{PAPER_GRAPH_BYTES_PER_P2 * q * q / GB:.1f} GB); coarsen the boundary "
                         "(larger max_area, fewer ring vertices) or use the pads model")
    top = MAX_BOUNDARY_NODES_PADS
    if model == "pads" and n_boundary > top:
        dense = PADS_SOLVER_BYTES_PER_P2 * max(solvers, 1) * n_boundary**2
        raise GraspError(f"{what}: the mesh has {n_boundary:,} boundary nodes, more than the "
                         f"limit {top:,} (dense boundary compliances of {dense / GB:.1f} GB); "
                         "coarsen the boundary (larger max_area, fewer ring vertices)")
    if model == "pads":
        nnz = _averaging_nonzeros(n_triangles, area, ell)
        if nnz > MAX_AVERAGING_NONZEROS:
            raise GraspError(f"{what}: averaging strains over the critical distance "
                             f"({ell:.3g} m) on {n_triangles:,} triangles needs "
                             f"{format_count(nnz)} element pairs (limit "
                             f"{format_count(MAX_AVERAGING_NONZEROS)}, the work of one "
                             "evaluation); coarsen the mesh "
                             "(larger max_area) or give a smaller "
                             "material.critical_distance")
    est = estimate_model_bytes(model, n_nodes=n_nodes, n_triangles=n_triangles,
                               n_boundary=n_boundary, n_jaw_nodes=n_jaw_nodes, area=area, ell=ell,
                               solvers=solvers, plan=plan, n_axes=n_axes,
                               path_limit=path_limit)
    if est["total"] > MEMORY_BUDGET:
        part, size = max(((k, v) for k, v in est.items() if k not in ("total", "base", "held")),
                         key=lambda kv: kv[1])
        hint = {"strains": "restrict the pairs (--region, --min-sep/--max-sep) or coarsen the mesh",
                "graph": "coarsen the boundary",
                "landscape": "use a coarser grid (--grid-angles, --grid-offsets) or coarsen the "
                             "boundary"}.get(part, "coarsen the mesh (larger max_area)")
        raise GraspError(f"{what}: this analysis of a {n_nodes:,}-node mesh would need "
                         f"about {est['total'] / GB:.1f} GB ({part}: {size / GB:.1f} GB), more "
                         f"than {MEMORY_BUDGET / GB:.0f} GB; {hint}")
    return est


def check_strain_responses(n_jaw_nodes: int, n_nodes: int, n_triangles: int,
                           max_bytes: float | None = None) -> None:
    """Refuse the paper planner's strain responses of ``n_jaw_nodes`` perimeter nodes when
    they would not fit in what :data:`MEMORY_BUDGET` leaves after the model (or in
    ``max_bytes``, if smaller).

    Raises
    ------
    GraspError
    """
    need = STRAIN_BYTES_PER_PM * n_jaw_nodes * n_triangles + STRAIN_BYTES_PER_PN * n_jaw_nodes * n_nodes
    room = MEMORY_BUDGET - BASE_BYTES - _factor_bytes(n_nodes) - MESH_BYTES_PER_TRIANGLE * n_triangles
    if max_bytes is not None:
        room = min(room, float(max_bytes))
    if need > room:
        raise GraspError(f"planning all pairs of this part needs {need / GB:.1f} GB for the strain "
                         f"responses of {n_jaw_nodes:,} perimeter nodes ({max(room, 0) / GB:.1f} GB "
                         "left); restrict the pairs (--region, --min-sep/--max-sep) or coarsen the "
                         "mesh")


def check_slice_size(resolution: int, n_fingers: int = 0, json_output: bool = False,
                     field: str = "--resolution") -> None:
    """Refuse a slice above :data:`MAX_SLICE_RESOLUTION` pixels per axis, or whose images
    (and JSON text) would not fit in :data:`MEMORY_BUDGET`.

    Raises
    ------
    DeformClosureError
    """
    if not (isinstance(resolution, Integral) and 2 <= resolution <= MAX_SLICE_RESOLUTION):
        raise DeformClosureError(f"{field} {resolution}: use 2..{MAX_SLICE_RESOLUTION:,} pixels "
                                 "per axis")
    px = float(resolution) ** 2
    images = 2 + int(n_fingers)
    need = BASE_BYTES + px * (8 + images)
    if json_output:
        need += px * (1 + images) * SLICE_JSON_BYTES_PER_VALUE
    if need > MEMORY_BUDGET:
        per = (8 + images) + ((1 + images) * SLICE_JSON_BYTES_PER_VALUE if json_output else 0)
        top = int(math.sqrt((MEMORY_BUDGET - BASE_BYTES) / per))
        raise DeformClosureError(f"{field} {resolution}: {resolution}² pixels with {n_fingers} "
                                 f"fingers need about {need / GB:.1f} GB"
                                 f"{' as JSON' if json_output else ''}; use {field} <= {top}"
                                 f"{' or write .npz' if json_output else ''}")


def limits_help(command: str) -> str:
    """The limits paragraph of a command's ``--help`` (click ``\\b`` block)."""
    mesh = (f"meshes: at most {MAX_TRIANGLES:,} triangles (estimated before meshing), narrow "
            f"features at most {MAX_THIN_ELEMENTS:,} boundary elements, holes at least "
            f"{MIN_GAP_FRACTION:g} x the diameter from other rings, at most {MAX_MESH_POINTS:,} "
            "inserted points")
    paper = (f"--model paper: at most {MAX_BOUNDARY_NODES_PAPER:,} jaw nodes on the boundary "
             "(outer loop; every loop with --expanding)")
    pads = (f"pads: at most {MAX_BOUNDARY_NODES_PADS:,} boundary nodes, "
            f"{MAX_AVERAGING_NONZEROS / 1e6:.0f} million critical-distance element pairs, and a "
            "memory estimate (mesh, grid, twin) within the budget")
    lines = {
        "mesh": [mesh],
        "plan": [mesh, paper, pads],
        "optimize": [mesh, paper, pads + "; with --refine N, for the finest mesh"],
        "check": [mesh, f"at most {MAX_BOUNDARY_NODES_PADS:,} boundary nodes, "
                  f"{MAX_AVERAGING_NONZEROS / 1e6:.0f} million critical-distance element pairs, "
                  "and a memory estimate within the budget"],
        "slice": [mesh, f"--resolution at most {MAX_SLICE_RESOLUTION:,} (less with many fingers "
                  "and -o .json)"],
    }[command]
    import textwrap

    body = "\n".join(textwrap.fill(ln, 86, initial_indent="  - ", subsequent_indent="    ")
                     for ln in lines)
    return (f"\b\nLimits (every maximum runs within {MEMORY_BUDGET / GB:.0f} GB; larger requests "
            f"are refused before the work):\n{body}\n")
