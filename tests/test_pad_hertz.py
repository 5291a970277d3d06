"""2-D Hertz check of the pad contact solver (SPEC §6): an elastic disc squeezed between
two rigid flat pads, in plane strain and in plane stress.

Each pad meets the disc as a cylinder on a flat (line contact). With ``P`` the force per
unit thickness (N/m) and ``E*`` the effective modulus (``E/(1 − ν²)`` in plane strain,
``E`` in plane stress; the pad is rigid), Hertz theory for line contact (Johnson,
*Contact Mechanics*, 1985, ch. 4–5) gives

    half-width        a    = sqrt(4 P R / (π E*))
    pressure          p(x) = (2 P / (π a)) sqrt(1 − x²/a²)          |x| ≤ a

and, for the whole disc, the approach of the two pads (derived below, as it is the
check of the solver's global compliance):

    δ = σ0 − σ = (2 P / (π E*)) (2 ln(4 R / a) − 1).

Derivation of δ (plane stress; plane strain is the same with E → E*, ν → ν/(1 − ν), and
ν drops out). Shortening of the loaded diameter = 2 × (column from the centre to a depth
b below a contact, a ≪ b ≪ R) + 2 × (column from depth b to the contact surface):

* disc under two diametral point loads (Flamant + the uniform tension P/(πR) that frees
  the rim, the Brazilian-test field): on the loaded diameter σ_xx = P/(πR),
  σ_yy = P/(πR) − (2P/π)(1/(R − y) + 1/(R + y)); ∫₀^{R−b} −(σ_yy − ν σ_xx)/E dy
  = (P/(πE)) (2 ln(2R/b) − (1 − ν));
* Hertz line contact, stresses on the axis (McEwen 1949; Johnson ch. 4): σ_z = −p0 a/√(a²+z²),
  σ_x = −(p0/a)((a²+2z²)/√(a²+z²) − 2z), p0 a = 2P/π; ∫₀^b −(σ_z − ν σ_x)/E dz
  = (P/(πE)) (2 ln(2b/a) − ν) for b ≫ a.

The sum is (P/(πE))(2 ln(4R/a) − 1) per contact, independent of b and of ν. Neglected
terms are of relative order (a/R)² (≤ 1.5 % here, and smaller relative to the log).

Measurements from the solver's piecewise-linear solution at two squeezes (a/R ≈ 0.06 and
0.12, inside Hertz's range of validity a ≪ R and small strain p0/E* = a/(2R) ≤ 6 %):

1. the half-width as the edge of the set of loaded nodes — bracketed by the last loaded and
   the first unloaded boundary node, so it is known to ± half a node spacing;
2. the half-width from the second moment of the nodal forces: for the elliptical pressure
   ∫x²p dx / ∫p dx = a²/4 exactly, so a_m = 2 sqrt(Σ fᵢ(xᵢ − x̄)² / Σ fᵢ) resolves a well below
   the node spacing;
3. the nodal forces against the Hertz pressure integrated over each node's tributary
   length (midpoint to midpoint), on the central nodes |x| < a/2;
4. the scaling a ∝ sqrt(P) between the two loads;
5. the pad approach δ against the formula above.

Mesh: the disc is a polygon whose vertices lie on the circle, 0.025 mm apart within 2 mm of
the two contact points (so a spans ≥ 20 boundary nodes and a facet is < 5 % of a; vertex
gaps to a flat pad are exactly the circle's) and up to 0.5 mm apart elsewhere, plus interior
points on half-rings around each contact point whose spacing grows by 10 % per ring, so the
triangles under the contact are as fine as the boundary there. (Refinement of the boundary
alone is not enough: with Triangle's own grading under 0.025 mm facets and max_area 1 mm²
the contact came out 4–7 % narrower than Hertz, a CST mesh being too stiff.)
"""

from __future__ import annotations

import numpy as np
import pytest

from deformclosure import Part, mesh_part
from deformclosure.pads.contact import PadContact
from deformclosure.pads.geometry import GraspAxis, Pad

MM = 1e-3
R_MM = 10.0                    # disc radius (mm)
R = R_MM * MM
E, NU, THICK = 2e6, 0.3, 1.0 * MM
H_FINE_MM = 0.025              # boundary node spacing near the contacts (mm)
PAD = Pad(width=8 * MM, radius=1 * MM)
AXIS = GraspAxis.at(np.zeros(2), 0.0)    # through the centre, closing along +x
SQUEEZES = (0.13 * MM, 0.43 * MM)        # pad approaches δ = σ0 − σ: a/R ≈ 0.06 and 0.12

