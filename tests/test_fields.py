"""``--export-fields``: the .vtu files ParaView opens hold the solver's state (issue 13,
item 2), checked against the independent full-stiffness pad solver and hand formulas."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from deformclosure import Part, mesh_part
from deformclosure.cli.main import main
from deformclosure.mesh.io import read_mesh

sys.path.insert(0, str(Path(__file__).parent))
from pad_reference import reference_pad_solution  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RECT = ROOT / "examples" / "rectangle.json"
BAR = ROOT / "examples" / "notched_bar.json"      # held by round pads in its notches


def _cst_strains(nodes: np.ndarray, tri: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Tensor strains [exx, eyy, exy] of linear triangles, from the shape-function
    gradients written out by hand (independent of the package)."""
    U = u.reshape(-1, 2)
    out = np.empty((len(tri), 3))
    for k, (i, j, m) in enumerate(tri):
        (x1, y1), (x2, y2), (x3, y3) = nodes[i], nodes[j], nodes[m]
        A2 = (x2 - x1) * (y3 - y1) - (x3 - x1) * (y2 - y1)
        b = np.array([y2 - y3, y3 - y1, y1 - y2]) / A2
        c = np.array([x3 - x2, x1 - x3, x2 - x1]) / A2
        ux, uy = U[[i, j, m], 0], U[[i, j, m], 1]
        out[k] = [b @ ux, c @ uy, 0.5 * (c @ ux + b @ uy)]
    return out


