"""The discretisation noise floor of grasp energies (SPEC §6, "Noise floor").

On an unstructured mesh the energy of a grasp axis carries an error that changes from
axis to axis: it depends on where the nodes happen to sit under the pads. Two mirror-image
axes of a symmetric part differ by ~1 % at a coarse mesh and ~0.1 % at a fine one, while
the energy differences that decide whether a part slides out can be smaller. We measure
that noise directly: the same part meshed a second time at the same resolution but in a
rotated frame (another, equally good realisation), and the energy of the same physical
axes compared between the two. A continuum answer cannot depend on the realisation, so
their difference is discretisation noise. Where no part geometry is available (a mesh
file), the jitter of the energy under sub-cell moves of the axis stands in for it.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..mesh import mesh_part
from .contact import PadContact
from .geometry import GraspAxis, Pad

__all__ = ["twin_mesh", "realisation_noise", "jitter_noise", "TWIN_ANGLE"]

#: Rotation (rad) of the frame in which the twin realisation is meshed.
TWIN_ANGLE = 1.0


def _rot(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def twin_mesh(part, max_area: float | None = None, angle: float = TWIN_ANGLE):
    """The part meshed in a frame rotated by ``angle`` (rad), returned in the part frame.

    Same mesher settings, so the same resolution; different node positions.
    """
    c = part.outer.mean(axis=0)
    R = _rot(angle)
    rot = lambda P: (np.asarray(P, float) - c) @ R.T + c  # noqa: E731
    opts = part.mesh_options
    pts = np.asarray(opts.points, float).reshape(-1, 2)
    rpart = replace(part, outer=rot(part.outer), holes=tuple(rot(h) for h in part.holes),
                    mesh_options=replace(opts, points=rot(pts) if len(pts) else opts.points))
    return mesh_part(rpart, max_area=max_area).rotated(-angle, c)


def realisation_noise(solver: PadContact, twin: PadContact, pad: Pad, axes: list[GraspAxis],
                      sigma_min: float, factor: float = 3.0, n_sigma: int = 16):
    """Noise floor from two mesh realisations, as a function of the separation.

    The relative difference ``|U₁ − U₂| / max(U₁, U₂)`` between the realisations is taken
    at its largest over ``axes`` and ``n_sigma`` separations between ``sigma_min`` and the
    first axis' first touch; the floor is ``factor`` × that × the first axis' energy.
    ``factor = 3``: a barrier is a difference of two noisy energies, and the largest of a
    few samples underestimates the largest of the many a landscape search compares.

    Returns
    -------
    callable
        ``noise(sigma)`` (J) at separation ``sigma`` (m).
    """
    pairs = [(solver.curve(ax, pad, sigma_min), twin.curve(ax, pad, sigma_min)) for ax in axes]
    start = pairs[0][0]
    sig = np.linspace(sigma_min, start.sigma0, n_sigma + 2)[1:-1]
    rel = 0.0
    for a, b in pairs:
        Ua, Ub = a.energy(sig), b.energy(sig)
        top = np.maximum(Ua, Ub)
        ok = top > 0
        if ok.any():
            rel = max(rel, float((np.abs(Ua - Ub)[ok] / top[ok]).max()))

    def noise(sigma: float) -> float:
        return factor * rel * float(start.energy(sigma))

    noise.relative = factor * rel
    return noise


def jitter_noise(solver: PadContact, pad: Pad, axis: GraspAxis, d_offset: float,
                 d_angle: float, sigma_min: float, n: int = 9, factor: float = 4.0):
    """Noise floor from the jitter of the energy under sub-cell moves of ``axis``.

    The axis is shifted across itself and turned in ``n`` steps spanning one grid cell
    (``d_offset`` m, ``d_angle`` rad); a continuum energy is smooth on that scale, so the
    residual of a quadratic fit is discretisation noise.

    Returns
    -------
    callable
        ``noise(sigma)`` (J): ``factor`` × the largest residual at ``sigma`` (m).
    """
    ts = np.linspace(-0.5, 0.5, n)
    curves = []
    for t in ts:
        curves.append(solver.curve(GraspAxis(axis.angle, axis.offset + t * d_offset, axis.origin),
                                   pad, sigma_min))
    for t in ts:
        curves.append(solver.curve(GraspAxis.at(axis.point, axis.angle + t * d_angle, axis.origin),
                                   pad, sigma_min))
    V = np.vander(ts, 3)
    proj = np.eye(n) - V @ np.linalg.pinv(V)      # residual of the least-squares quadratic

    def noise(sigma: float) -> float:
        U = np.array([float(c.energy(sigma)) for c in curves]).reshape(2, n)
        return factor * float(np.abs(U @ proj.T).max())

    return noise
