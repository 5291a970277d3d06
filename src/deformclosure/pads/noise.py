"""The discretisation noise floor of grasp energies (SPEC §6, "Noise floor").

On an unstructured mesh the energy of a grasp axis carries an error that changes from
axis to axis: it depends on where the nodes happen to sit under the pads. Two mirror-image
axes of a symmetric part differ by ~1 % at a coarse mesh and ~0.1 % at a fine one, while
the energy differences that decide whether a part slides out can be smaller. We measure
that noise directly: the same part meshed a second time, in a rotated frame and with
:data:`TWIN_AREA` times the triangle area (another, equally good realisation whose boundary
nodes sit elsewhere: Triangle splits a straight edge evenly, so a rotation alone would
reproduce the boundary nodes and miss the largest part of the noise, the position of the
nodes under the pads), and the energy of the same physical axes compared between the two. A continuum answer cannot depend on the realisation, so
their difference is discretisation noise. Where no part geometry is available (a mesh
file), the jitter of the energy under sub-cell moves of the axis stands in for it.

This module only *measures* (it builds the twin mesh and solves the jittered axes); the
rule that turns the measurements into the floor is :mod:`deformclosure.landscape.noise`,
shared with the placements of SPEC §7.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..landscape.noise import JITTER_FACTOR, jitter_floor, quadratic_residual
from ..mesh import mesh_part
from .contact import PadContact
from .geometry import GraspAxis, Pad

__all__ = ["twin_mesh", "jitter_noise", "TWIN_ANGLE", "TWIN_AREA"]

#: Rotation (rad) of the frame in which the twin realisation is meshed.
TWIN_ANGLE = 1.0

#: Triangle-area ratio of the twin realisation: boundary nodes at other positions, and a
#: coarser mesh, so the noise it shows errs on the large (cautious) side and costs less.
TWIN_AREA = 1.3


def _rot(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def twin_mesh(part, max_area: float | None = None, angle: float = TWIN_ANGLE,
              area_ratio: float = TWIN_AREA):
    """A second realisation of the part's mesh, returned in the part frame.

    Meshed in a frame rotated by ``angle`` (rad) with ``area_ratio`` × the triangle area
    ``max_area`` (m², default the part's), so every node, boundary nodes included, sits
    elsewhere.
    """
    c = part.outer.mean(axis=0)
    R = _rot(angle)
    rot = lambda P: (np.asarray(P, float) - c) @ R.T + c  # noqa: E731
    opts = part.mesh_options
    pts = np.asarray(opts.points, float).reshape(-1, 2)
    rpart = replace(part, outer=rot(part.outer), holes=tuple(rot(h) for h in part.holes),
                    mesh_options=replace(opts, points=rot(pts) if len(pts) else opts.points))
    from ..mesh.generate import default_max_area

    area = default_max_area(part) if max_area is None else max_area
    return mesh_part(rpart, max_area=area * area_ratio).rotated(-angle, c)


def jitter_noise(solver: PadContact, pad: Pad, axis: GraspAxis, d_offset: float,
                 d_angle: float, sigma_end: float, n: int = 9, factor: float = JITTER_FACTOR,
                 hole: int | None = None):
    """Noise floor from the jitter of the energy under sub-cell moves of ``axis``.

    The axis is shifted across itself and turned in ``n`` steps spanning one grid cell
    (``d_offset`` m, ``d_angle`` rad); a continuum energy is smooth on that scale, so the
    residual of a quadratic fit is discretisation noise.

    Returns
    -------
    callable
        ``noise(sigma)``: ``factor`` × the largest residual at ``sigma`` (m), relative to
        the axis' own energy there.
    """
    ts = np.linspace(-0.5, 0.5, n)
    curves = []
    for t in ts:
        curves.append(solver.curve(GraspAxis(axis.angle, axis.offset + t * d_offset, axis.origin),
                                   pad, sigma_end, hole))
    for t in ts:
        curves.append(solver.curve(GraspAxis.at(axis.point, axis.angle + t * d_angle, axis.origin),
                                   pad, sigma_end, hole))
    proj = quadratic_residual(ts)

    def noise(sigma: float) -> float:
        U = np.array([float(c.energy(sigma)) for c in curves]).reshape(2, n)
        U0 = float(curves[n // 2].energy(sigma))
        return jitter_floor(float(np.abs(U @ proj.T).max()), U0, factor) if U0 > 0 else 0.0

    return noise
