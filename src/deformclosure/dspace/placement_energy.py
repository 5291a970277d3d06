"""Contact energy of a part placed rigidly among fixed fingers (SPEC §7, kernel).

For fixed fingers the state of a frictionless part is its *placement* ``g = (x, y, φ)``:
the part at rest, turned by ``φ`` (rad) about its area centroid ``c`` and then moved by
``(x, y)`` (m), so a material point ``p`` goes to ``R(φ)(p − c) + c + (x, y)``. Every
placement has the contact energy of §6 with the fingers as rigid bodies::

    E(g) = min ½ uᵀ K u   subject to  g_r(g) + C_r u ≥ 0  for every contact row r,

where the deformation ``u`` has no rigid part (area-weighted, the placement *is* the rigid
motion: the gauge of SPEC §7, :meth:`deformclosure.contact.compliance.BoundaryCompliance.placement_gauge`,
the same functionals as the pads' axis gauge), whose boundary compliance ``Y = Pᵀ Z P``
(one factorisation) is reused. In the dual, with the Delassus
matrix ``W = C Y Cᵀ``::

    E(g) = max_{λ ≥ 0} −(g₀ᵀ λ + ½ λᵀ W λ) = ½ λᵀ W λ    at the solution,

a small linear complementarity problem solved per placement by block principal pivoting
(Júdice & Pires; the compiled kernel of :mod:`deformclosure.contact.lcp`, called from
this module's compiled placement solve) and warm-started from a neighbour's active set.

Contact rows are built in the part frame, at rest (small-displacement theory), from the
fingers moved by ``g⁻¹``:

* boundary node against a finger body (convex polygon, half-plane): the node's signed
  distance to the body, force along the body's outward normal there;
* boundary node against a disc: a disc presses like a round pad of SPEC §6 along its
  *axis* (:func:`disc_axes`, fixed to the finger). For a node not behind the disc (axial
  coordinate from the centre ``s ≥ −ρ``) within the pad's contact reach (75° from the
  axis, ``|x| < ρ sin 75°``) the gap is its distance *along the axis* to the disc's
  surface at its own cross coordinate ``x``, the force along the disc's normal there —
  so discs at the pads' places give the pads' energies, also when pressed past their
  centre; beyond the reach (the steep flanks and the sides, ``|x| ≥ ρ sin 75°``) contact
  is not enforced, exactly as for pads (a node can slip past a disc's side only through a
  sliver 3.4 % of ρ wide). Behind the disc (``s < −ρ``) the radial distance — except in
  material the disc is pressed into by more than its diameter (the node's boundary does
  not face the disc's back — inward normal within 45° of minus the axis, the far wall of
  a hole the disc sits in — and the disc's back at the node's cross coordinate, at most
  the reach, lies inside the part at rest), where the pad's rule holds: the gap along the
  axis within the reach (a pad pressed that deep still pushes it, SPEC §6) and no contact
  beyond it;
* finger corner (point finger, polygon corner) against a boundary edge whose foot point
  lies on the edge: the corner's distance to the edge line, force along the edge's inward
  normal, shared by the edge's end nodes (``1 − s``, ``s``); a corner outside the part in
  the normal cone of a convex vertex gives a row to that vertex; a corner inside the part
  presses only on its nearest edge (or vertex), so thin walls are safe;
* a disc with no boundary node inside it, against a boundary edge whose foot point it
  faces and whose end nodes are outside it: its centre's distance to the edge line minus
  ``r`` (between two nodes a straight edge may cut the disc while both stay outside it,
  on a mesh coarse for the disc; once a node is inside, the node rows of SPEC §6 alone
  see the disc);
* a disc whose centre lies inside the part with no boundary node inside the disc presses
  on one edge like a corner with an offset ``r`` (otherwise a small disc could pass
  through the material with no node inside it); once a node is inside, the node rows
  alone see the disc, as for a round pad pressed past its centre.

A disc is thus exactly a round pad of SPEC §6 on its axis: two discs at the pads' places
give, minimised over the part's float along the axis, the pads' energy of that axis.

Gaps within the touching tolerance (``1e-9`` × the diameter, SPEC §3) count as free.
Candidate rows are those with a rest gap below twice the deepest penetration; every row
with a gap up to four times it is checked against the solution's displacement and added
if the solution makes it penetrate (then solved again).

Placements where a finger other than a disc reaches deeper into the part than
``max_depth_ratio`` (50 %) of the part's largest inscribed radius are *inadmissible*
(energy ``inf``; a disc, like a pad, has no depth limit — the gap along its axis already
resists any depth): the rule
:func:`deformclosure.dspace.placement.check_finger_placement` applies at rest, outside the
small-displacement model. So are placements whose energy exceeds that of a unit strain
throughout the part (``½ E t A``): contradictory contact rows (a finger cutting through
a thin part) make the contact problem infeasible.

The energy is exactly invariant under a rigid motion of part and fingers together
(everything is computed in the part frame).

References
----------
J. J. Júdice and F. M. Pires, "A block principal pivoting algorithm for large-scale
strictly monotone linear complementarity problems", Computers & Operations Research
21(5), 1994.
P. Wriggers, *Computational Contact Mechanics*, 2nd ed., Springer 2006.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from numba import njit

# numba's cache of this module's kernels (cache=True) keys on this file alone: after an edit
# of contact/lcp.py, delete this package's __pycache__/*.nbi, *.nbc or the kernels keep the
# old bpp_kernel (numba's documented limit on functions from other files)
from ..contact.lcp import bpp_kernel
from ..limits import blas_threads
from ..contact.bodies import KERNEL_DISC, KERNEL_HALFPLANE, KERNEL_POINT, KERNEL_POLYGON, Finger
from .obstacles import BoundaryModel, resolve_tolerance
from .placement import MAX_DEPTH_RATIO

__all__ = ["PlacementEnergy", "PlacementState", "inscribed_radius", "disc_axes"]

# finger codes (:meth:`Finger.kernel_encoding`)
_POINT, _DISC, _POLYGON, _HALFPLANE = KERNEL_POINT, KERNEL_DISC, KERNEL_POLYGON, KERNEL_HALFPLANE
# row kinds
_NODE_BODY, _CORNER_EDGE, _CORNER_NODE, _CENTRE_EDGE, _DISC_EDGE = 0, 1, 2, 3, 4
# a boundary faces a disc's back when its inward normal is within 45° of minus the axis
_HALF_SQRT2 = 0.7071067811865476


def inscribed_radius(mesh: Any) -> float:
    """Radius (m) of the largest circle inscribed in the part at rest."""
    import shapely

    rings = [mesh.nodes[np.asarray(loop)] for loop in mesh.loops]
    return float(shapely.maximum_inscribed_circle(shapely.Polygon(rings[0], rings[1:])).length)


# ----------------------------------------------------------------------------- geometry


@njit(cache=True, nogil=True)
def _place_fingers(g, c, ftype, fpar, verts, vnorm):  # pragma: no cover - compiled
    """Fingers in the part frame for placement ``g``: params, vertices, normals, offsets."""
    cph, sph = np.cos(g[2]), np.sin(g[2])
    F = ftype.shape[0]
    par = fpar.copy()
    V = verts.shape[0]
    pv = np.empty((V, 2))
    pn = np.empty((V, 2))
    po = np.empty(V)
    for f in range(F):
        t = ftype[f]
        # a point w of the world goes to Rᵀ (w − c − t) + c
        x, y = fpar[f, 0] - c[0] - g[0], fpar[f, 1] - c[1] - g[1]
        par[f, 0] = cph * x + sph * y + c[0]
        par[f, 1] = -sph * x + cph * y + c[1]
        if t == _HALFPLANE:
            nx, ny = fpar[f, 2], fpar[f, 3]
            par[f, 2] = cph * nx + sph * ny
            par[f, 3] = -sph * nx + cph * ny
        elif t == _DISC:
            nx, ny = fpar[f, 3], fpar[f, 4]
            par[f, 3] = cph * nx + sph * ny
            par[f, 4] = -sph * nx + cph * ny
    for k in range(V):
        x, y = verts[k, 0] - c[0] - g[0], verts[k, 1] - c[1] - g[1]
        pv[k, 0] = cph * x + sph * y + c[0]
        pv[k, 1] = -sph * x + cph * y + c[1]
        nx, ny = vnorm[k, 0], vnorm[k, 1]
        pn[k, 0] = cph * nx + sph * ny
        pn[k, 1] = -sph * nx + cph * ny
        po[k] = pn[k, 0] * pv[k, 0] + pn[k, 1] * pv[k, 1]
    return par, pv, pn, po


# disc sides of a boundary point (:func:`_disc_side`)
_FRONT, _BACK_WALL, _BEHIND = 0, 1, 2


@njit(cache=True, nogil=True)
def _disc_side(cx, cy, r, ax, ay, reach, px, py, nx, ny):  # pragma: no cover - compiled
    """Which rule a boundary point ``(px, py)`` with inward normal ``(nx, ny)``
    (unnormalised) follows against the disc ``(cx, cy, r)`` pressing along ``(ax, ay)``
    with contact reach ``reach``: ``_FRONT`` — not behind the disc (``s ≥ −r`` along its
    axis): the pad's gap along the axis; ``_BACK_WALL`` — behind it, on a boundary facing
    its back (inward normal within 45° of minus the axis: the far wall of a hole): the
    radial distance; ``_BEHIND`` — behind it elsewhere: the pad's rule when the disc's
    back at the point's cross coordinate (clipped to the reach) is buried in the part
    (:func:`_buried`), else the radial distance. Returns ``(side, clipped cross
    coordinate)``. Scalars only, so the scans' per-node loop passes no arrays."""
    dx, dy = px - cx, py - cy
    if dx * ax + dy * ay >= -r:
        return _FRONT, 0.0
    if nx * ax + ny * ay > -_HALF_SQRT2 * np.hypot(nx, ny):
        x = -dx * ay + dy * ax
        return _BEHIND, min(max(x, -reach), reach)
    return _BACK_WALL, 0.0