# --------------------------------------------------------------------------- tolerances
# (1) Edge of the loaded set: the discrete patch edge lies between the last loaded node and
#     the first unloaded one, i.e. a = midpoint ± h/2 (h the local node spacing, 0.025 mm =
#     2–4 % of a); allowed on top: 1 % of a for the model error that (2) measures (a CST
#     mesh is too stiff, so its contact is narrower: −0.2 … −0.6 % measured).
EDGE_MODEL_TOL = 0.01
# (2) Second-moment half-width: no node-spacing quantisation (quadrature error O(h²/a²) <
#     0.2 %), so it sees the discretisation error (−0.2 … −0.6 % measured) and Hertz's
#     neglected O((a/R)²) ≤ 1.5 % geometry terms: 1.5 %.
MOMENT_TOL = 0.015
# (3) Nodal forces on the central nodes (|x| < a/2, 23–47 nodes per pad): each lumped
#     nodal force carries node-to-node scatter from the unstructured triangles under it
#     (−0.8 … +1.5 % measured), so 5 % per node (an under-refined interior, Triangle's
#     own grading, gives +11 … +13 %); their sum (the share of the load on the central
#     half, ≈ 60 % by Hertz) averages the scatter out: 1 % (0.0–0.3 % measured).
NODE_FORCE_TOL = 0.05
CENTRAL_SHARE_TOL = 0.01
# (4) a ∝ sqrt(P): the common discretisation bias largely cancels in the ratio (−0.3 %
#     measured); what is left is the difference of the bias and of the O((a/R)²) terms
#     between the two loads: 1 %.
SCALING_TOL = 0.01
# (5) Approach: the formula neglects terms O((a/R)²) relative to its O(1)–O(ln) terms, and
#     the mesh is slightly too stiff (δ −0.1 … −0.3 % measured, converging to the formula
#     under refinement of the interior): 1 %.
APPROACH_TOL = 0.01


def _effective_modulus(plane: str) -> float:
    return E / (1 - NU**2) if plane == "strain" else E


def _disc_outline() -> np.ndarray:
    """Vertices (mm) on the circle: H_FINE_MM apart within 0.2 rad of the contact points
    (±R, 0), then growing 0.3 mm per mm of arc to 0.5 mm; symmetric about both axes."""
    phi_fine, grow, h_max = 0.2, 0.3, 0.5
    q, p = [0.0], 0.0
    while True:
        h = min(H_FINE_MM + grow * max(p - phi_fine, 0.0) * R_MM, h_max)
        if p + 1.5 * h / R_MM > np.pi / 2:
            break
        p += h / R_MM
        q.append(p)
    q = np.append(q, np.pi / 2)
    half = np.concatenate([q, np.pi - q[-2::-1]])                 # 0 … π
    full = np.concatenate([half, 2 * np.pi - half[-2:0:-1]])      # 0 … 2π (open)
    return np.column_stack([R_MM * np.cos(full), R_MM * np.sin(full)])


def _refinement_points(r_max: float = 5.0, growth: float = 1.1) -> np.ndarray:
    """Interior points (mm) on half-rings about both contact points, spacing
    max(H_FINE_MM, 10 % of the ring radius), kept clear of the rim by 0.8 spacing."""
    pts = []
    r = H_FINE_MM
    while r < r_max:
        s = max(H_FINE_MM, r * (growth - 1))
        r += s
        th = np.linspace(-np.pi / 2, np.pi / 2, int(np.ceil(np.pi * r / s)) + 1)
        ring = np.column_stack([R_MM - r * np.cos(th), r * np.sin(th)])
        ring = ring[np.hypot(ring[:, 0], ring[:, 1]) < R_MM - 0.8 * s]
        pts += [ring, -ring]
    return np.concatenate(pts)


def _disc_mesh(plane: str):
    part = Part.from_dict({
        "name": "hertz-disc", "units": "mm",
        "outer": _disc_outline().tolist(), "holes": [],
        "material": {"youngs_modulus": E, "poisson_ratio": NU, "thickness": THICK / MM,
                     "elastic_limit_strain": 0.8, "plane": plane},
        "mesh": {"max_area": 0.5, "min_angle": 30,
                 "points": _refinement_points().tolist()},
    })
    return mesh_part(part)


