"""The discretisation noise floor of grasp energies (SPEC §6, "Noise floor").

On an unstructured mesh the energy of a grasp axis carries an error that changes from
axis to axis: it depends on where the nodes happen to sit under the pads. Two mirror-image
axes of a symmetric part differ by ~1 % at a coarse mesh and ~0.1 % at a fine one, while
the energy differences that decide whether a part slides out can be smaller. We measure
that noise directly: the same part meshed a second time
(:func:`deformclosure.mesh.generate.twin_mesh`), in a rotated frame and with
:data:`~deformclosure.mesh.generate.TWIN_AREA` times the triangle area (another, equally good realisation whose boundary
nodes sit elsewhere: Triangle splits a straight edge evenly, so a rotation alone would
reproduce the boundary nodes and miss the largest part of the noise, the position of the
nodes under the pads), and the energy of the same physical axes compared between the two. A continuum answer cannot depend on the realisation, so
their difference is discretisation noise. Where no part geometry is available (a mesh
file), the jitter of the energy under sub-cell moves of the axis stands in for it.

This module only *measures* (it solves the jittered axes; the twin mesh is the mesher's); the
rule that turns the measurements into the floor is :mod:`deformclosure.landscape.noise`,
shared with the placements of SPEC §7.
"""

from __future__ import annotations

import numpy as np

from ..landscape.noise import JITTER_FACTOR, jitter_floor, quadratic_residual
from .contact import PadContact
from .geometry import GraspAxis, Pad

__all__ = ["jitter_noise"]

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
