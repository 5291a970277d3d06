"""Pictures of pad grasps (SPEC §6): the part deformed at σ* with its averaged strain, the
pads and the contact pressure; the quality and force curves; the escape path; the
convergence of a refined run; and of plans, the quality map over (θ, c) and the best
grasps deformed.

Every ``plot_*`` function draws on ``ax`` (a new figure when ``None``) or makes its own
figure (the strips), and returns the figure. Lengths in ``units``, energies in mJ,
forces in N, strains in m/m, pressures in Pa (or kPa, MPa).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..pads.geometry import pad_depth, pad_pair
from ..units import length_scale
from .grasp import quality_lines, sigma_marks
from .mesh import figure_axes, legend_below, legend_outside, save_figures, side_colorbar

__all__ = ["plot_pad_quality", "plot_pad_grasp", "plot_pad_plan", "draw_pads", "save_pad_plots",
           "PadState", "pad_state", "curve_state", "draw_state", "plot_force_squeeze",
           "escape_states", "plot_escape_strip", "plot_convergence", "plot_pad_quality_map",
           "plot_pad_top_grasps", "plot_plan_convergence", "save_pad_plan_plots",
           "check_scale"]


def _nan(v) -> np.ndarray:
    return np.array([np.nan if x is None else x for x in v], float)


def _outline(ax, mesh, s: float) -> None:
    """The part's boundary loops, lightly filled, in plot units (``s`` per metre)."""
    for lp in mesh.loops:
        P = mesh.nodes[np.append(lp, lp[0])] * s
        ax.plot(P[:, 0], P[:, 1], color="k", lw=1)
    ax.fill(*(mesh.nodes[mesh.outer_loop] * s).T, color="C0", alpha=0.15, lw=0)
    for lp in mesh.hole_loops:
        ax.fill(*(mesh.nodes[lp] * s).T, color="white", lw=0)


def plot_pad_quality(result, ax=None, units: str = "mm"):
    """``U``, ``U_A``, ``U_L`` and ``Q`` (mJ) against the pad separation σ: the picture of
    :func:`deformclosure.plotting.grasp.plot_quality_curve` with the grasp energy ``U``.

    Parameters
    ----------
    result : PadGraspResult or FiniteStrainResult
    ax : matplotlib Axes, optional
    units : str
        Length unit of σ; energies are drawn in mJ.

    Returns
    -------
    matplotlib.figure.Figure
        ``ax.figure``, to compose with others or save.
    """
    ax, s = figure_axes(ax, (7, 4.5), units)
    c = result.curve
    sig = _nan(c["sigma"]) * s
    quality_lines(ax, sig, _nan(c["Q"]) * 1e3, _nan(c["U_A"]) * 1e3, _nan(c["U_L"]) * 1e3)
    ax.plot(sig, _nan(c["U"]) * 1e3, color="k", lw=0.8, ls="--", label="$U$ (grasp energy)")
    sigma_marks(ax, result.sigma_star, result.quality, result.sigma_L, s, units)
    ax.set_xlabel(f"pad separation σ ({units})")
    ax.set_ylabel("energy (mJ)")
    ax.set_title(f"{_model_tag(result)}pads W = {result.pad.width * s:.3g}, "
                 f"ρ = {result.pad.radius * s:.3g} {units}: {result.verdict}")
    legend_outside(ax)
    return ax.figure


def draw_pads(ax, result, sigma: float | None = None, units: str = "mm", **kw):
    """Draw both pads of ``result`` at separation ``sigma`` (m; default first touch) where
    the contact path puts them relative to the part in its solver's gauge (pad A's face at
    ``z_a − t``, pad B's at ``z_b − δ − t``; see :class:`PadState`)."""
    s = 1.0 / length_scale(units)
    curve = result.start_curve
    sigma = result.sigma0 if sigma is None else sigma
    delta, t = _path_motion(curve, sigma)
    for P in _pads_at(curve, result.pad, delta, t, _pad_depth(result)):
        ax.fill(P[:, 0] * s, P[:, 1] * s, color=kw.get("color", "0.35"),
                alpha=kw.get("alpha", 0.8), lw=0)
    return ax


def _path_motion(curve, sigma: float) -> tuple[float, float]:
    """The squeeze ``δ`` (m) at ``sigma`` and the part's axial translation ``t`` (m) on
    the curve's contact path there (0 before first touch)."""
    path = curve.path
    if path is None:
        return 0.0, 0.0
    delta = float(curve.delta(sigma))
    t = float(np.interp(delta, path.delta, path.t)) if len(path.delta) > 1 else 0.0
    return delta, t


@dataclass(frozen=True)
class PadState:
    """A pad grasp solved at one separation, for pictures (SI units).

    The part is drawn in the gauge of its solver (mean displacement and mean rotation
    zero, SPEC §6), the pads where the contact path puts them relative to it: pad A's
    face at ``z_a`` and pad B's at ``z_b`` along the axis (m), both moved by the part's
    axial translation ``t`` of the path so that the pads touch the deformed part. A
    finite-strain state (:func:`finite_strain_state`) is drawn in its own curve's frame,
    its pads' faces given by the same ``delta`` and ``translation``.

    Attributes
    ----------
    sigma : float
        Separation (m).
    delta : float
        Squeeze (m).
    displacement : ndarray, shape (n, 2)
        Node displacements (m), in the solver's gauge.
    translation : float
        The part's axial translation on the contact path (m).
    forces : ndarray, shape (n, 2)
        Contact forces on the nodes (N).
    strain : ndarray, shape (m,)
        Per element, the largest absolute principal value of the strain averaged over
        the critical-distance disc (dimensionless, m/m): SPEC §6's measure, whose maximum
        is compared with ``e_L`` (finite strain: SPEC §8's averaged stretch magnitude
        ``max |λᵢ − 1|``).
    pressure : ndarray, shape (n,)
        Contact pressure (Pa): normal force over the node's tributary boundary length
        times the thickness (:func:`deformclosure.fields.state_data`).
    energy : float
        Grasp energy (J).
    force : float
        The pads' axial force (N).
    """

    sigma: float
    delta: float
    displacement: np.ndarray
    translation: float
    forces: np.ndarray
    strain: np.ndarray
    pressure: np.ndarray
    energy: float
    force: float