def _patch(mesh, curve, sigma: float, pad: int) -> dict:
    """One pad's contact patch at ``sigma``: cross-axis positions ``x`` (m, sorted) of its
    candidate nodes, their compressive forces ``f`` (N) and the loaded mask."""
    sel = curve.pad_of == pad
    _, x = AXIS.coordinates(mesh.nodes[curve.nodes[sel]])
    F = curve.forces(sigma)[sel]
    push = 1.0 if pad == 0 else -1.0            # pad A pushes along +a, pad B along −a
    f = push * (F @ AXIS.direction)
    order = np.argsort(x)
    x, f, F = x[order], f[order], F[order]
    loaded = f > 1e-9 * f.max()
    return {"x": x, "f": f, "F": F, "loaded": loaded}


def _hertz_tributary(x: np.ndarray, P: float, a: float) -> np.ndarray:
    """Hertz force (N) on each node's tributary length (midpoints to neighbours)."""
    def cumulative(u):                          # ∫₀^u p dx per unit thickness (N/m)
        xi = np.clip(u / a, -1.0, 1.0)
        return (P / np.pi) * (xi * np.sqrt(1 - xi * xi) + np.arcsin(xi))
    mids = np.concatenate([[-np.inf], 0.5 * (x[1:] + x[:-1]), [np.inf]])
    return THICK * (cumulative(mids[1:]) - cumulative(mids[:-1]))


@pytest.fixture(scope="module", params=["strain", "stress"])
def squeezed_disc(request):
    """The disc's contact solution at both squeezes: a list of dicts per load."""
    plane = request.param
    mesh = _disc_mesh(plane)
    curve = PadContact(mesh).curve(AXIS, PAD, 2 * R - 1.05 * max(SQUEEZES))
    assert curve.sigma0 == pytest.approx(2 * R, rel=1e-12)   # vertices lie on the circle
    Es = _effective_modulus(plane)
    loads = []
    for delta in SQUEEZES:
        sigma = curve.sigma0 - delta
        Fax = curve.axial_force(sigma)
        P = Fax / THICK
        loads.append({
            "plane": plane, "delta": delta, "sigma": sigma, "axial_force": Fax, "P": P,
            "a_hertz": np.sqrt(4 * P * R / (np.pi * Es)), "Es": Es,
            "patches": [_patch(mesh, curve, sigma, pad) for pad in (0, 1)],
        })
    return loads


def _moment_half_width(patch) -> float:
    x, f = patch["x"], patch["f"]
    xm = (f * x).sum() / f.sum()
    return 2.0 * np.sqrt((f * (x - xm) ** 2).sum() / f.sum())


def test_setup_is_in_hertz_range(squeezed_disc):
    for L in squeezed_disc:
        a, P = L["a_hertz"], L["P"]
        assert 0.04 < a / R <= 0.125, f"{L['plane']}: a/R = {a / R:.3f} outside the test's range"
        for pad, p in enumerate(L["patches"]):
            x, f, lo = p["x"], p["f"], p["loaded"]
            # Equal and opposite pad forces, all axial (the flat's normal), compressive.
            assert f.sum() == pytest.approx(L["axial_force"], rel=1e-9)
            assert np.all(f >= -1e-12 * f.max())
            assert np.abs(p["F"] @ AXIS.normal).max() <= 1e-12 * f.max()
            # The patch lies on the flat and within the candidate set, resolved by ≥ 20
            # boundary nodes per half-width.
            assert np.abs(x[lo]).max() < PAD.width / 2
            assert not lo[0] and not lo[-1]
            n_half = lo.sum() / 2
            assert n_half >= 20, f"{L['plane']} pad {pad}: only {n_half:.0f} nodes per half-width"
            h = np.diff(x[lo]).max()
            assert h < 0.05 * a, (
                f"{L['plane']} pad {pad}: node spacing {h / MM:.4f} mm ≥ 5 % of a")