@njit(cache=True, nogil=True)
def _disc_sd(cx, cy, r, ax, ay, reach, px, py, axial):  # pragma: no cover - compiled
    """Signed distance and outward unit normal of the disc of :func:`_disc_side` at
    ``(px, py)``: with ``axial`` the gap along the disc's axis to its surface at the
    point's cross coordinate (SPEC §6), scaled to a unit gradient (the disc's normal at
    that surface point), and not enforced (``inf``) beyond the reach — the pad's steep
    flanks (beyond 75° from the axis) and its sides; otherwise the radial distance."""
    dx, dy = px - cx, py - cy
    if axial:
        s = dx * ax + dy * ay
        x = -dx * ay + dy * ax
        if abs(x) >= reach:
            return np.inf, ax, ay
        root = np.sqrt(r * r - x * x)
        return (s - root) * root / r, (ax * root - ay * x) / r, (ay * root + ax * x) / r
    d = np.sqrt(dx * dx + dy * dy)
    if d > 0:
        return d - r, dx / d, dy / d
    return -r, 1.0, 0.0


@njit(cache=True, nogil=True)
def _disc_point_sd(par, px, py, nx, ny, xb, ea, eb, box):  # pragma: no cover - compiled
    """Signed distance and outward unit normal of the disc finger ``par`` (``(cx, cy, r,
    ax, ay, reach)``) at the boundary point ``(px, py)`` with inward normal ``(nx, ny)``
    (unnormalised): the disc rule of SPEC §6/§7 (:func:`_disc_side`, :func:`_buried`,
    :func:`_disc_sd`); ``box`` is the part's bounding box (:func:`_bbox`)."""
    cx, cy, r, ax, ay, reach = par[0], par[1], par[2], par[3], par[4], par[5]
    side, xc = _disc_side(cx, cy, r, ax, ay, reach, px, py, nx, ny)
    axial = side == _FRONT or (side == _BEHIND and _buried(cx, cy, ax, ay, xc, r, xb, ea, eb, box))
    return _disc_sd(cx, cy, r, ax, ay, reach, px, py, axial)


@njit(cache=True, nogil=True)
def _solid_sd(t, par, vs, ve, pv, pn, po, px, py):  # pragma: no cover - compiled
    """Signed distance and outward unit normal of a half-plane or convex polygon finger at
    ``(px, py)``."""
    if t == _HALFPLANE:
        return (px - par[0]) * par[2] + (py - par[1]) * par[3], par[2], par[3]
    # convex polygon
    depth = -np.inf
    jd = vs
    for j in range(vs, ve):
        lev = pn[j, 0] * px + pn[j, 1] * py - po[j]
        if lev > depth:
            depth, jd = lev, j
    if depth <= 0:
        return depth, pn[jd, 0], pn[jd, 1]
    best, bx, by = np.inf, 0.0, 0.0
    for j in range(vs, ve):
        k = j + 1 if j + 1 < ve else vs
        ax, ay = pv[j, 0], pv[j, 1]
        ex, ey = pv[k, 0] - ax, pv[k, 1] - ay
        s = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
        s = min(max(s, 0.0), 1.0)
        fx, fy = ax + s * ex, ay + s * ey
        d = np.hypot(px - fx, py - fy)
        if d < best:
            best, bx, by = d, fx, fy
    if best > 0:
        return best, (px - bx) / best, (py - by) / best
    return 0.0, pn[jd, 0], pn[jd, 1]