def curve_state(solver, curve, sigma: float, ell: float) -> PadState:
    """The state of one grasp curve (a :class:`~deformclosure.pads.contact.GraspCurve` on
    ``solver``) at separation ``sigma`` (m), strains averaged over ``ell`` (m)."""
    from ..fields import FieldState, state_data

    mesh = solver.mesh
    n = mesh.n_nodes
    forces = np.zeros((n, 2))
    path = curve.path
    if path is None:
        u, t, delta = np.zeros(2 * n), 0.0, 0.0
    else:
        delta, t = _path_motion(curve, sigma)
        lam = path.multipliers(delta)
        np.add.at(forces, curve.nodes, lam[:, None] * curve.normals)
        u = solver.displacement(solver.load_vector(curve, lam))
    point, cell = state_data(mesh, FieldState("picture", u, forces), ell)
    strain = np.asarray(cell["strain_magnitude_averaged"], float).reshape(-1)
    return PadState(float(sigma), delta, np.asarray(u, float).reshape(n, 2), t, forces,
                    strain, np.asarray(point["contact_pressure"], float).reshape(-1),
                    float(curve.energy_at(sigma)), float(curve.axial_force(sigma)))


def pad_state(result, sigma: float | None = None) -> PadState:
    """The state of ``result`` on its start axis at ``sigma`` (m; default σ*, or first
    touch when ``Q ≡ 0``): a PadGraspResult's linear state, or a FiniteStrainResult's
    finite-strain one (:func:`finite_strain_state`)."""
    if sigma is None:
        sigma = result.sigma_star if result.sigma_star is not None else result.sigma0
    if elasticity_of(result) is not None:
        return finite_strain_state(result, sigma)
    return curve_state(result.solver, result.start_curve, sigma,
                       result.limit.critical_distance)


def elasticity_of(result) -> str | None:
    """``"neo-hookean"`` (or ``"linear"``: the small-strain law with the exact gap) for
    a finite-strain result (SPEC §8,
    :class:`~deformclosure.pads.finite_strain_grasp.FiniteStrainResult`), ``None`` for
    the linear pads model's."""
    from ..pads.finite_strain_grasp import FiniteStrainResult

    return result.elasticity if isinstance(result, FiniteStrainResult) else None


#: How a finite-strain run's pictures name its model.
MODEL_NAMES = {"neo-hookean": "neo-Hookean", "linear": "linear law, exact gap"}


def finite_strain_state(result, sigma: float) -> PadState:
    """The finite-strain state (SPEC §8) of ``result`` (a FiniteStrainResult) at
    ``sigma`` (m): its displacements and contact forces
    (:meth:`~deformclosure.pads.finite_strain_grasp.FiniteStrainResult.state_at`), the
    strain measure it compares with ``e_L`` per element
    (:meth:`~deformclosure.pads.large_deformation.FiniteStrainCurve.strain_field`), and
    the pads where that model puts them (their faces,
    :meth:`~deformclosure.pads.large_deformation.FiniteStrainCurve.faces_at`), expressed
    as :class:`PadState`'s squeeze and translation."""
    from ..fields import state_data

    c = result.start_curve
    ell = result.limit.critical_distance
    mesh = result.solver.mesh
    n = mesh.n_nodes
    fs = result.state_at(sigma, "picture")
    forces = np.asarray(fs.forces, float).reshape(n, 2)
    delta, t = 0.0, 0.0
    if c.touch is not None:
        d = float(c.delta(sigma))
        if d > c.delta0:
            z_a, z_b = c.faces_at(d)
            # A's face at touch.z_a − t, B's at touch.z_b − δ − t (draw_state's frame)
            t = c.touch.z_a - z_a
            delta = c.touch.z_b - z_b - t
    point, _ = state_data(mesh, fs, ell)
    return PadState(float(sigma), delta, np.asarray(fs.displacement, float).reshape(n, 2), t,
                    forces, np.asarray(c.strain_field(sigma, ell), float),
                    np.asarray(point["contact_pressure"], float).reshape(-1),
                    float(c.energy_at(sigma)), float(c.axial_force(sigma)))


def _model_tag(result) -> str:
    """``"neo-Hookean: "`` and the like before a finite-strain run's titles, else ``""``."""
    e = elasticity_of(result)
    return "" if e is None else f"{MODEL_NAMES.get(e, e)}: "


def _pads_at(curve, pad, delta: float, t: float, depth: float) -> tuple[np.ndarray, np.ndarray]:
    """Outlines (m, :func:`~deformclosure.pads.geometry.pad_pair`) of the pads of
    ``curve`` at squeeze ``delta`` and part translation ``t`` (m), the contact path's
    frame: A's face at ``z_a − t``, B's at ``z_b − δ − t``."""
    touch = curve.touch
    return pad_pair(pad, curve.axis, touch, touch.z_a - t, touch.z_b - delta - t, depth)