def test_half_width_edge_against_hertz(squeezed_disc):
    for L in squeezed_disc:
        aH = L["a_hertz"]
        for pad, p in enumerate(L["patches"]):
            x, lo = p["x"], p["loaded"]
            idx = np.flatnonzero(lo)
            # Both edges of the patch: (last loaded, first unloaded) node positions.
            for inner, outer in ((x[idx[-1]], x[idx[-1] + 1]), (-x[idx[0]], -x[idx[0] - 1])):
                a_mid, h = 0.5 * (inner + outer), outer - inner
                tol = 0.5 * h + EDGE_MODEL_TOL * aH
                assert abs(a_mid - aH) <= tol, (
                    f"{L['plane']}, δ = {L['delta'] / MM:.2f} mm, pad {pad}: contact edge "
                    f"{a_mid / MM:.4f} ± {0.5 * h / MM:.4f} mm (between nodes at "
                    f"{inner / MM:.4f} and {outer / MM:.4f} mm) vs Hertz a = {aH / MM:.4f} mm "
                    f"(P = {L['P']:.4g} N/m); tolerance h/2 + {EDGE_MODEL_TOL:.0%} a")


def test_half_width_moment_against_hertz(squeezed_disc):
    for L in squeezed_disc:
        aH = L["a_hertz"]
        for pad, p in enumerate(L["patches"]):
            am = _moment_half_width(p)
            assert am == pytest.approx(aH, rel=MOMENT_TOL), (
                f"{L['plane']}, δ = {L['delta'] / MM:.2f} mm, pad {pad}: second-moment "
                f"half-width {am / MM:.4f} mm vs Hertz {aH / MM:.4f} mm "
                f"({am / aH - 1:+.2%}; tolerance {MOMENT_TOL:.1%})")


def test_nodal_forces_against_hertz_pressure(squeezed_disc):
    for L in squeezed_disc:
        aH, P = L["a_hertz"], L["P"]
        for pad, p in enumerate(L["patches"]):
            x, f = p["x"], p["f"]
            fh = _hertz_tributary(x, P, aH)
            central = np.abs(x) < 0.5 * aH
            assert central.sum() >= 20
            rel = f[central] / fh[central] - 1
            worst = int(np.argmax(np.abs(rel)))
            assert np.abs(rel).max() <= NODE_FORCE_TOL, (
                f"{L['plane']}, δ = {L['delta'] / MM:.2f} mm, pad {pad}: nodal force at x = "
                f"{x[central][worst] / MM:.4f} mm is {f[central][worst]:.4e} N vs Hertz "
                f"{fh[central][worst]:.4e} N ({rel[worst]:+.2%}; tolerance {NODE_FORCE_TOL:.0%})")
            share, share_h = f[central].sum() / f.sum(), fh[central].sum() / fh.sum()
            assert share == pytest.approx(share_h, rel=CENTRAL_SHARE_TOL), (
                f"{L['plane']}, δ = {L['delta'] / MM:.2f} mm, pad {pad}: central half carries "
                f"{share:.4f} of the load vs Hertz {share_h:.4f} "
                f"(tolerance {CENTRAL_SHARE_TOL:.0%})")


def test_half_width_scales_as_sqrt_load(squeezed_disc):
    lo, hi = squeezed_disc
    for pad in (0, 1):
        ratio = _moment_half_width(hi["patches"][pad]) / _moment_half_width(lo["patches"][pad])
        expected = np.sqrt(hi["P"] / lo["P"])
        assert ratio == pytest.approx(expected, rel=SCALING_TOL), (
            f"{lo['plane']}, pad {pad}: a ratio {ratio:.4f} between P = {lo['P']:.4g} and "
            f"{hi['P']:.4g} N/m vs sqrt(P ratio) = {expected:.4f} "
            f"({ratio / expected - 1:+.2%}; tolerance {SCALING_TOL:.0%})")


def test_pad_approach_against_disc_formula(squeezed_disc):
    for L in squeezed_disc:
        P, aH, Es = L["P"], L["a_hertz"], L["Es"]
        predicted = 2 * P / (np.pi * Es) * (2 * np.log(4 * R / aH) - 1)
        assert L["delta"] == pytest.approx(predicted, rel=APPROACH_TOL), (
            f"{L['plane']}: approach {L['delta'] / MM:.5f} mm at P = {P:.4g} N/m vs "
            f"(2P/πE*)(2 ln(4R/a) − 1) = {predicted / MM:.5f} mm "
            f"({L['delta'] / predicted - 1:+.2%}; tolerance {APPROACH_TOL:.0%})")