@njit(cache=True, nogil=True)
def _body_sd(t, par, vs, ve, pv, pn, po, px, py, nx, ny, part):  # pragma: no cover - compiled
    """Signed distance and outward unit normal of a finger body at boundary point (px, py),
    where the part's inward normal is (nx, ny) (unnormalised): :func:`_disc_point_sd` for
    a disc, :func:`_solid_sd` otherwise. (The scans call the two directly.)"""
    if t == _DISC:
        return _disc_point_sd(par, px, py, nx, ny, part[0], part[1], part[2], _bbox(part[0]))
    return _solid_sd(t, par, vs, ve, pv, pn, po, px, py)


@njit(cache=True, nogil=True)
def _bbox(xb):  # pragma: no cover - compiled
    """Bounding box ``(xmin, xmax, ymin, ymax)`` of the boundary nodes, widened by 1e-6 of
    its half-perimeter: a point outside it is outside the part, also for the even-odd test
    of :func:`_inside` in floating point (whose crossing abscissae stray from their edges
    by round-off only)."""
    x0, x1, y0, y1 = np.inf, -np.inf, np.inf, -np.inf
    for i in range(xb.shape[0]):
        x0, x1 = min(x0, xb[i, 0]), max(x1, xb[i, 0])
        y0, y1 = min(y0, xb[i, 1]), max(y1, xb[i, 1])
    m = 1e-6 * ((x1 - x0) + (y1 - y0)) if xb.shape[0] > 0 else 0.0
    return x0 - m, x1 + m, y0 - m, y1 + m


@njit(cache=True, nogil=True)
def _buried(cx, cy, ax, ay, x, r, xb, ea, eb, box):  # pragma: no cover - compiled
    """Whether the back of the disc (centre ``(cx, cy)``, radius ``r``, axis ``(ax, ay)``)
    at cross coordinate ``x`` (``|x| < r``) lies inside the part at rest (``box``: its
    bounding box, :func:`_bbox`, which decides most points without walking the boundary)."""
    px, py = _disc_back(cx, cy, ax, ay, x, r)
    return _in_box(px, py, box) and _inside(px, py, xb, ea, eb)


@njit(cache=True, nogil=True)
def _disc_back(cx, cy, ax, ay, x, r):  # pragma: no cover - compiled
    """The point of the disc's back at cross coordinate ``x`` (:func:`_buried`)."""
    sb = -np.sqrt(r * r - x * x)
    return cx + sb * ax - x * ay, cy + sb * ay + x * ax


@njit(cache=True, nogil=True)
def _in_box(px, py, box):  # pragma: no cover - compiled
    """Whether ``(px, py)`` lies in the box ``(xmin, xmax, ymin, ymax)``."""
    return box[0] <= px <= box[1] and box[2] <= py <= box[3]


@njit(cache=True, nogil=True)
def _crosses(px, py, ax, ay, bx, by):  # pragma: no cover - compiled
    """Whether the edge ``a → b`` crosses the ray from ``(px, py)`` towards ``+x`` (the
    even-odd rule)."""
    if (ay > py) != (by > py):
        return px < ax + (py - ay) * (bx - ax) / (by - ay)
    return False


@njit(cache=True, nogil=True)
def _inside(px, py, xb, ea, eb):  # pragma: no cover - compiled
    """Even-odd membership of (px, py) in the part."""
    inside = False
    for e in range(ea.shape[0]):
        if _crosses(px, py, xb[ea[e], 0], xb[ea[e], 1], xb[eb[e], 0], xb[eb[e], 1]):
            inside = not inside
    return inside


@njit(cache=True, nogil=True)
def _inside_and_distance(px, py, xb, ea, eb):  # pragma: no cover - compiled
    """Even-odd membership of (px, py) in the part, and its distance to the boundary."""
    inside = False
    dmin = np.inf
    for e in range(ea.shape[0]):
        ax, ay = xb[ea[e], 0], xb[ea[e], 1]
        bx, by = xb[eb[e], 0], xb[eb[e], 1]
        if _crosses(px, py, ax, ay, bx, by):
            inside = not inside
        ex, ey = bx - ax, by - ay
        den = ex * ex + ey * ey
        s = ((px - ax) * ex + (py - ay) * ey) / den if den > 0 else 0.0
        s = min(max(s, 0.0), 1.0)
        d = np.hypot(px - ax - s * ex, py - ay - s * ey)
        if d < dmin:
            dmin = d
    return inside, dmin


@njit(cache=True, nogil=True)
def _new_rows(cap):  # pragma: no cover - compiled
    """Empty row storage of capacity ``cap``: ``(kind, finger, corner, element, na, nb, wa,
    wb, dx, dy, gap, px, py)``."""
    return (np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap, np.int64),
            np.empty(cap, np.int64), np.empty(cap, np.int64), np.empty(cap), np.empty(cap), np.empty(cap),
            np.empty(cap), np.empty(cap), np.empty(cap), np.empty(cap))


@njit(cache=True, nogil=True)
def _put(rows, n, kind, f, corner, element, na, nb, wa, wb, dx, dy, gap, px, py):  # pragma: no cover
    """Store row ``n`` (see :func:`_new_rows`); returns ``n + 1``."""
    rows[0][n], rows[1][n], rows[2][n], rows[3][n] = kind, f, corner, element
    rows[4][n], rows[5][n], rows[6][n], rows[7][n] = na, nb, wa, wb
    rows[8][n], rows[9][n], rows[10][n], rows[11][n], rows[12][n] = dx, dy, gap, px, py
    return n + 1


@njit(cache=True, nogil=True)
def _foot(part, e, wx, wy):  # pragma: no cover - compiled
    """Edge ``e``'s start ``(ax, ay)`` and vector ``(ex, ey)``, the foot parameter ``s`` of
    the point ``(wx, wy)`` on it and the point's distance ``gl`` to its line (> 0 outside)."""
    xb, ea, eb, en, el2 = part[0], part[1], part[2], part[3], part[4]
    ax, ay = xb[ea[e], 0], xb[ea[e], 1]
    ex, ey = xb[eb[e], 0] - ax, xb[eb[e], 1] - ay
    s = ((wx - ax) * ex + (wy - ay) * ey) / el2[e]
    gl = -((wx - ax) * en[e, 0] + (wy - ay) * en[e, 1])
    return ax, ay, ex, ey, s, gl


@njit(cache=True, nogil=True)
def _put_edge(rows, n, kind, f, corner, part, e, s, gap):  # pragma: no cover - compiled
    """Store a row on edge ``e`` at foot parameter ``s``: force along its inward normal,
    shared by its end nodes."""
    xb, ea, eb, en = part[0], part[1], part[2], part[3]
    ax, ay = xb[ea[e], 0], xb[ea[e], 1]
    ex, ey = xb[eb[e], 0] - ax, xb[eb[e], 1] - ay
    return _put(rows, n, kind, f, corner, e, ea[e], eb[e], 1.0 - s, s, en[e, 0], en[e, 1], gap,
                ax + s * ex, ay + s * ey)


