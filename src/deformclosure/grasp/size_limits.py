"""Resource limits of the paper's two-jaw model on a mesh (SPEC §4).

The constants and the cost model are the foundation's (:mod:`deformclosure.limits`);
this module reads what the paper model needs from a mesh — its jaw nodes — and asks
:func:`~deformclosure.limits.check_plan_size` before the heavy work.
"""

from __future__ import annotations

from ..limits import check_plan_size

__all__ = ["check_paper_size"]


def check_paper_size(mesh, *, mode: str = "contracting", plan: bool = False,
                     restricted: bool = False, what: str | None = None) -> dict[str, float]:
    """Refuse a paper-model analysis of ``mesh`` that exceeds the limits.

    Parameters
    ----------
    mesh : Mesh
        Only its boundary ``loops``, ``n_nodes`` and ``n_triangles`` are read.
    mode : {"contracting", "expanding"}
        Expanding grasps pair the nodes of every loop, contracting ones those of the
        outer loop.
    plan : bool
        The planner (strain responses of every jaw node).
    restricted : bool
        Planner restricted to some pairs (regions, separation range): the strain
        responses are then checked by the planner itself once the pairs are known.
    what : str, optional
        What the messages start with (default ``--model paper``).

    Returns
    -------
    dict
        The memory estimate (bytes), see :func:`deformclosure.limits.estimate_model_bytes`.

    Raises
    ------
    GraspError
        Above :data:`~deformclosure.limits.MAX_BOUNDARY_NODES_PAPER` jaw nodes or the
        memory budget.
    """
    loops = list(mesh.loops)
    n_b = sum(len(lp) for lp in loops)
    jaw = len(loops[0]) if mode == "contracting" else n_b
    return check_plan_size(n_b, "paper", n_nodes=mesh.n_nodes, n_triangles=mesh.n_triangles,
                           n_jaw_nodes=jaw, plan=plan and not restricted, what=what)