@pytest.fixture(scope="module")
def pad_export(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("fields")
    out, rep = tmp / "f.vtu", tmp / "r.json"
    assert main(["optimize", str(BAR), "--at", "15,0", "15,12", "--pad-radius", "2",
                 "--grid-angles", "8", "--grid-offsets", "8", "--refine", "1",
                 "--export-fields", str(out), "-o", str(rep), "-q"]) == 0
    return out, json.loads(rep.read_text())   # one mesh: the part's, rebuilt below


def test_pad_fields_match_the_full_stiffness_reference(pad_export):
    out, report = pad_export
    assert report["sigma_star"] is not None
    m = meshio.read(out)
    mesh = mesh_part(Part.from_file(BAR))
    n, ne = mesh.n_nodes, len(mesh.triangles)
    for name, shape in (("displacement", (n, 3)), ("rest_position", (n, 3)),
                        ("contact_force", (n, 3)), ("contact_pressure", (n,))):
        assert m.point_data[name].shape == shape
    for name, shape in (("strain", (ne, 9)), ("stress", (ne, 9)), ("strain_magnitude", (ne,)),
                        ("strain_magnitude_averaged", (ne,))):
        assert m.cell_data[name][0].shape == shape
    np.testing.assert_allclose(m.point_data["rest_position"][:, :2], mesh.nodes, rtol=0, atol=1e-15)
    # the file's points are the part at rest: Warp By Vector (scale 1) deforms it once
    u = m.point_data["displacement"][:, :2]
    np.testing.assert_allclose(m.points[:, :2], mesh.nodes, rtol=0, atol=1e-15)

    ax, pad = report["axis"], report["pad"]
    theta = ax["angle"]
    normal = np.array([-np.sin(theta), np.cos(theta)])
    ref = reference_pad_solution(mesh, theta, float(normal @ np.array(ax["point"])),
                                 pad["width"], pad["radius"], report["sigma_star"])
    # strains do not see the free axial translation of the reference: compare them
    eps_ref = _cst_strains(mesh.nodes, mesh.triangles, ref["u"])
    scale = np.abs(eps_ref).max()
    np.testing.assert_allclose(m.cell_data["strain"][0][:, [0, 4, 1]], eps_ref, rtol=0,
                               atol=1e-6 * scale)
    # contact forces: same nodes, same vectors
    f = m.point_data["contact_force"][:, :2]
    f_ref = np.zeros_like(f)
    for side in ("A", "B"):
        f_ref[np.asarray(ref[side]["nodes"], int)] = ref[side]["forces"]
    np.testing.assert_allclose(f, f_ref, rtol=0, atol=1e-6 * np.abs(f_ref).max())
    # work of the contact forces = twice the energy at σ* (Clapeyron)
    assert 0.5 * float(np.sum(f * u)) == pytest.approx(ref["energy"], rel=1e-6)
    # pressure = |f| / (tributary length × thickness) at a contact node, by hand
    i = int(np.argmax(np.linalg.norm(f, axis=1)))
    loop = mesh.outer_loop
    k = int(np.flatnonzero(loop == i)[0])
    prev, nxt = mesh.nodes[loop[k - 1]], mesh.nodes[loop[(k + 1) % len(loop)]]
    trib = 0.5 * (np.linalg.norm(mesh.nodes[i] - prev) + np.linalg.norm(nxt - mesh.nodes[i]))
    assert m.point_data["contact_pressure"][i] == pytest.approx(
        np.linalg.norm(f[i]) / (trib * mesh.material.thickness), rel=1e-12)


def test_the_sigma_L_file_and_the_material(pad_export):
    out, report = pad_export
    low = out.with_name("f_sigma_L.vtu")
    m = meshio.read(low)
    mag_avg = m.cell_data["strain_magnitude_averaged"][0]
    # at σ_L the averaged strain reaches e_L (SPEC §6 definition of σ_L)
    assert mag_avg.max() == pytest.approx(report["e_L"], rel=1e-6)
    assert m.cell_data["strain_magnitude"][0].max() >= mag_avg.max() * (1 - 1e-12)
    # the file reads back as a mesh with the part's material
    assert read_mesh(low).material == Part.from_file(BAR).material


def test_paper_fields_hand_values(tmp_path, capsys):
    out, rep = tmp_path / "p.vtu", tmp_path / "p.json"
    assert main(["optimize", str(RECT), "--model", "paper", "--at", "0,10", "12,10",
                 "--export-fields", str(out), "-o", str(rep), "-q"]) == 0
    report = json.loads(rep.read_text())
    m = meshio.read(out)
    f = m.point_data["contact_force"][:, :2]
    u = m.point_data["displacement"][:, :2]
    delta = report["sigma0"] - report["sigma_star"]
    # two jaw forces k01 δ along the jaw line, opposite
    jaw = np.flatnonzero(np.linalg.norm(f, axis=1) > 0)
    assert len(jaw) == 2
    np.testing.assert_allclose(np.linalg.norm(f[jaw], axis=1), report["k01"] * delta, rtol=1e-12)
    np.testing.assert_allclose(f[jaw].sum(axis=0), 0, atol=1e-12 * report["k01"] * delta)
    # Clapeyron: ½ f·u = ½ k01 δ² = U(σ*)
    assert 0.5 * float(np.sum(f * u)) == pytest.approx(0.5 * report["k01"] * delta**2, rel=1e-9)


def test_bad_field_file_is_refused_before_the_work(tmp_path, capsys):
    assert main(["optimize", str(RECT), "--axis", "6,10,0", "--export-fields",
                 str(tmp_path / "f.png")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --export-fields") and err.count("\n") == 1


@pytest.mark.slow
def test_check_fields_at_the_equilibrium(tmp_path):
    """Contact forces balance, and their work on the elastic displacement is twice the
    equilibrium energy of the report (Clapeyron); the strain of the file is that of the
    elastic displacement, independent of the rigid rotation that places the nodes."""
    out, rep = tmp_path / "c.vtu", tmp_path / "c.json"
    assert main(["check", str(ROOT / "examples" / "l_shape.json"), "--fingers",
                 str(ROOT / "examples" / "fingers" / "l_shape.json"), "--grid-steps", "16",
                 "--saddle-levels", "0", "--export-fields", str(out), "-o", str(rep), "-q"]) == 0
    report = json.loads(rep.read_text())
    m = meshio.read(out)
    f = m.point_data["contact_force"][:, :2]
    np.testing.assert_allclose(f.sum(axis=0), 0, atol=1e-9 * np.abs(f).max())
    mesh = read_mesh(out)                    # the file's own mesh: the part at rest
    rest = m.point_data["rest_position"][:, :2]
    np.testing.assert_array_equal(mesh.nodes, rest)
    eps = m.cell_data["strain"][0][:, [0, 4, 1]]
    assert np.abs(eps).max() > 0
    energy = report["energy"]
    # strain energy of the file's strains, by hand (CST): ½ Σ A t εᵀ D ε
    mat = mesh.material
    E, nu, t = mat.youngs_modulus, mat.poisson_ratio, mat.thickness
    if mat.plane == "strain":      # plane strain: E' = E/(1-ν²), ν' = ν/(1-ν)
        E, nu = E / (1 - nu**2), nu / (1 - nu)
    D = E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    tri = m.cells_dict["triangle"]
    a, b, c = rest[tri[:, 0]], rest[tri[:, 1]], rest[tri[:, 2]]
    area = 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1]))
    eng = eps * np.array([1, 1, 2])
    U = 0.5 * t * np.sum(area * np.einsum("ki,ij,kj->k", eng, D, eng))
    assert U == pytest.approx(energy, rel=1e-9)


def test_slice_fields_equal_the_slice_arrays(tmp_path):
    out, npz = tmp_path / "s.vtu", tmp_path / "s.npz"
    assert main(["slice", str(RECT), "--node", "5", "--fingers",
                 str(ROOT / "examples" / "fingers" / "rectangle.json"), "--resolution", "24",
                 "--export-fields", str(out), "-o", str(npz), "-q"]) == 0
    m, arrays = meshio.read(out), np.load(npz)
    np.testing.assert_array_equal(m.point_data["energy"], arrays["energy"].ravel())
    np.testing.assert_array_equal(m.point_data["d_free"].astype(bool), arrays["free"].ravel())
    X, Y = np.meshgrid(arrays["xs"], arrays["ys"])
    np.testing.assert_array_equal(m.points[:, 0], X.ravel())
    np.testing.assert_array_equal(m.points[:, 1], Y.ravel())
    assert m.cells_dict["quad"].shape == (23 * 23, 4)