@njit(cache=True, nogil=True)
def _node_inward(part, i):  # pragma: no cover - compiled
    """Inward normal (unnormalised) of the boundary at node ``i``: the sum of its two
    edges' inward unit normals."""
    en, eprev, enext = part[3], part[5], part[6]
    return en[eprev[i], 0] + en[enext[i], 0], en[eprev[i], 1] + en[enext[i], 1]


@njit(cache=True, nogil=True)
def _body_rows(f, t, parf, vs, ve, fg, part, box, radius, emit, rows, n, pmax, depth):  # pragma: no cover
    """Boundary nodes against the body of finger ``f``: rows with a gap below ``radius``
    (when ``emit``), and the deepest node. Returns ``(n, any node inside, pmax, depth)``.
    ``box``: the part's bounding box (:func:`_bbox`)."""
    pv, pn, po = fg[1], fg[2], fg[3]
    xb, ea, eb = part[0], part[1], part[2]
    cx, cy, r, ax, ay, reach = parf[0], parf[1], parf[2], parf[3], parf[4], parf[5]
    anyin = False
    for i in range(xb.shape[0]):
        px, py = xb[i, 0], xb[i, 1]
        if t == _DISC:
            # :func:`_disc_point_sd`, with the arrays passed only where the buried test
            # needs them (a call taking arrays in this loop costs more than the geometry)
            nx, ny = _node_inward(part, i)
            side, xc = _disc_side(cx, cy, r, ax, ay, reach, px, py, nx, ny)
            axial = side == _FRONT
            if side == _BEHIND:
                # :func:`_buried`, the box test first (most points behind a disc are
                # far from the part)
                qx, qy = _disc_back(cx, cy, ax, ay, xc, r)
                axial = _in_box(qx, qy, box) and _inside(qx, qy, xb, ea, eb)
            sd, ox, oy = _disc_sd(cx, cy, r, ax, ay, reach, px, py, axial)
        else:
            sd, ox, oy = _solid_sd(t, parf, vs, ve, pv, pn, po, px, py)
        if sd < 0:
            anyin = True
        if -sd > pmax:
            pmax = -sd
        if -sd > depth and t != _DISC:    # a disc is a round pad: no depth limit (SPEC §6)
            depth = -sd
        if emit and sd < radius:
            n = _put(rows, n, _NODE_BODY, f, -1, i, i, i, 1.0, 0.0, ox, oy, sd, px, py)
    return n, anyin, pmax, depth


@njit(cache=True, nogil=True)
def _disc_edges(f, parf, part, box, wx, wy, off, radius, emit, rows, n, pmax):  # pragma: no cover
    """A disc outside the part with no node inside it, against the edges whose foot point
    it faces and whose end nodes are outside it: between two nodes a straight edge may cut
    the disc while both stay outside it (a mesh coarse for the disc). One pass serves both
    uses: with ``emit`` it stores the rows with a gap below ``radius``, without it raises
    ``pmax`` to the deepest such cut. Returns ``(n, pmax)``."""
    xb, ea, eb = part[0], part[1], part[2]
    for e in range(part[1].shape[0]):
        ax, ay, ex, ey, s, gl = _foot(part, e, wx, wy)
        if s <= 0.0 or s >= 1.0:
            continue
        if emit:
            if not (gl >= 0 and gl - off < radius):
                continue
        elif not (gl >= 0 and off - gl > pmax):
            continue
        na, ma = _node_inward(part, part[1][e])
        nb, mb = _node_inward(part, part[2][e])
        sa = _disc_point_sd(parf, ax, ay, na, ma, xb, ea, eb, box)[0]
        sb = _disc_point_sd(parf, ax + ex, ay + ey, nb, mb, xb, ea, eb, box)[0]
        if sa > 0 and sb > 0:
            if emit:
                n = _put_edge(rows, n, _DISC_EDGE, f, -1, part, e, s, gl - off)
            else:
                pmax = off - gl
    return n, pmax


@njit(cache=True, nogil=True)
def _nearest_edge(t, vs, ve, pv, part, wx, wy, off, dmin):  # pragma: no cover - compiled
    """For a corner (or disc centre, offset ``off``) inside the part at distance ``dmin``
    from the boundary: among the nearest edges (within twice that distance) the one the
    finger crosses least deeply — for a polygon the depth of the whole polygon past the
    edge's line (separating axes), so a finger corner passing a part's corner presses its
    side, not its end. Returns ``(edge or -1, its gl, its s)``."""
    en, el2 = part[3], part[4]
    best, bdepth, bgl, bs = -1, np.inf, 0.0, 0.0
    for e in range(part[1].shape[0]):
        ax, ay, ex, ey, s, gl = _foot(part, e, wx, wy)
        if s < 0.0 or s > 1.0:
            continue
        eps = 1e-12 * np.sqrt(el2[e])      # on the edge up to round-off counts (a corner
        if gl >= eps or -gl > 2.0 * dmin + eps:  # on the boundary is inside or not by a bit)
            continue
        dep = -gl + off
        if t == _POLYGON:
            for j in range(vs, ve):
                dep = max(dep, (pv[j, 0] - ax) * en[e, 0] + (pv[j, 1] - ay) * en[e, 1])
        if dep < bdepth * (1 - 1e-12) or (dep <= bdepth * (1 + 1e-12) and gl > bgl):
            best, bdepth, bgl, bs = e, dep, gl, s
    return best, bgl, bs


@njit(cache=True, nogil=True)
def _outside_edges(f, k, part, wx, wy, radius, rows, n):  # pragma: no cover - compiled
    """A corner outside the part against every edge whose foot point it has, gap below
    ``radius`` (touching up to round-off counts)."""
    el2 = part[4]
    for e in range(part[1].shape[0]):
        ax, ay, ex, ey, s, gl = _foot(part, e, wx, wy)
        if s < 0.0 or s > 1.0:
            continue
        if gl >= -1e-12 * np.sqrt(el2[e]) and gl < radius:
            n = _put_edge(rows, n, _CORNER_EDGE, f, k, part, e, s, gl)
    return n


