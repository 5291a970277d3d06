"""Where fingers start: how deep each finger reaches into the part at rest.

SPEC §5: fingers are placed against the part at rest, touching it or slightly overlapping
it (a pre-squeeze). A finger placed *inside* the part — a point finger in the middle of
it, a disc swallowed by it, a jaw reaching across it — describes no physical grasp: the
small-displacement equilibrium then returns numbers that mean nothing (a part impaled on a
point, a disc cut out of the material). :func:`check_finger_placement` refuses those with
a message that says which finger and by how much.

The depth of a finger is how far it reaches into the part: the largest distance from the
part's rest boundary of a point of the finger inside the part (sampled on the finger's
corners, centre and outline), or of a boundary node inside the finger. It is compared with
the radius of the largest circle inscribed in the part, the part's own "half-thickness".
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from ..errors import DeformClosureError
from .fingers import Finger

__all__ = ["FingerPlacementError", "finger_depths", "check_finger_placement", "MAX_DEPTH_RATIO"]

#: Largest accepted depth of a finger, as a fraction of the part's inscribed radius.
MAX_DEPTH_RATIO = 0.5


class FingerPlacementError(DeformClosureError):
    """A finger starts (deep) inside the part instead of against it."""


def _part_polygon(mesh: Any):
    import shapely

    rings = [mesh.nodes[np.asarray(loop)] for loop in mesh.loops]
    return shapely.Polygon(rings[0], rings[1:])


def finger_depths(mesh: Any, fingers: Sequence[Finger]) -> np.ndarray:
    """How far each finger reaches into the part at rest (m; 0 when it only touches).

    Parameters
    ----------
    mesh : Mesh
        The part at rest (metres).
    fingers : sequence of Finger

    Returns
    -------
    ndarray, shape (n_fingers,)
        Largest distance from the rest boundary of a finger point inside the part, or of
        a perimeter node inside the finger (sampled; m).
    """
    import shapely

    poly = _part_polygon(mesh)
    boundary = poly.boundary
    nodes = mesh.nodes[np.unique(np.concatenate([np.asarray(loop) for loop in mesh.loops]))]
    out = np.zeros(len(fingers))
    for i, f in enumerate(fingers):  # a handful of fingers; each query is vectorised
        depth = 0.0
        pts = f.depth_samples()
        if len(pts):
            g = shapely.points(pts)
            inside = shapely.contains_xy(poly, pts[:, 0], pts[:, 1])
            if inside.any():
                depth = float(shapely.distance(g[inside], boundary).max())
        if f.has_interior:
            sd = f.signed_distance(nodes)
            depth = max(depth, float(-sd.min(initial=0.0)))
        out[i] = depth
    return out


def check_finger_placement(mesh: Any, fingers: Sequence[Finger],
                           max_depth_ratio: float = MAX_DEPTH_RATIO) -> np.ndarray:
    """Refuse fingers that start deep inside the part; return the depths (m).

    Raises
    ------
    FingerPlacementError
        A finger reaches deeper into the part than ``max_depth_ratio`` × the radius of
        the part's largest inscribed circle.
    """
    import shapely

    depths = finger_depths(mesh, fingers)
    radius = float(shapely.maximum_inscribed_circle(_part_polygon(mesh)).length)
    limit = max_depth_ratio * radius
    bad = np.flatnonzero(depths > limit)
    if len(bad):
        i = int(bad[0])
        raise FingerPlacementError(
            f"fingers[{i}] ({fingers[i].type}) reaches {depths[i]:.3g} m into the part at rest, "
            f"{depths[i] / radius:.0%} of its largest inscribed radius ({radius:.3g} m); place "
            f"fingers against the part, touching it or overlapping it by less than "
            f"{max_depth_ratio:.0%} of that radius")
    return depths
