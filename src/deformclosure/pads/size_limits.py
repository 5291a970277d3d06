"""Resource limits of the pads model on a mesh (SPEC §6): ``optimize``, ``plan`` and
``check``.

The constants and the cost model are the foundation's (:mod:`deformclosure.limits`);
this module reads what the pads model needs from a mesh — its boundary, its area and the
material's critical distance
(:func:`~deformclosure.elasticity.critical_distance.critical_distance_of`) — and asks
:func:`~deformclosure.limits.check_plan_size` before the heavy work.
"""

from __future__ import annotations

import math
from numbers import Integral

from ..elasticity.critical_distance import critical_distance_of
from ..errors import GraspError
from ..mesh.generate import TWIN_AREA
from ..limits import (MAX_TRIANGLES, PADS_SEARCH_AXES_FRACTION, PADS_SEARCH_PATCH_FRACTION,
                      check_plan_size, format_count)

__all__ = ["check_pads_size", "estimate_pads_bytes", "level_axes", "search_axes",
           "WITH_TWIN"]

#: Solvers held by an analysis with its noise-floor twin, for :func:`check_pads_size`:
#: the twin's mesh has ``1 / TWIN_AREA`` of the nodes (its triangles are larger), so the
#: pair costs ``1 + 1 / TWIN_AREA`` solvers of the main mesh.
WITH_TWIN = 1.0 + 1.0 / TWIN_AREA


def search_axes(n_angles: int, n_offsets: int) -> int:
    """Grasp axes whose curves one ``optimize`` level keeps, for its memory estimate: the
    measured share :data:`~deformclosure.limits.PADS_SEARCH_AXES_FRACTION` of its grid
    (the release search stops at the escape; a plan solves the whole grid)."""
    return math.ceil(PADS_SEARCH_AXES_FRACTION * int(n_angles) * int(n_offsets))


def level_axes(n_angles: int, n_offsets: int, k: int = 0, n_saddles: int = 0) -> int:
    """Grasp axes whose curves level ``k + 1`` of an ``optimize`` run solves, for its memory
    estimate: :func:`search_axes` of the coarse grid and, from the second level on, the
    measured share :data:`~deformclosure.limits.PADS_SEARCH_PATCH_FRACTION` of the fine
    vertices of its saddle patches (``(2f + 1)²`` each, ``f = 2^k``): one around each of
    the ``n_saddles`` known saddles and one around the saddle a re-solve may add
    (:func:`deformclosure.pads.refine.solve_level`)."""
    patches = 0 if k <= 0 else (int(n_saddles) + 1) * (2 * 2 ** int(k) + 1) ** 2
    return search_axes(n_angles, n_offsets) + math.ceil(PADS_SEARCH_PATCH_FRACTION * patches)


def check_pads_size(mesh, *, solvers: float = 1, refine: int = 1, n_axes: int = 0,
                    path_limit: bool = True, what: str | None = None) -> dict[str, float]:
    """Refuse a pads analysis of ``mesh`` that exceeds the limits.

    Parameters
    ----------
    mesh : Mesh
        Its boundary ``loops``, ``n_nodes``, ``n_triangles``, element ``areas`` (m²),
        ``diameter`` and ``material`` are read.
    solvers : float
        Factorised meshes held at once, in solvers of ``mesh`` (:data:`WITH_TWIN` with the
        noise-floor twin, also for ``check``: its rigid test's solver is released before
        the landscape's and the twin's are made).
    refine : int
        ``--refine N`` (1..5): the finest of N meshes has about 4^(N−1) times the
        triangles and 2^(N−1) times the boundary nodes.
    n_axes : int
        Grasp axes of the release landscape (a plan's grid; an optimize evaluates part
        of its grid).
    path_limit : bool
        The elastic limit is evaluated along squeeze paths (optimize, plan); ``check``
        averages single placements' strains only. See
        :func:`deformclosure.limits.estimate_model_bytes`.
    what : str, optional
        What the messages start with (default ``--model pads``).

    Returns
    -------
    dict
        The memory estimate (bytes), see :func:`deformclosure.limits.estimate_model_bytes`.

    Raises
    ------
    GraspError
        Above :data:`~deformclosure.limits.MAX_BOUNDARY_NODES_PADS` boundary nodes,
        :data:`~deformclosure.limits.MAX_AVERAGING_NONZEROS`, the memory budget, or (with
        ``refine``) :data:`~deformclosure.limits.MAX_TRIANGLES` on the finest mesh.
    """
    levels = int(refine) if isinstance(refine, Integral) and 1 <= refine <= 5 else 1
    if levels > 1 and mesh.n_triangles * 4 ** (levels - 1) > MAX_TRIANGLES:
        raise GraspError(f"--refine {levels}: the finest mesh would have about "
                         f"{format_count(mesh.n_triangles * 4 ** (levels - 1))} triangles "
                         f"(limit {MAX_TRIANGLES:,}); use fewer meshes or a larger "
                         "mesh.max_area")
    sizes = _sizes(mesh, solvers, levels)
    return check_plan_size(sizes.pop("n_boundary"), "pads", **sizes, plan=False,
                           n_axes=n_axes, path_limit=path_limit, what=what)


def estimate_pads_bytes(mesh, *, solvers: float = 1, refine: int = 1, n_axes: int = 0,
                        path_limit: bool = True) -> dict[str, float]:
    """The estimate of :func:`check_pads_size` without its checks (bytes), e.g. of what a
    finished step keeps (:func:`deformclosure.limits.kept_bytes`) with fewer solvers
    than it held while it ran."""
    from ..limits import estimate_model_bytes

    return estimate_model_bytes("pads", **_sizes(mesh, solvers, max(int(refine), 1)),
                                n_axes=n_axes, path_limit=path_limit)


def _sizes(mesh, solvers: float, levels: int) -> dict:
    """The sizes :func:`deformclosure.limits.estimate_model_bytes` reads, of the finest of
    ``levels`` meshes starting at ``mesh``."""
    f, g = 4 ** (levels - 1), 2 ** (levels - 1)
    # --refine keeps every level's solvers: about 4/3 of the finest mesh's
    k = solvers * (4.0 / 3.0 if levels > 1 else 1.0)
    return {"n_boundary": sum(len(lp) for lp in mesh.loops) * g, "n_nodes": mesh.n_nodes * f,
            "n_triangles": mesh.n_triangles * f, "area": float(mesh.areas.sum()),
            "ell": critical_distance_of(mesh), "solvers": k}