@njit(cache=True, nogil=True)
def _vertex_rows(f, k, part, wx, wy, off, inside, dmin, got, radius, rows, n):  # pragma: no cover
    """Corner ``k`` against boundary vertices: inside the part, when its nearest feature
    is a vertex (no edge row ``got``), push that vertex past the corner; outside, a
    convex vertex whose normal cone holds the corner."""
    xb, ea, eb, el2, eprev, enext, convex = part[0], part[1], part[2], part[4], part[5], part[6], part[7]
    for i in range(xb.shape[0]):
        rx, ry = xb[i, 0] - wx, xb[i, 1] - wy
        d = np.hypot(rx, ry)
        if d <= 0:
            continue
        if inside:
            ok = (not got) and d <= dmin * (1 + 1e-9) + 1e-12 * d
            gp = -d - off
            ux, uy = -rx / d, -ry / d
        else:
            if not convex[i] or d >= radius:
                continue
            e1, e0 = enext[i], eprev[i]
            a1x, a1y = xb[ea[e1], 0], xb[ea[e1], 1]
            s1 = ((wx - a1x) * (xb[eb[e1], 0] - a1x) + (wy - a1y) * (xb[eb[e1], 1] - a1y)) / el2[e1]
            a0x, a0y = xb[ea[e0], 0], xb[ea[e0], 1]
            s0 = ((wx - a0x) * (xb[eb[e0], 0] - a0x) + (wy - a0y) * (xb[eb[e0], 1] - a0y)) / el2[e0]
            ok = s1 < 0 and s0 > 1      # in the vertex's normal cone
            gp = d
            ux, uy = rx / d, ry / d
        if ok:
            n = _put(rows, n, _CORNER_NODE, f, k, i, i, i, 1.0, 0.0, ux, uy, gp, xb[i, 0], xb[i, 1])
    return n


@njit(cache=True, nogil=True)
def _corner_rows(f, t, vs, ve, fg, part, box, radius, emit, anyin, rows, n, pmax, depth):  # pragma: no cover
    """The corners of finger ``f`` (point finger, polygon corners) and a disc's centre:
    inside the part they set the depth and press on their nearest edge or vertex; outside,
    corners press on edges and convex vertices, and a disc on the edges cutting it.
    Returns ``(n, pmax, depth)``."""
    par, pv = fg[0], fg[1]
    xb, ea, eb = part[0], part[1], part[2]
    ncorner = 0
    if t == _POINT or t == _DISC:
        ncorner = 1
    elif t == _POLYGON:
        ncorner = ve - vs
    for k in range(ncorner):
        if t == _POLYGON:
            wx, wy, off = pv[vs + k, 0], pv[vs + k, 1], 0.0
        else:
            wx, wy = par[f, 0], par[f, 1]
            off = par[f, 2] if t == _DISC else 0.0
        inside, dmin = _inside_and_distance(wx, wy, xb, ea, eb)
        if inside:
            if dmin + off > depth and t != _DISC:
                depth = dmin + off
            if dmin + off > pmax:
                pmax = dmin + off
        elif t == _DISC:
            if not anyin:       # once a node is inside, the node rows of SPEC §6 see the disc
                n, pmax = _disc_edges(f, par[f], part, box, wx, wy, off, radius, emit, rows, n, pmax)
            continue
        if not emit or (t == _DISC and anyin):
            # once a node is inside a disc, the node rows of SPEC §6 alone see it (as
            # for a round pad pressed past its centre): its centre adds no row
            continue
        got = False
        if inside:
            best, bgl, bs = _nearest_edge(t, vs, ve, pv, part, wx, wy, off, dmin)
            if best >= 0:
                n = _put_edge(rows, n, _CENTRE_EDGE if t == _DISC else _CORNER_EDGE, f, k, part, best, bs,
                              bgl - off)
            got = best >= 0
        else:
            n = _outside_edges(f, k, part, wx, wy, radius, rows, n)
        n = _vertex_rows(f, k, part, wx, wy, off, inside, dmin, got, radius, rows, n)
    return n, pmax, depth


@njit(cache=True, nogil=True)
def _scan(g, radius, emit, c, xb, ea, eb, en, el2, eprev, enext, convex, ftype, fpar, vstart,
          verts, vnorm, cap):  # pragma: no cover - compiled
    """All contact rows with a gap below ``radius`` (when ``emit``) and, always, the
    deepest penetration and the largest finger depth (for admissibility).

    Returns ``(n, kind, finger, corner, element, na, nb, wa, wb, dx, dy, gap, px, py,
    pmax, depth)``; arrays have capacity ``cap``.
    """
    fg = _place_fingers(g, c, ftype, fpar, verts, vnorm)
    part = (xb, ea, eb, en, el2, eprev, enext, convex)
    box = _bbox(xb)
    rows = _new_rows(cap)
    n = 0
    pmax = 0.0
    depth = 0.0
    for f in range(ftype.shape[0]):
        t = ftype[f]
        vs, ve = vstart[f], vstart[f + 1]
        anyin = False
        if t != _POINT:
            n, anyin, pmax, depth = _body_rows(f, t, fg[0][f], vs, ve, fg, part, box, radius, emit, rows, n,
                                               pmax, depth)
        n, pmax, depth = _corner_rows(f, t, vs, ve, fg, part, box, radius, emit, anyin, rows, n, pmax, depth)
    return (n, rows[0], rows[1], rows[2], rows[3], rows[4], rows[5], rows[6], rows[7], rows[8], rows[9],
            rows[10], rows[11], rows[12], pmax, depth)


# ----------------------------------------------------------------------------- LCP


@njit(cache=True, nogil=True)
def _row_dofs(na, nb, wa, wb, dx, dy, ypos, sel):  # pragma: no cover - compiled
    """Each selected row as 4 (dof of Y, coefficient) pairs."""
    m = sel.shape[0]
    dof = np.zeros((m, 4), np.int64)
    cf = np.zeros((m, 4))
    for r in range(m):
        i = sel[r]
        pa, pb = ypos[na[i]], ypos[nb[i]]
        dof[r, 0], dof[r, 1], dof[r, 2], dof[r, 3] = 2 * pa, 2 * pa + 1, 2 * pb, 2 * pb + 1
        cf[r, 0], cf[r, 1] = wa[i] * dx[i], wa[i] * dy[i]
        cf[r, 2], cf[r, 3] = wb[i] * dx[i], wb[i] * dy[i]
    return dof, cf


@njit(cache=True, nogil=True)
def _delassus(Y, dof, cf):  # pragma: no cover - compiled
    m = dof.shape[0]
    W = np.empty((m, m))
    for r in range(m):
        for s in range(r, m):
            v = 0.0
            for a in range(4):
                ca = cf[r, a]
                if ca == 0.0:
                    continue
                for b in range(4):
                    cb = cf[s, b]
                    if cb != 0.0:
                        v += ca * cb * Y[dof[r, a], dof[s, b]]
            W[r, s] = v
            W[s, r] = v
    return W


@njit(cache=True, nogil=True)
def _no_solution(E, status):  # pragma: no cover - compiled
    """The result of :func:`_solve_placement` without contact rows."""
    empty_i = np.zeros(0, np.int64)
    empty_f = np.zeros(0)
    return (E, status, np.zeros(3), empty_i, empty_i, empty_f, empty_f, empty_f, empty_f, empty_f, empty_f,
            empty_i, empty_i, empty_f, empty_f, empty_i)


@njit(cache=True, nogil=True)
def _row_keys(R, n, n_ids):  # pragma: no cover - compiled
    """Identity key of each of the ``n`` rows of scan ``R`` (warm starts)."""
    kind, finger, corner, element = R[1][:n], R[2][:n], R[3][:n], R[4][:n]
    return ((kind * 64 + finger) * 4096 + (corner + 1)) * n_ids + element


