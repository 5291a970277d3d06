"""Escape paths as animated GIFs (``--animate``, beside the ``--plot`` pictures).

One frame per point of the path (at most :data:`MAX_FRAMES`, evenly spread, the start,
the saddle and the end always among them: :func:`.pads.path_indices`), written with
matplotlib's :class:`~matplotlib.animation.PillowWriter` (Pillow), atomically
(:func:`deformclosure.outputs.atomic_path`). The frames draw states the models have
already solved — the pads' escape axes at σ* (:func:`.pads.escape_states`), the fingers'
placements of the release path — and solve nothing of their own.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ..units import length_scale

__all__ = ["MAX_FRAMES", "FPS", "NAME", "check_animate", "write_gif", "pad_escape_animation",
           "check_escape_animation"]

#: Most frames of an animation (a longer path is sampled evenly).
MAX_FRAMES = 48

#: Frames per second of the GIFs.
FPS = 4

#: The animation's name beside the pictures (``escape.gif``, ``<stem>_escape.gif``).
NAME = "escape"


def _need_pillow() -> None:
    from ..errors import DeformClosureError

    import importlib.util

    if importlib.util.find_spec("PIL") is None:
        raise DeformClosureError("--animate: the GIF needs Pillow; install it "
                                 "(pip install pillow) or leave out --animate")


def check_animate(params: dict) -> Path | None:
    """``--animate``, before any work: the GIF's path beside ``--plot``
    (:func:`deformclosure.outputs.animation_file`), ``None`` without ``--animate``.

    Raises
    ------
    DeformClosureError
        ``--animate`` without ``--plot``, ``--plot`` a device, or Pillow missing (one line).
    """
    from ..errors import DeformClosureError
    from ..outputs import animation_file

    if not params.get("animate"):
        return None
    if not params.get("plot"):
        raise DeformClosureError("--animate: give --plot too; the GIF is written beside the "
                                 "pictures (--plot out/ writes out/escape.gif)")
    _need_pillow()
    return animation_file(params["plot"], NAME)


def write_gif(fig, draw: Callable[[int], None], n_frames: int, path: str | Path,
              fps: float = FPS, dpi: float = 100) -> Path:
    """Write ``n_frames`` frames of ``fig`` — ``draw(k)`` redraws it as frame ``k`` — to
    the GIF ``path`` (looping, ``1/fps`` s a frame) and close ``fig``.

    Raises
    ------
    DeformClosureError
        Pillow missing, or the file cannot be written (one line).
    """
    import matplotlib.pyplot as plt
    from matplotlib.animation import PillowWriter

    from ..errors import DeformClosureError
    from ..outputs import atomic_path

    try:
        _need_pillow()
    except DeformClosureError:
        plt.close(fig)
        raise
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = PillowWriter(fps=fps)
    try:
        with atomic_path(path, "animation") as tmp:
            with writer.saving(fig, str(tmp), dpi):
                for k in range(n_frames):
                    draw(k)
                    writer.grab_frame()
    except DeformClosureError:
        raise
    except (OSError, ValueError) as err:
        raise DeformClosureError(f"{path}: cannot write the animation ({err})") from None
    finally:
        plt.close(fig)
    return path


def pad_escape_animation(result, path: str | Path, units: str = "mm", scale: float = 1.0,
                         n: int = MAX_FRAMES) -> Path | None:
    """The escape path of a pad grasp at σ* as a GIF: frame by frame the part deformed on
    the path's axes (:func:`.pads.escape_states`: start, saddle — title in red —, end),
    the pads, the grasp energy ``U`` (mJ) in the title, one strain colour scale and one
    frame for all. Of a finite-strain result (SPEC §8), its linear twin's path, titled
    so (as the escape strip).

    Parameters
    ----------
    result : PadGraspResult or FiniteStrainResult
    path : str or Path
        The GIF to write.
    units : str
        Length unit of the axes.
    scale : float
        Displacements drawn ``scale`` times their size (the pads move with them).
    n : int
        Most frames.

    Returns
    -------
    Path or None
        ``None`` (nothing written) when there is no escape path.
    """
    import matplotlib.cm as cm
    from matplotlib.colors import Normalize

    from .mesh import new_figure, side_colorbar
    from .pads import (MODEL_NAMES, _clean, _energy_text, _frame, _pad_depth, check_scale,
                       draw_state, elasticity_of, escape_states)

    check_scale(scale)
    model = elasticity_of(result)
    lin = result.linear if model is not None else result
    states = escape_states(lin, n)
    if not states:
        return None
    s = 1.0 / length_scale(units)
    mesh = lin.solver.mesh
    depth = _pad_depth(lin)
    norm = Normalize(0.0, max(max(float(st.strain.max()) for _, _, st in states), 1e-300))
    span = np.ptp(mesh.nodes, axis=0)
    fig, ax = new_figure((6.5, min(max(5.2 * span[1] / span[0], 2.0), 5.5) + 1.6))
    side_colorbar(ax, cm.ScalarMappable(norm=norm, cmap="viridis"),
                  "averaged strain magnitude (m/m)")
    pts = []
    for _, curve, st in states:                 # one frame holding every frame's part
        _, xy = draw_state(ax, mesh, curve, lin.pad, st, units, scale, depth, norm=norm,
                           pressure=False)
        pts.append(np.vstack([xy, mesh.nodes * s]))
        ax.clear()
    allp = np.vstack(pts)
    sad = lin.saddle
    twin = "" if model is None else f"linear twin of the {MODEL_NAMES.get(model, model)} run: "
    U0 = states[0][2].energy

    def draw(k: int) -> None:
        i, curve, st = states[k]
        ax.clear()
        draw_state(ax, mesh, curve, lin.pad, st, units, scale, depth, norm=norm,
                   pressure=False)
        _frame(ax, allp)
        is_saddle = sad is not None and np.isclose(curve.axis.angle, sad.angle) \
            and np.isclose(curve.axis.offset, sad.offset)
        ax.set_title(f"{twin}escape path at σ* = {lin.sigma_star * s:.4g} {units} "
                     f"(U_A = {_energy_text(lin.U_A)})\naxis {i + 1}/{len(lin.escape_path)}: "
                     f"{np.degrees(curve.axis.angle) % 180:.0f}°, "
                     f"c = {_clean(curve.axis.offset, mesh.diameter) * s:.3g} {units}; "
                     f"U − U_start = {(st.energy - U0) * 1e3:.4g} mJ"
                     + (" (saddle)" if is_saddle else ""), fontsize=9,
                     color="C3" if is_saddle else "k")
        ax.set_xlabel(f"x ({units})")
        ax.set_ylabel(f"y ({units})")

    return write_gif(fig, draw, len(states), path)


def check_escape_animation(mesh, rel, fingers: Sequence[Any], path: str | Path,
                           units: str = "m", n: int = MAX_FRAMES) -> Path | None:
    """The escape path of ``check`` (SPEC §7) as a GIF: frame by frame the part's outline
    at the path's placements among the fingers (the equilibrium's dashed; the saddle's in
    red), the centroid's path so far, and the energy above the equilibrium's (J) in the
    title.

    Parameters
    ----------
    mesh : Mesh
    rel : FingerRelease
    fingers : sequence of Finger
    path : str or Path
        The GIF to write.
    units : str
        Length unit of the axes.
    n : int
        Most frames.

    Returns
    -------
    Path or None
        ``None`` (nothing written) when the path has fewer than two placements (no
        escape to show: :func:`.escape.escape_note` says why).
    """
    from .dspace import fingers_in_frame
    from .mesh import new_figure
    from .pads import path_indices

    P = np.asarray(rel.path, float)
    if len(P) < 2:
        return None
    s = length_scale(units)
    idx = path_indices(len(P), n, rel.saddle)
    loops = [np.asarray(mesh.nodes, float)[np.asarray(lp)] for lp in mesh.loops]

    def outline(g):
        return [np.vstack([q, q[:1]]) / s for q in (rel.place(g, lp) for lp in loops)]

    rings = {k: outline(P[k]) for k in idx}
    allp = np.vstack([r for k in idx for r in rings[k]])
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.1 * float(np.max(hi - lo))
    bounds = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    C = np.array([rel.place(g, rel.centroid[None])[0] for g in P]) / s
    E = np.asarray(rel.path_energy, float)
    E0 = float(E[0]) if len(E) else 0.0
    fig, ax = new_figure((6.0, 6.0))

    def draw(f: int) -> None:
        k = idx[f]
        ax.clear()
        for q in rings[idx[0]]:
            ax.plot(q[:, 0], q[:, 1], color="0.45", lw=0.8, ls="--", zorder=2)
        colour = "tab:red" if k == rel.saddle else "tab:blue"
        for q in rings[k]:
            ax.fill(q[:, 0], q[:, 1], color=colour, alpha=0.25, lw=0, zorder=2)
            ax.plot(q[:, 0], q[:, 1], color=colour, lw=1.4, zorder=3)
        ax.plot(C[:k + 1, 0], C[:k + 1, 1], "-", color="k", lw=0.8, zorder=4)
        ax.plot(*C[k], "o", color="k", ms=4, zorder=5)
        fingers_in_frame(ax, fingers, units, bounds, f"x ({units})", f"y ({units})")
        e = f"; E − E_eq = {E[k] - E0:.4g} J" if len(E) > k else ""
        ax.set_title(f"escape path: placement {k + 1}/{len(P)}{e}"
                     + (" (saddle)" if k == rel.saddle else ""), fontsize=9,
                     color="C3" if k == rel.saddle else "k")

    return write_gif(fig, draw, len(idx), path)
