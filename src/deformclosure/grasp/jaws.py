"""Jaw contact patches: the boundary nodes a jaw of finite width moves together.

A point jaw touches one perimeter node. A jaw of contact width ``w`` is a flat,
frictionless, non-rotating face perpendicular to the jaw line; it touches every node of
the same boundary loop within arclength ``w/2`` of the jaw node, and all of them share
the jaw's displacement *along the jaw line* (they slide freely across it). See
docs/two_jaw.md, "Contact model".
"""

from __future__ import annotations

import numpy as np

from ..errors import GraspError

__all__ = ["jaw_patches", "loop_arclength"]


def loop_arclength(nodes: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Arclength (m) of each loop node from the loop's first node, shape ``(len(loop),)``."""
    seg = np.linalg.norm(np.diff(nodes[np.append(loop, loop[0])], axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(seg[:-1])])


def jaw_patches(nodes: np.ndarray, loops: tuple[np.ndarray, ...], centers: np.ndarray,
                width: float) -> list[np.ndarray]:
    """Node ids touched by a jaw of contact ``width`` (m) centred at each node of ``centers``.

    Parameters
    ----------
    nodes : ndarray, shape (n, 2)
    loops : tuple of ndarray
        Boundary loops of the mesh.
    centers : ndarray of int
        Jaw nodes (perimeter node ids).
    width : float
        Contact width (m), ≥ 0; 0 gives point jaws.

    Returns
    -------
    list of ndarray
        For each center, the node ids within arclength ``width/2`` along its loop
        (the center first).

    Raises
    ------
    GraspError
        Negative or non-finite width, or a center not on any loop.
    """
    if not np.isfinite(width) or width < 0:
        raise GraspError(f"jaw width = {width!r}: must be a finite length >= 0 (0 = point jaws)")
    centers = np.asarray(centers, dtype=np.int64)
    if width == 0:
        return [np.array([c]) for c in centers]
    out: list[np.ndarray | None] = [None] * len(centers)
    for lp in loops:
        s = loop_arclength(nodes, lp)
        total = s[-1] + np.linalg.norm(nodes[lp[0]] - nodes[lp[-1]])
        pos = np.full(len(nodes), -1, dtype=np.int64)
        pos[lp] = np.arange(len(lp))
        which = np.flatnonzero(pos[centers] >= 0)
        if not len(which):
            continue
        sc = s[pos[centers[which]]]
        # Periodic arclength distance from each center to each loop node: (k, len(lp)).
        d = np.abs(s[None, :] - sc[:, None])
        d = np.minimum(d, total - d)
        inside = d <= 0.5 * width * (1 + 1e-12)
        for i, row in zip(which, inside):
            ids = lp[row]
            c = centers[i]
            out[i] = np.concatenate([[c], ids[ids != c]])
    missing = [int(c) for c, o in zip(centers, out) if o is None]
    if missing:
        raise GraspError(f"jaw node {missing[0]} is not on the part's boundary; choose a perimeter node")
    return out  # type: ignore[return-value]