@njit(cache=True, nogil=True)
def _solve_rows(R, sel, key, tol, warm, ypos, Y):  # pragma: no cover - compiled
    """The LCP of the rows ``sel`` of scan ``R``, warm-started from the active keys
    ``warm`` (or, without them, from the penetrating rows). Returns ``(λ, ok, W, dof, cf)``."""
    n = R[0]
    na, nb, wa, wb, dx, dy, gap = R[5][:n], R[6][:n], R[7][:n], R[8][:n], R[9][:n], R[10][:n], R[11][:n]
    dof, cf = _row_dofs(na, nb, wa, wb, dx, dy, ypos, sel)
    W = _delassus(Y, dof, cf)
    reg = 0.0
    for i in range(W.shape[0]):
        reg += W[i, i]
    reg *= 1e-12 / max(W.shape[0], 1)
    for i in range(W.shape[0]):
        W[i, i] += reg
    q = gap[sel] + tol
    free0 = np.zeros(sel.shape[0], np.bool_)
    for r in range(sel.shape[0]):
        kk = key[sel[r]]
        j = np.searchsorted(warm, kk)
        if j < warm.shape[0] and warm[j] == kk:
            free0[r] = True
        elif q[r] < 0 and warm.shape[0] == 0:
            free0[r] = True
    lam, ok = bpp_kernel(W, q, free0)
    return lam, ok, W, dof, cf


@njit(cache=True, nogil=True)
def _n_violated(R, rest, sel, lam, dof, cf, tol, ypos, Y):  # pragma: no cover - compiled
    """How many of the rows ``rest`` left out of the LCP the solution makes penetrate."""
    n = R[0]
    na, nb, wa, wb, dx, dy, gap = R[5][:n], R[6][:n], R[7][:n], R[8][:n], R[9][:n], R[10][:n], R[11][:n]
    dof2, cf2 = _row_dofs(na, nb, wa, wb, dx, dy, ypos, rest)
    worst = 0
    for r in range(rest.shape[0]):
        v = gap[rest[r]] + tol
        for a in range(4):
            if cf2[r, a] == 0.0:
                continue
            for s in range(sel.shape[0]):
                if lam[s] == 0.0:
                    continue
                for b in range(4):
                    if cf[s, b] != 0.0:
                        v += cf2[r, a] * Y[dof2[r, a], dof[s, b]] * cf[s, b] * lam[s]
        if v < -tol:
            worst += 1
    return worst


@njit(cache=True, nogil=True)
def _force_and_keys(g, c, R, sel, lam, key):  # pragma: no cover - compiled
    """Generalised force ``dE/dg = −Σ λ_r [R d_r, (p_r − c) × d_r]`` and the sorted keys
    of the pressing rows."""
    grad = np.zeros(3)
    cph, sph = np.cos(g[2]), np.sin(g[2])
    nact = 0
    for s in range(sel.shape[0]):
        if lam[s] > 0:
            nact += 1
            i = sel[s]
            ddx, ddy = R[9][i], R[10][i]
            grad[0] -= lam[s] * (cph * ddx - sph * ddy)
            grad[1] -= lam[s] * (sph * ddx + cph * ddy)
            grad[2] -= lam[s] * ((R[12][i] - c[0]) * ddy - (R[13][i] - c[1]) * ddx)
    act = np.empty(nact, np.int64)
    k = 0
    for s in range(sel.shape[0]):
        if lam[s] > 0:
            act[k] = key[sel[s]]
            k += 1
    return grad, np.sort(act)


@njit(cache=True, nogil=True)
def _solve_placement(g, tol, depth_limit, e_cap, warm, c, xb, ea, eb, en, el2, eprev, enext, convex, ftype,
                     fpar, vstart, verts, vnorm, ypos, Y, cap):  # pragma: no cover - compiled
    """Energy of one placement. Returns ``(E, status, grad(3), active keys, selected rows, λ,
    gaps, dx, dy, px, py, na, nb, wa, wb, finger)`` (rows: indices into the scan; the rest
    per selected row, part frame, local boundary node indices).

    status: 0 no contact (E = 0), 1 solved, 2 inadmissible, 3 LCP not converged.
    """
    z = _scan(g, 0.0, False, c, xb, ea, eb, en, el2, eprev, enext, convex, ftype, fpar, vstart,
              verts, vnorm, 1)
    pmax, depth = z[14], z[15]
    if depth > depth_limit:
        return _no_solution(np.inf, 2)
    if pmax <= tol:
        return _no_solution(0.0, 0)
    factor = 2.0
    status = 1
    lam = np.zeros(0)
    sel = np.zeros(0, np.int64)
    W = np.zeros((0, 0))
    key = np.zeros(0, np.int64)
    R = z
    for attempt in range(8):
        R = _scan(g, 2.0 * factor * pmax + tol, True, c, xb, ea, eb, en, el2, eprev, enext, convex,
                  ftype, fpar, vstart, verts, vnorm, cap)
        key = _row_keys(R, R[0], xb.shape[0] + ea.shape[0] + 1)
        gap = R[11][:R[0]]
        sel = np.flatnonzero(gap < factor * pmax + tol)
        lam, ok, W, dof, cf = _solve_rows(R, sel, key, tol, warm, ypos, Y)
        if not ok:
            status = 3
        # check the rows left out against the solution's displacement
        rest = np.flatnonzero(gap >= factor * pmax + tol)
        if rest.shape[0] == 0 or _n_violated(R, rest, sel, lam, dof, cf, tol, ypos, Y) == 0:
            break
        factor *= 2.0
    E = 0.5 * (lam @ (W @ lam))
    if not E <= e_cap:
        # beyond any small-strain state (contradictory contact rows: the finger cuts
        # through the part): outside the model
        return _no_solution(np.inf, 2)
    grad, act = _force_and_keys(g, c, R, sel, lam, key)
    return (E, status, grad, act, sel, lam, R[11][sel], R[9][sel], R[10][sel], R[12][sel], R[13][sel],
            R[5][sel], R[6][sel], R[7][sel], R[8][sel], R[2][sel])


@njit(cache=True, nogil=True)
def _batch(G, tol, depth_limit, e_cap, chain, c, xb, ea, eb, en, el2, eprev, enext, convex, ftype, fpar,
           vstart, verts, vnorm, ypos, Y, cap):  # pragma: no cover - compiled
    """Energies of many placements, each warm-started from the previous one (``chain``)."""
    B = G.shape[0]
    E = np.empty(B)
    st = np.empty(B, np.int64)
    warm = np.zeros(0, np.int64)
    for b in range(B):
        out = _solve_placement(G[b], tol, depth_limit, e_cap, warm, c, xb, ea, eb, en, el2, eprev, enext, convex,
                               ftype, fpar, vstart, verts, vnorm, ypos, Y, cap)
        E[b] = out[0]
        st[b] = out[1]
        if chain:
            warm = out[3]
    return E, st