def _pad_depth(result) -> float:
    """How far (m) the drawn pads reach behind their faces: the geometry's stub
    (:func:`~deformclosure.pads.geometry.pad_depth`), at most 5 % of the part's size, so
    that the frame holding them stays on the part."""
    touch = result.start_curve.touch
    if touch is None:
        return 0.0
    return min(pad_depth(result.pad, touch), 0.05 * result.solver.mesh.diameter)


def _frame(ax, pts: np.ndarray, margin: float = 0.04) -> None:
    """Axes limits on the points ``pts`` (plot units) with ``margin`` of their span, equal
    aspect: the frame fits the part, not the lines drawn across it."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = margin * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal", adjustable="box")


def _strain_label(result, units: str) -> str:
    s = 1.0 / length_scale(units)
    what = ("averaged strain magnitude" if elasticity_of(result) in (None, "linear")
            else "averaged stretch magnitude max|λ−1|")
    return f"{what} (m/m)\nover ℓ = {result.limit.critical_distance * s:.3g} {units}"


def draw_state(ax, mesh, curve, pad, state: PadState, units: str = "mm", scale: float = 1.0,
               depth: float | None = None, norm=None, cmap: str = "viridis",
               pressure: bool = True, rest: bool = True):
    """Draw the deformed part of ``state`` (displacements × ``scale``) coloured by its
    averaged strain, the rest outline dashed, the pads and (``pressure``) the contact
    pressure as arrows into the boundary. Returns the colour mapping (for a colour bar)
    and the points (plot units) the frame should hold: the deformed part and the pads."""
    import matplotlib.tri as mtri

    s = 1.0 / length_scale(units)
    xy = (mesh.nodes + scale * state.displacement) * s
    tri = mtri.Triangulation(xy[:, 0], xy[:, 1], mesh.triangles)
    pc = ax.tripcolor(tri, facecolors=state.strain, cmap=cmap, norm=norm, edgecolors="face",
                      linewidth=0.0, zorder=1)
    pc.set_rasterized(True)      # SVG/PDF: the thousands of coloured triangles as one image
    for i, lp in enumerate(mesh.loops):
        ring = np.append(lp, lp[0])
        if rest:
            ax.plot(mesh.nodes[ring, 0] * s, mesh.nodes[ring, 1] * s, color="0.45", lw=0.8,
                    ls="--", zorder=2, label="part at rest" if i == 0 else None)
        ax.plot(xy[ring, 0], xy[ring, 1], color="k", lw=1.0, zorder=3)
    if depth is None:
        depth = pad_depth(pad, curve.touch) if curve.touch is not None else 0.0
    pts = [xy]
    if curve.touch is not None:
        for k, P in enumerate(_pads_at(curve, pad, scale * state.delta,
                                       scale * state.translation, depth)):
            ax.fill(P[:, 0] * s, P[:, 1] * s, color="0.35", alpha=0.75, lw=0, zorder=4,
                    label="pads" if k == 0 else None)
            pts.append(P * s)
    if pressure:
        _draw_pressure(ax, mesh, xy, state, s)
    return pc, np.vstack(pts)


#: Most pressure arrows drawn: on a fine mesh every ``k``-th pressed node along the
#: boundary (the most pressed one always), so the arrows stay readable.
MAX_PRESSURE_ARROWS = 24


def pressure_nodes(mesh, pressure: np.ndarray, most: int = MAX_PRESSURE_ARROWS) -> np.ndarray:
    """The pressed nodes (``pressure > 0``) whose arrows are drawn: all of them, or — more
    than ``most`` — evenly many along the boundary loops, the most pressed included."""
    on = np.flatnonzero(pressure > 0)
    if len(on) <= most:
        return on
    order = np.concatenate(mesh.loops)
    rank = np.full(mesh.n_nodes, len(order))
    rank[order] = np.arange(len(order))
    along = on[np.argsort(rank[on], kind="stable")]
    pick = along[np.linspace(0, len(along) - 1, most - 1).round().astype(int)]
    return np.union1d(pick, [on[np.argmax(pressure[on])]])


def _draw_pressure(ax, mesh, xy: np.ndarray, state: PadState, s: float) -> None:
    """Contact pressure as arrows along the force on pressed nodes (at most
    :data:`MAX_PRESSURE_ARROWS`, :func:`pressure_nodes`), pointing at them, their lengths
    proportional to the pressure (the longest 7 % of the part's size)."""
    p = state.pressure
    on = pressure_nodes(mesh, p)
    if not len(on):
        return
    f = state.forces[on]
    d = f / np.linalg.norm(f, axis=1)[:, None]
    L = 0.07 * mesh.diameter * s * p[on] / p[on].max()
    tail = xy[on] - d * L[:, None]
    ax.quiver(tail[:, 0], tail[:, 1], d[:, 0] * L, d[:, 1] * L, angles="xy",
              scale_units="xy", scale=1, color="C3", width=0.004, zorder=6,
              label=f"contact pressure (max {_pressure_text(p.max())})")


def _pressure_text(p: float) -> str:
    for unit, f in (("GPa", 1e9), ("MPa", 1e6), ("kPa", 1e3)):
        if p >= f:
            return f"{p / f:.3g} {unit}"
    return f"{p:.3g} Pa"


def plot_pad_grasp(result, mesh=None, ax=None, units: str = "mm", scale: float = 1.0,
                   sigma: float | None = None):
    """The part deformed at σ* coloured by the critical-distance strain, the pads at σ*,
    the contact pressure along the boundary and the grip force (SPEC §6).

    Parameters
    ----------
    result : PadGraspResult or FiniteStrainResult
        A finite-strain result (SPEC §8) draws its own state (title names the model).
    mesh : Mesh, optional
        Unused: the picture draws the mesh ``result`` was solved on (``result.solver``).
    ax : matplotlib Axes, optional
    units : str
        Length unit of the axes.
    scale : float
        Displacements drawn ``scale`` times their size (1: true scale); the pads move
        with them.
    sigma : float, optional
        Separation (m); default σ* (first touch when ``Q ≡ 0``).

    Returns
    -------
    matplotlib.figure.Figure
        The figure holding ``ax``; the colour bar is labelled in the strain's units (m/m)
        and marks ``e_L``; the legend sits below the axes.
    """
    from matplotlib.colors import Normalize

    ax, s = figure_axes(ax, (6.5, 6.5), units)
    check_scale(scale)
    msh = result.solver.mesh
    st = pad_state(result, sigma)
    e_L = result.e_L
    top = max(float(st.strain.max()), e_L or 0.0, 1e-300)
    pc, xy = draw_state(ax, msh, result.start_curve, result.pad, st, units, scale,
                        _pad_depth(result), norm=Normalize(0.0, top))
    _frame(ax, np.vstack([xy, msh.nodes * s]))
    cb = side_colorbar(ax, pc, _strain_label(result, units)
                       + ("" if e_L is None else f"; red: $e_L$ = {e_L:g}"))
    if e_L is not None:
        cb.ax.axhline(e_L, color="C3", lw=2)
    ax.set_xlabel(f"x ({units})")
    ax.set_ylabel(f"y ({units})")
    how = "true scale" if scale == 1 else f"displacements × {scale:g}"
    at = "σ*" if sigma is None and result.sigma_star is not None else "σ"
    measure = ("strain" if elasticity_of(result) in (None, "linear")
               else "stretch max|λ−1|")        # SPEC §8's measure for the finite-strain law
    ax.set_title(f"{_model_tag(result)}{result.verdict}: {at} = {st.sigma * s:.4g} {units}, "
                 f"F = {st.force:.4g} N, "
                 f"Q* = {result.quality * 1e3:.4g} mJ\nmax averaged {measure} "
                 f"{st.strain.max():.3g}" + ("" if e_L is None else f" (e_L = {e_L:g})")
                 + f"; {how}", fontsize=9)
    legend_below(ax)
    return ax.figure


def check_scale(scale: float) -> float:
    """``--scale``: a finite number > 0; one line naming the option otherwise."""
    import math

    from ..errors import DeformClosureError

    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not math.isfinite(scale) \
            or scale <= 0:
        raise DeformClosureError(f"--scale = {scale!r}: give a number > 0 (1 = true scale)")
    return float(scale)


def plot_force_squeeze(result, ax=None, units: str = "mm"):
    """The pads' axial force ``F(σ)`` (N) from first touch ``σ0`` to the elastic limit
    ``σ_L``, with σ* (and ``F(σ*)``) and ``σ_L`` marked.

    Parameters
    ----------
    result : PadGraspResult or FiniteStrainResult
    ax : matplotlib Axes, optional
    units : str
        Length unit of σ.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ax, s = figure_axes(ax, (7, 4.5), units)
    c = result.curve
    sig, F = _nan(c["sigma"]) * s, _nan(c["F"])
    order = np.argsort(sig)
    ax.plot(sig[order], F[order], color="k", lw=1.4, label="$F(\\sigma)$, each pad")
    if result.sigma_star is not None:
        f = result.force
        ax.axvline(result.sigma_star * s, color="C3", ls="--", lw=1)
        ax.plot([result.sigma_star * s], [f], "o", color="C3",
                label=f"$\\sigma^*$ = {result.sigma_star * s:.4g} {units}: F = {f:.4g} N")
    ax.axvline(result.sigma_L * s, color="C1", ls=":", lw=1,
               label=f"$\\sigma_L$ = {result.sigma_L * s:.4g} {units} (elastic limit)")
    ax.axvline(result.sigma0 * s, color="0.5", ls="-.", lw=0.8,
               label=f"$\\sigma_0$ = {result.sigma0 * s:.4g} {units} (first touch)")
    ax.set_xlabel(f"pad separation σ ({units})")
    ax.set_ylabel("grip force F (N)")
    stiff = result.stiffness
    ax.set_title(f"{_model_tag(result)}force against squeeze" + ("" if stiff is None else
                                            f"; stiffness at σ* {stiff:.4g} N/m"))
    ax.grid(alpha=0.3)
    legend_outside(ax)
    return ax.figure


def _hole_of(mesh, curve) -> int | None:
    """The hole (index into ``mesh.hole_loops``) an expanding curve's pads open in."""
    if not curve.expanding or not len(curve.nodes):
        return None
    node = int(curve.nodes[0])
    return next((k for k, lp in enumerate(mesh.hole_loops) if node in set(lp.tolist())), None)


def path_indices(k: int, n: int, saddle: int | None = None) -> list[int]:
    """Up to ``n`` indices into a path of ``k`` points, evenly spread, always the start,
    the end and ``saddle`` (so at least those, even when ``n`` is smaller); sorted.

    Examples
    --------
    >>> path_indices(10, 4), path_indices(10, 3, saddle=4), path_indices(3, 8)
    ([0, 3, 6, 9], [0, 4, 9], [0, 1, 2])
    """
    if k <= 0:
        return []
    idx = set(np.linspace(0, k - 1, max(min(n, k), 1)).round().astype(int).tolist())
    keep = {0, k - 1} | ({int(saddle)} if saddle is not None else set())
    idx |= keep
    while len(idx) > max(n, len(keep)):      # keep the start, the end and the saddle
        rest = sorted(idx - keep)
        idx.discard(rest[len(rest) // 2])
    return sorted(idx)


def escape_states(result, n: int = 6) -> list[tuple[int, object, PadState]]:
    """Up to ``n`` axes of the escape path at σ* — the start, the saddle, the end and
    evenly between — each solved at σ*: ``(index on the path, curve, state)``. Of a
    finite-strain result, its linear twin's (the linear model found the path, SPEC §8)."""
    if elasticity_of(result) is not None:
        result = result.linear
    path = result.escape_path
    if not path or result.sigma_star is None:
        return []
    saddle = None
    if result.saddle is not None:
        saddle = next((i for i, a in enumerate(path) if np.isclose(a.angle, result.saddle.angle)
                       and np.isclose(a.offset, result.saddle.offset)), None)
    solver, pad, sig = result.solver, result.pad, result.sigma_star
    hole = _hole_of(solver.mesh, result.start_curve)
    out = []
    for i in path_indices(len(path), n, saddle):
        curve = solver.curve(path[i], pad, sig, hole)
        out.append((i, curve, curve_state(solver, curve, sig, result.limit.critical_distance)))
    return out


def plot_escape_strip(result, units: str = "mm", n: int = 6, scale: float = 1.0):
    """The escape path at σ* as a strip of small pictures: the part deformed on each of up
    to ``n`` axes along it (the start, the saddle — title in red —, the end), the pads,
    the grasp energy ``U`` (mJ) in each title, one strain colour scale for all. Of a
    finite-strain result, its linear twin's path at the linear σ*, and the title says so.

    Returns
    -------
    matplotlib.figure.Figure or None
        ``None`` when there is no escape path (no barrier, or ``U_A`` infinite).
    """
    from matplotlib.colors import Normalize

    from .mesh import new_figure

    model = elasticity_of(result)
    if model is not None:
        result = result.linear
    states = escape_states(result, n)
    if not states:
        return None
    check_scale(scale)
    s = 1.0 / length_scale(units)
    mesh = result.solver.mesh
    top = max(max(float(st.strain.max()) for _, _, st in states), 1e-300)
    norm = Normalize(0.0, top)
    span = np.ptp(mesh.nodes, axis=0)
    w = 2.6
    fig, _ = new_figure((w * len(states) + 1.2, min(max(w * span[1] / span[0], 1.0), 4.0) + 1.3))
    fig.clf()
    axes = fig.subplots(1, len(states), squeeze=False)[0]
    pts, pc = [], None
    sad = result.saddle
    for ax, (i, curve, st) in zip(axes, states):
        pc, xy = draw_state(ax, mesh, curve, result.pad, st, units, scale, _pad_depth(result),
                            norm=norm, pressure=False)
        pts.append(np.vstack([xy, mesh.nodes * s]))
        is_saddle = sad is not None and np.isclose(curve.axis.angle, sad.angle) \
            and np.isclose(curve.axis.offset, sad.offset)
        ax.set_title(f"{i + 1}/{len(result.escape_path)}: {np.degrees(curve.axis.angle) % 180:.0f}°, "
                     f"c = {_clean(curve.axis.offset, mesh.diameter) * s:.3g} {units}\n"
                     f"U = {st.energy * 1e3:.4g} mJ"
                     + (" (saddle)" if is_saddle else ""), fontsize=8,
                     color="C3" if is_saddle else "k")
        ax.set_xticks([])
        ax.set_yticks([])
    allp = np.vstack(pts)
    for ax in axes:
        _frame(ax, allp)
    cb = fig.colorbar(pc, ax=list(axes), shrink=0.8, pad=0.02)
    cb.set_label("averaged strain (m/m)", fontsize=8)
    twin = "" if model is None else (f"linear twin of the {MODEL_NAMES.get(model, model)} run "
                                     "(linear model's σ*, U, U_A): ")
    _title_above(fig, axes, f"{twin}escape path at σ* = {result.sigma_star * s:.4g} {units}: "
                 f"U_A = {_energy_text(result.U_A)} over the start's U = "
                 f"{states[0][2].energy * 1e3:.4g} mJ")
    return fig


def _clean(v: float, size: float) -> float:
    """A length for a title without floating-point dust (below 1e-6 of ``size``: 0)."""
    return 0.0 if abs(v) < 1e-6 * size else float(v)


def _energy_text(U: float) -> str:
    return "∞" if not np.isfinite(U) else f"{U * 1e3:.4g} mJ"


def plot_convergence(convergence: list[dict], ax=None, units: str = "mm", label: str = ""):
    """``Q*`` (mJ) and — when the rows have it — ``σ*`` (``units``) against the number of
    mesh nodes of each level of a refined run (the report's ``convergence`` rows: optimize,
    a verified plan row, check), on a log axis of nodes. Check's rows have ``U_A`` instead
    of ``σ*``; it is drawn in its place.

    Parameters
    ----------
    convergence : list of dict
        ``{"nodes", "quality", "sigma_star" | "U_A", ...}`` per level (SI, JSON form:
        ``None`` for none or infinite).
    ax : matplotlib Axes, optional
    units : str
    label : str
        Prefix of the legend entries (a plan draws one run per row).

    Returns
    -------
    matplotlib.figure.Figure
        Two y axes (left ``Q*``, right ``σ*``); the legend below.
    """
    ax, s = figure_axes(ax, (7, 4.5), units)
    n = np.array([r["nodes"] for r in convergence], float)
    Q = _nan([r.get("quality") for r in convergence]) * 1e3
    l1 = ax.plot(n, Q, "-o", color="C0", ms=4, label=f"{label}Q* (mJ)")
    if n.max() > 8 * n.min() or ax.get_xscale() == "log":   # decades of nodes: a log axis
        ax.set_xscale("log")
    ax.set_xlabel("mesh nodes")
    ax.set_ylabel("Q* (mJ)", color="C0")
    twin = getattr(ax, "_dc_twin", None) or ax.twinx()
    ax._dc_twin = twin
    if any("sigma_star" in r for r in convergence):
        y = _nan([r.get("sigma_star") for r in convergence]) * s
        l2 = twin.plot(n, y, "--s", color="C1", ms=4, label=f"{label}σ* ({units})")
        twin.set_ylabel(f"σ* ({units})", color="C1")
    else:
        y = _nan([r.get("U_A") for r in convergence]) * 1e3
        l2 = twin.plot(n, y, "--s", color="C1", ms=4, label=f"{label}U_A (mJ)")
        twin.set_ylabel("U_A (mJ)", color="C1")
    ax.grid(alpha=0.3)
    ax.set_title(f"convergence over {len(convergence)} mesh levels", fontsize=9)
    hs = ax.get_legend_handles_labels()
    ht = twin.get_legend_handles_labels()
    _ = l1, l2
    ax.legend(hs[0] + ht[0], hs[1] + ht[1], loc="upper center", bbox_to_anchor=(0.5, -0.16),
              ncol=2, fontsize=8, frameon=False)
    return ax.figure


def plot_pad_plan(plan, mesh, ax=None, units: str = "mm", n: int = 5):
    """The best ``n`` grasp axes of a pad plan on the part at rest: each axis as the chord
    between its rest contact points, ranked, verified rows solid and screened ones
    dashed (the grasps themselves, deformed at σ*, are :func:`plot_pad_top_grasps`)."""
    ax, s = figure_axes(ax, (6, 6), units)
    _outline(ax, mesh, s)
    for k, row in enumerate(plan.rows[:n]):
        if row["quality"] <= 0:
            break
        c = np.asarray(row["contacts"]) * s
        ax.plot(c[:, 0], c[:, 1], "-o" if row["verified"] else "--o", color=f"C{k % 10}",
                lw=1.5, ms=4, zorder=4,
                label=f"#{k + 1}: {np.degrees(row['angle']) % 180:.0f}°, Q* = "
                      f"{row['quality'] * 1e3:.3g} mJ ({row['verdict']})")
        ax.annotate(f"#{k + 1}", c.mean(axis=0), color=f"C{k % 10}", fontsize=8,
                    fontweight="bold", xytext=(3, 3), textcoords="offset points")
    _frame(ax, mesh.nodes * s)
    ax.set_xlabel(f"x ({units})")
    ax.set_ylabel(f"y ({units})")
    ax.set_title("best grasp axes (contact chords at rest; solid: verified)", fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        legend_outside(ax)
    return ax.figure


def _plan_cells(plan) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plan's grid as cell edges in angle (deg) and offset (m) and, per cell, the
    screened (lattice) quality (J; ``nan`` where the pads miss the part)."""
    g = plan.grid
    n_off = g.j_max - g.j_min + 1
    M = np.full((n_off, g.n_angles), np.nan)
    for r in plan.rows:
        i = int(round((r["angle"] - g.angle0) / g.d_angle)) % g.n_angles
        j = int(round((r["offset"] - g.offset0) / g.d_offset)) - g.j_min
        if 0 <= j < n_off:
            M[j, i] = r.get("lattice_quality", r["quality"])
    th = np.degrees(g.angle0 + (np.arange(g.n_angles + 1) - 0.5) * g.d_angle)
    c = g.offset0 + (np.arange(g.j_min, g.j_max + 2) - 0.5) * g.d_offset
    return th, c, M


def plot_pad_quality_map(plan, ax=None, units: str = "mm"):
    """Quality of every grasp axis over (angle θ, offset c from the area centroid): the
    screened (lattice) ``Q`` in mJ on a log colour scale
    (:func:`~deformclosure.plotting.grasp.quality_color_range` from the least positive
    ``Q``, at most four decades below the best), axes that cannot hold
    light grey, axes the pads miss white; the verified rows marked by their verdict
    (held, undecided, not held), the other candidates dotted, the plan's chosen axes
    (``top``) numbered. How far the colour stays high around a chosen axis is how much
    positioning error it tolerates.

    Returns
    -------
    matplotlib.figure.Figure
        Colour bar on the right, legend below the axes.
    """
    import matplotlib
    from matplotlib.colors import LogNorm

    from .grasp import quality_color_range

    ax, s = figure_axes(ax, (7.5, 6), units)
    th, c, M = _plan_cells(plan)
    rng = quality_color_range(M[np.isfinite(M)], percentile=0.0)   # every holding axis
    cmap = matplotlib.colormaps["magma"].with_extremes(under="0.85", bad="white")
    if rng is None:
        pc = ax.pcolormesh(th, c * s, np.where(np.isnan(M), np.nan, -1.0), cmap=cmap,
                           vmin=0.0, vmax=1.0, shading="flat")
        label = "quality Q (mJ): no axis holds"
    else:
        lo, hi = rng[0] * 1e3, rng[1] * 1e3
        Mc = np.where(M > 0, M * 1e3, np.where(np.isnan(M), np.nan, lo * 1e-3))
        pc = ax.pcolormesh(th, c * s, Mc, cmap=cmap, shading="flat",
                           norm=LogNorm(vmin=lo, vmax=hi))
        label = "screened quality Q (mJ, log scale)"
    ax.figure.colorbar(pc, ax=ax, label=label, extend="min", shrink=0.85)
    styles = {"held": ("*", "C2", 12), "undecided": ("D", "C1", 7), "not held": ("X", "C0", 8)}
    shown = set()
    for r in plan.rows:
        x, y = np.degrees(r["angle"]) % 180.0, r["offset"] * s
        if r["verified"]:
            m, col, ms = styles[r["verdict"]]
            lab = f"verified: {r['verdict']}"
            ax.plot([x], [y], m, color=col, mec="k", ms=ms, zorder=5,
                    label=None if lab in shown else lab)
            shown.add(lab)
        elif r["verdict"] == "candidate":
            ax.plot([x], [y], ".", color="c", ms=3, zorder=4,
                    label=None if "candidate" in shown else "candidate (screened, Q > 0)")
            shown.add("candidate")
    for k, r in enumerate(plan.held):
        ax.annotate(f"#{k + 1}", (np.degrees(r["angle"]) % 180.0, r["offset"] * s),
                    xytext=(6, 6), textcoords="offset points", fontsize=8, color="C2",
                    fontweight="bold", zorder=6)
    ax.set_xlim(th[0], th[-1])
    ax.set_ylim(c[0] * s, c[-1] * s)
    ax.set_xlabel("axis angle θ (deg)")
    ax.set_ylabel(f"axis offset c from the area centroid ({units})")
    ax.set_title(f"grasp axes: {len(plan.held)} held (#: chosen), "
                 f"{sum(r['verified'] for r in plan.rows)} verified", fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        legend_below(ax)
    return ax.figure


def _verified_results(plan) -> list[tuple[int, dict, object]]:
    """``(rank, row, result)`` of the verified rows whose result the plan keeps."""
    out = []
    for k, r in enumerate(plan.rows):
        if not r["verified"]:
            continue
        res = next((t for t in plan.top if np.isclose(t.axis.angle, r["angle"])
                    and np.isclose(t.axis.offset, r["offset"])), None)
        if res is not None and getattr(res, "solver", None) is not None:
            out.append((k, r, res if elasticity_of(res) is not None
                        else getattr(res, "linear", res)))
    return out


def plot_pad_top_grasps(plan, units: str = "mm", n: int = 4, scale: float = 1.0):
    """The best ``n`` verified grasps of a plan, each deformed at its σ* with the pads
    where they hold it and its averaged strain (one colour scale), a panel each.

    Returns
    -------
    matplotlib.figure.Figure or None
        ``None`` when no row was verified.
    """
    from matplotlib.colors import Normalize

    from .mesh import new_figure

    picks = [(k, r, res) for k, r, res in _verified_results(plan)
             if res.sigma_star is not None][:n]
    if not picks:
        return None
    check_scale(scale)
    s = 1.0 / length_scale(units)
    states = [pad_state(res) for _, _, res in picks]
    top = max(max(float(st.strain.max()) for st in states),
              max((res.e_L or 0.0) for _, _, res in picks), 1e-300)
    span = np.ptp(picks[0][2].solver.mesh.nodes, axis=0)
    w = 3.6
    fig, _ = new_figure((w * len(picks) + 1.2, min(max(w * span[1] / span[0], 1.2), 5.0) + 1.8))
    fig.clf()
    axes = fig.subplots(1, len(picks), squeeze=False)[0]
    pc = None
    for ax, (k, r, res), st in zip(axes, picks, states):
        msh = res.solver.mesh
        pc, xy = draw_state(ax, msh, res.start_curve, res.pad, st, units, scale,
                            _pad_depth(res), norm=Normalize(0.0, top))
        _frame(ax, np.vstack([xy, msh.nodes * s]))
        ax.set_title(f"#{k + 1} ({r['verdict']}): {np.degrees(r['angle']) % 180:.0f}°, "
                     f"c = {_clean(r['offset'], msh.diameter) * s:.3g} {units}\n"
                     f"σ* = {st.sigma * s:.4g} {units}, "
                     f"F = {st.force:.3g} N, Q* = {r['quality'] * 1e3:.3g} mJ", fontsize=8)
        ax.set_xlabel(f"x ({units})", fontsize=8)
    axes[0].set_ylabel(f"y ({units})", fontsize=8)
    cb = fig.colorbar(pc, ax=list(axes), shrink=0.8, pad=0.02)
    cb.set_label("averaged strain (m/m)", fontsize=8)
    _title_above(fig, axes, "best verified grasps, deformed at σ*"
                 + ("" if scale == 1 else f" (displacements × {scale:g})"))
    handles, labels = axes[0].get_legend_handles_labels()
    bottom = min(a.get_position().y0 for a in axes)
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.45, bottom),
               borderaxespad=4.0, ncol=3, fontsize=8, frameon=False)
    return fig


def plot_plan_convergence(plan, ax=None, units: str = "mm", n: int = 4):
    """``Q*`` (mJ, solid, left axis) and ``σ*`` (dashed, right axis) against the mesh
    nodes of the best ``n`` verified rows refined on several levels (their
    ``convergence`` rows), one colour per row; ``None`` without any."""
    runs = [(k, r) for k, r in enumerate(plan.rows)
            if r["verified"] and len(r.get("convergence") or ()) > 1][:n]
    if not runs:
        return None
    from matplotlib.lines import Line2D

    ax, s = figure_axes(ax, (7.5, 4.8), units)
    twin = ax.twinx()
    handles = []
    for c, (k, r) in enumerate(runs):
        conv = r["convergence"]
        nodes = np.array([v["nodes"] for v in conv], float)
        col = f"C{c % 10}"
        ax.plot(nodes, _nan([v.get("quality") for v in conv]) * 1e3, "-o", color=col, ms=4)
        twin.plot(nodes, _nan([v.get("sigma_star") for v in conv]) * s, "--s", color=col,
                  ms=3, alpha=0.8)
        handles.append(Line2D([], [], color=col, marker="o",
                              label=f"#{k + 1} ({r['verdict']}): {np.degrees(r['angle']) % 180:.0f}°, "
                                    f"c = {_clean(r['offset'], 1.0) * s:.3g} {units}"))
    handles += [Line2D([], [], color="k", ls="-", label="Q* (mJ, left)"),
                Line2D([], [], color="k", ls="--", label=f"σ* ({units}, right)")]
    ax.set_xlabel("mesh nodes")
    ax.set_ylabel("Q* (mJ)")
    twin.set_ylabel(f"σ* ({units})")
    ax.grid(alpha=0.3)
    ax.set_title(f"convergence of {len(runs)} verified grasps", fontsize=9)
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0), borderaxespad=4.5,
              ncol=2, fontsize=8, frameon=False)
    return ax.figure


def _title_above(fig, axes, text: str) -> None:
    """``text`` as the figure's title just above ``axes`` (equal-aspect panels shrink
    inside their slots, so ``suptitle``'s default place floats far above them)."""
    fig.canvas.draw()
    top = max(a.get_position().y1 for a in axes)
    fig.suptitle(text, fontsize=9, y=min(top + 0.16, 0.99), va="bottom")


def save_pad_plots(result, mesh, target: str | Path, units: str = "mm", scale: float = 1.0,
                   convergence: list | None = None) -> list[Path]:
    """Write the pictures of a pad grasp for ``--plot target``
    (:func:`~deformclosure.plotting.mesh.figure_path`): ``grasp`` (deformed at σ*),
    ``quality`` (``U``, ``U_A``, ``U_L``, ``Q`` against σ), ``force`` (``F(σ)``),
    ``escape`` (the escape path's strip, when there is one) and ``convergence`` (when
    ``convergence`` has several levels). A finite-strain result (SPEC §8) draws its own
    state, curves and force; the escape strip is its linear twin's, titled so. Returns
    the paths written."""
    from .mesh import new_figure

    check_scale(scale)
    figs = []
    fig, ax = new_figure((6.5, 6.5))
    figs.append(("grasp", plot_pad_grasp(result, mesh, ax=ax, units=units, scale=scale)))
    fig, ax = new_figure((7, 4.5))
    figs.append(("quality", plot_pad_quality(result, ax=ax, units=units)))
    fig, ax = new_figure((7, 4.5))
    figs.append(("force", plot_force_squeeze(result, ax=ax, units=units)))
    strip = plot_escape_strip(result, units=units, scale=scale)
    if strip is not None:
        figs.append(("escape", strip))
    if convergence is not None and len(convergence) > 1:
        fig, ax = new_figure((7, 4.5))
        figs.append(("convergence", plot_convergence(convergence, ax=ax, units=units)))
    return save_figures(figs, target)


def save_pad_plan_plots(plan, mesh, target: str | Path, units: str = "mm",
                        scale: float = 1.0) -> list[Path]:
    """Write the pictures of a pad plan for ``--plot target``: ``quality_map`` (θ, c),
    ``top_axes`` (chords on the part), ``top_grasps`` (the verified grasps deformed at σ*)
    and ``convergence`` (verified rows refined on several levels), the last two when
    there is something to draw. Returns the paths written."""
    from .mesh import new_figure

    check_scale(scale)
    figs = []
    fig, ax = new_figure((7.5, 6))
    figs.append(("quality_map", plot_pad_quality_map(plan, ax=ax, units=units)))
    fig, ax = new_figure((6, 6))
    figs.append(("top_axes", plot_pad_plan(plan, mesh, ax=ax, units=units)))
    tops = plot_pad_top_grasps(plan, units=units, scale=scale)
    if tops is not None:
        figs.append(("top_grasps", tops))
    fig, ax = new_figure((7.5, 4.8))
    conv = plot_plan_convergence(plan, ax=ax, units=units)
    if conv is not None:
        figs.append(("convergence", conv))
    else:
        import matplotlib.pyplot as plt

        plt.close(fig)
    return save_figures(figs, target)