# ----------------------------------------------------------------------------- Python API


@dataclass(frozen=True)
class PlacementState:
    """Contact solution of one placement.

    Attributes
    ----------
    placement : ndarray (3,)
        ``(x, y, φ)``: translation of the area centroid (m) and rotation about it (rad).
    energy : float
        Contact energy (J); ``inf`` when inadmissible.
    status : str
        ``"free"`` (no finger presses), ``"contact"``, ``"inadmissible"`` (a finger deeper
        than the model allows) or ``"unconverged"`` (the LCP stopped at its budget).
    gradient : ndarray (3,)
        ``dE/dg`` (N, N, N m): minus the force and moment the fingers exert on the part.
    active : ndarray of int
        Identity keys of the pressing contact rows (for warm starts).
    forces : ndarray (k, 2)
        Contact forces on the part (N), part frame, one per pressing row.
    points : ndarray (k, 2)
        Their material points on the part at rest (m, part frame).
    nodes, weights : ndarray (k, 2)
        Mesh nodes carrying each force and their shares (an edge row splits its force
        between the edge's end nodes).
    fingers : ndarray (k,) of int
        The finger exerting each force.
    """

    placement: np.ndarray
    energy: float
    status: str
    gradient: np.ndarray
    active: np.ndarray
    forces: np.ndarray
    points: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    fingers: np.ndarray = None  # type: ignore[assignment]


_STATUS = {0: "free", 1: "contact", 2: "inadmissible", 3: "unconverged"}
_NO_KEYS = np.zeros(0, np.int64)


def disc_axes(mesh: Any, fingers: Sequence[Finger]) -> np.ndarray:
    """Pressing direction of every disc finger (unit, world frame; zeros for others).

    A disc presses like a round pad (SPEC §6) along its *axis*, fixed to the finger. A
    disc overlapping the part at rest (pre-squeeze) presses from its part outside the
    part towards its part inside: the axis joins the centroids of the two (a disc seated
    in a V-notch presses along the notch's bisector, even when pressed past its centre).
    A disc that only touches, or misses, presses towards the nearest boundary nodes: the
    weighted mean of the unit vectors from its centre to the nodes within a quarter
    radius of the nearest one (weights falling linearly to zero there).
    """
    import shapely

    rings = [np.asarray(mesh.nodes, float)[np.asarray(lp)] for lp in mesh.loops]
    poly = shapely.Polygon(rings[0], rings[1:])
    P = np.concatenate(rings)
    out = np.zeros((len(fingers), 2))
    for i, f in enumerate(fingers):
        rc = f.round_centre()
        if rc is None:
            continue
        c, r = np.asarray(rc[0], float), rc[1]
        disc = shapely.Point(c).buffer(r, quad_segs=64)
        inside = disc.intersection(poly)
        if inside.area > 1e-6 * disc.area:
            outside = disc.difference(poly)
            co = np.asarray(outside.centroid.coords[0]) if outside.area > 0 else c
            v = np.asarray(inside.centroid.coords[0]) - co
            nv = float(np.linalg.norm(v))
            if nv > 1e-9 * r:
                out[i] = v / nv
                continue
        rel = P - c
        d = np.linalg.norm(rel, axis=1)
        band = d.min() + 0.25 * r
        w = np.clip(band - d, 0.0, None)
        v = (w[:, None] * rel / np.maximum(d, 1e-300)[:, None]).sum(axis=0)
        nv = float(np.linalg.norm(v))
        out[i] = v / nv if nv > 0 else rel[np.argmin(d)] / max(d.min(), 1e-300)
    return out


def _encode(fingers: Sequence[Finger], axes: np.ndarray):
    """The fingers for the compiled kernels (:meth:`Finger.kernel_encoding`): kind codes,
    parameters, and the polygon corners and normals stacked (``vstart`` indexes them)."""
    F = len(fingers)
    ftype = np.zeros(F, np.int64)
    fpar = np.zeros((F, 6))
    vstart = np.zeros(F + 1, np.int64)
    verts, vnorm = [], []
    for i, f in enumerate(fingers):
        ftype[i], fpar[i], v, m = f.kernel_encoding(axes[i])
        verts.append(v)
        vnorm.append(m)
        vstart[i + 1] = vstart[i] + len(v)
    verts = np.concatenate(verts) if verts else np.zeros((0, 2))
    vnorm = np.concatenate(vnorm) if vnorm else np.zeros((0, 2))
    return ftype, fpar, vstart, np.ascontiguousarray(verts, float), np.ascontiguousarray(vnorm, float)


class PlacementEnergy:
    """Contact energy ``E(g)`` of a part among fixed fingers, for any placement ``g``.

    Parameters
    ----------
    mesh : Mesh
        The part at rest (m), with its material.
    fingers : sequence of Finger
        Fixed fingers (m), in the frame of the part at rest.
    solver : BoundaryCompliance, optional
        Reuse a factorisation of this mesh (its ``Y`` and centroid); a pads model's
        :class:`~deformclosure.pads.contact.PadContact` is one.
    centroid : array_like (2,), optional
        Reference point of the rotation (m); default the solver's area centroid. A second
        mesh realisation of the same part must use the first one's.
    tol : float, optional
        Touching tolerance (m), default ``1e-9`` × the diameter.
    max_depth_ratio : float
        Placements where a finger other than a disc reaches deeper than this fraction of
        the part's largest inscribed radius are inadmissible.
    disc_axes_ : array_like (n_fingers, 2), optional
        Pressing axes of the disc fingers (world frame); default :func:`disc_axes`. A
        second mesh realisation must use the first one's.

    Examples
    --------
    >>> pe = PlacementEnergy(mesh, fingers)           # doctest: +SKIP
    >>> pe.energy([0.0, 1e-4, 0.01]).energy           # doctest: +SKIP
    """

    def __init__(self, mesh: Any, fingers: Sequence[Finger], *, solver: Any = None,
                 centroid: Any = None, tol: float | None = None,
                 max_depth_ratio: float = MAX_DEPTH_RATIO, disc_axes_: Any = None) -> None:
        from ..contact.compliance import BoundaryCompliance

        self.mesh = mesh
        self.fingers = tuple(fingers)
        self.solver = BoundaryCompliance.placement_gauge(mesh) if solver is None else solver
        self.centroid = np.asarray(self.solver.centroid if centroid is None else centroid, float)
        self.tol = resolve_tolerance(mesh, tol)
        self.diameter = float(mesh.diameter)
        self.inscribed_radius = inscribed_radius(mesh)
        self.depth_limit = float(max_depth_ratio) * self.inscribed_radius
        mat = getattr(mesh, "material", None)
        # energy of a unit strain everywhere: no small-strain state comes near it
        self.energy_cap = (0.5 * mat.youngs_modulus * mat.thickness * mesh.area if mat is not None
                           else np.inf)
        bd = BoundaryModel(mesh)
        nodes = bd.nodes
        self.nodes = nodes
        local = np.full(mesh.n_nodes, -1, np.int64)
        local[nodes] = np.arange(len(nodes))
        self._xb = np.ascontiguousarray(mesh.nodes[nodes], float)
        self._ea = local[bd.edges[:, 0]]
        self._eb = local[bd.edges[:, 1]]
        self._en = np.ascontiguousarray(bd.inward_normals(np.asarray(mesh.nodes, float)))
        ab = self._xb[self._eb] - self._xb[self._ea]
        self._el2 = np.einsum("ij,ij->i", ab, ab)
        self._enext = bd.edge_of[nodes].copy()
        self._eprev = bd.edge_of[bd.prev[nodes]].copy()
        from .obstacles import CONVEX

        self._convex = bd.feature[nodes] == CONVEX
        self._ypos = np.asarray(self.solver.cc.position(nodes), np.int64)
        self._Y = np.ascontiguousarray(self.solver.Y)
        self.disc_axes = (disc_axes(mesh, self.fingers) if disc_axes_ is None
                          else np.asarray(disc_axes_, float).reshape(len(self.fingers), 2))
        self._fing = _encode(self.fingers, self.disc_axes)
        # corners, and disc centres, each against every node and edge
        nc = sum(len(f.vertices) for f in self.fingers) + sum(f.round_centre() is not None for f in self.fingers)
        n_body = sum(f.has_interior for f in self.fingers)
        self._cap = int(n_body * len(nodes) + nc * (len(nodes) + len(self._ea)) + 8)
        # convex hull of the part at rest (part frame), for the escape test
        import shapely

        hull = shapely.Polygon(mesh.nodes[mesh.outer_loop]).convex_hull
        self.hull = np.asarray(hull.exterior.coords)[:-1]
        self.radius = float(np.linalg.norm(self._xb - self.centroid, axis=1).max())

    # ---------------------------------------------------------------- kernels
    def _args(self):
        ftype, fpar, vstart, verts, vnorm = self._fing
        return (self.centroid, self._xb, self._ea, self._eb, self._en, self._el2, self._eprev,
                self._enext, self._convex, ftype, fpar, vstart, verts, vnorm)

    def energy(self, g: Any, warm: np.ndarray | None = None) -> PlacementState:
        """Contact solution at placement ``g = (x, y, φ)`` (m, m, rad).

        ``warm``: active keys of a nearby placement (:attr:`PlacementState.active`).
        """
        g = np.asarray(g, float).reshape(3)
        w = np.zeros(0, np.int64) if warm is None else np.asarray(warm, np.int64)
        out = _solve_placement(g, self.tol, self.depth_limit, self.energy_cap, w, *self._args(), self._ypos,
                               self._Y, self._cap)
        E, st, grad, act, sel, lam, gap, dx, dy, px, py, na, nb, wa, wb, fi = out
        pos = lam > 0
        lp = lam[pos]
        forces = np.stack([lp * dx[pos], lp * dy[pos]], axis=1)
        return PlacementState(g.copy(), float(E), _STATUS[int(st)], grad, act, forces,
                              np.stack([px[pos], py[pos]], axis=1),
                              self.nodes[np.stack([na[pos], nb[pos]], axis=1)],
                              np.stack([wa[pos], wb[pos]], axis=1), fi[pos])

    def energy_and_active(self, g: Any, warm: np.ndarray | None = None) -> tuple[float, np.ndarray]:
        """Energy (J) at ``g`` and the active keys (for warm starts): :meth:`energy`
        without building the state (the landscape's inner loop)."""
        out = _solve_placement(np.asarray(g, float), self.tol, self.depth_limit, self.energy_cap,
                               _NO_KEYS if warm is None else warm, *self._args(), self._ypos, self._Y,
                               self._cap)
        return float(out[0]), out[3]

    def load_vector(self, state: PlacementState) -> np.ndarray:
        """Global load vector (N, part frame), shape ``(2n,)``, of a state's contact forces."""
        f = np.zeros(2 * self.mesh.n_nodes)
        for j in range(2):
            w = state.weights[:, j, None] * state.forces
            np.add.at(f, 2 * state.nodes[:, j], w[:, 0])
            np.add.at(f, 2 * state.nodes[:, j] + 1, w[:, 1])
        return f

    def displacement(self, state: PlacementState) -> np.ndarray:
        """Deformation (m, part frame, no rigid part), shape ``(n, 2)``, of a state."""
        return self.solver.displacement(self.load_vector(state)).reshape(-1, 2)

    def energies(self, G: Any, chain: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Energies (J) of many placements ``G (B, 3)``; each solve is warm-started from
        the previous one when ``chain`` (order ``G`` along a grid line for speed).

        Returns ``(E, status)``, status codes 0 free, 1 contact, 2 inadmissible,
        3 unconverged.
        """
        G = np.ascontiguousarray(np.asarray(G, float).reshape(-1, 3))
        with blas_threads():      # one small LCP per placement (limits.BLAS_THREADS)
            return _batch(G, self.tol, self.depth_limit, self.energy_cap, bool(chain), *self._args(),
                          self._ypos, self._Y, self._cap)

    # ---------------------------------------------------------------- placement geometry
    def place(self, g: Any, points: Any) -> np.ndarray:
        """World coordinates (m) of part-frame ``points (k, 2)`` at placement ``g``."""
        g = np.asarray(g, float)
        c, s = np.cos(g[2]), np.sin(g[2])
        R = np.array([[c, -s], [s, c]])
        return (np.asarray(points, float) - self.centroid) @ R.T + self.centroid + g[:2]

    def escapable(self, g: Any, n_directions: int = 32, angle0: float = 0.0) -> bool:
        """Whether the part at ``g`` can translate to infinity, in one of ``n_directions``
        directions, without entering any finger (touching allowed). Tested on the part's
        convex hull (separating axes), so it errs on the side of "not yet free". The
        directions start at ``angle0`` (rad)."""
        H = self.place(g, self.hull)
        ang = angle0 + np.linspace(0.0, 2 * np.pi, n_directions, endpoint=False)
        D = np.c_[np.cos(ang), np.sin(ang)]
        tol = 10.0 * self.tol
        e = np.roll(H, -1, axis=0) - H
        hn = np.c_[e[:, 1], -e[:, 0]]
        hn /= np.linalg.norm(hn, axis=1, keepdims=True)
        clear = np.ones(len(D), bool)
        for f in self.fingers:
            idx = np.flatnonzero(clear)
            if len(idx):
                clear[idx] = f.translation_clear(H, hn, D[idx], tol)
        return bool(clear.any())
