"""``--export-fields FILE.pvd``: the ParaView series over the squeeze, read back with meshio
(issue 24, item 4): names, shapes, units, the tensors against Hooke's law written out in
the test, the pads on the deformed part, no NaN anywhere."""

from __future__ import annotations

import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np
import pytest

from deformclosure import Part, mesh_part, reports
from deformclosure.cli.main import main
from deformclosure.fields import TENSOR_COMPONENTS, series_sigmas
from deformclosure.mesh.io import read_mesh, write_mesh
from deformclosure.pads.geometry import GraspAxis, Pad

sys.path.insert(0, str(Path(__file__).parent))
from pad_reference import reference_pad_solution  # noqa: E402
from test_fields import _cst_strains  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
BAR = ROOT / "examples" / "notched_bar.json"
RECT = ROOT / "examples" / "rectangle.json"


def _hooke_3d(eps9: np.ndarray, E: float, nu: float) -> np.ndarray:
    """σ = λ tr(ε) I + 2μ ε of full 3 × 3 strains (rows of 9), isotropic 3-D law."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    tr = eps9[:, 0] + eps9[:, 4] + eps9[:, 8]
    return lam * tr[:, None] * np.eye(3).ravel()[None] + 2 * mu * eps9


def _frames(pvd: Path) -> list[dict]:
    root = ET.parse(pvd).getroot()
    assert root.get("type") == "Collection"
    return [dict(ds.attrib) for ds in root.iter("DataSet")]


@pytest.fixture(scope="module")
def series(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("series")
    rep = reports.run("optimize", str(BAR), {
        "at": ("15,0", "15,12"), "pad_radius": 2.0, "grid_angles": 8, "grid_offsets": 8,
        "refine": 1, "export_fields": str(tmp / "s.pvd"), "quiet": True})
    written = rep.save()
    return tmp / "s.pvd", rep, written


def test_the_collection_plays_the_squeeze_from_first_touch_to_sigma_L(series):
    pvd, rep, written = series
    assert [Path(w).name for w in written] == ["s.pvd", "s_series"]
    d = rep.data
    frames = _frames(pvd)
    parts = [f for f in frames if f["part"] == "0"]
    pads = [f for f in frames if f["part"] == "1"]
    assert len(parts) == len(pads) == len(series_sigmas(d["sigma0"], d["sigma_L"], d["sigma_star"]))
    t = np.array([float(f["timestep"]) for f in parts])
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)             # ParaView's play order
    assert t[-1] == pytest.approx(d["sigma0"] - d["sigma_L"], rel=1e-12)
    star = [f for f in parts if f["name"] == "sigma_star"]
    assert len(star) == 1
    assert float(star[0]["timestep"]) == pytest.approx(d["sigma0"] - d["sigma_star"], rel=1e-12)
    for f in frames:                                          # relative to the .pvd
        assert (pvd.parent / f["file"]).is_file()


def test_every_frame_reads_back_with_names_shapes_units(series):
    pvd, rep, _ = series
    d = rep.data
    mesh = mesh_part(Part.from_file(BAR))
    n, ne = mesh.n_nodes, len(mesh.triangles)
    fine = rep.result.finest
    for f in _frames(pvd):
        m = meshio.read(pvd.parent / f["file"])
        for arrays in (m.point_data, m.field_data):
            for k, v in arrays.items():
                assert np.all(np.isfinite(v)), k
        for k, v in m.cell_data.items():
            assert all(np.all(np.isfinite(b)) for b in v), k
        assert float(m.field_data["TimeValue"][0]) == float(f["timestep"])
        if f["part"] == "1":                     # the pads: two polygons, zero warp
            assert m.cells[0].type == "polygon" and len(m.cells[0].data) == 2
            assert np.all(m.point_data["displacement"] == 0)
            continue
        np.testing.assert_array_equal(m.points[:, :2], mesh.nodes)           # at rest
        assert {k: v.shape for k, v in m.point_data.items()} == {
            "displacement": (n, 3), "rest_position": (n, 3), "contact_force": (n, 3),
            "contact_pressure": (n,)}
        for k in ("strain", "stress"):
            assert m.cell_data[k][0].shape == (ne, 9)
        sigma = float(m.field_data["sigma"][0])
        assert d["sigma0"] - sigma == pytest.approx(float(f["timestep"]), abs=1e-15)
        assert float(m.field_data["critical_distance"][0]) == fine.limit.critical_distance
        # the result's own state at that separation
        state = fine.state_at(sigma, "x")
        np.testing.assert_array_equal(m.point_data["displacement"][:, :2],
                                      np.asarray(state.displacement).reshape(-1, 2))
    # ParaView's names of the tensor components, in the file
    first = pvd.parent / _frames(pvd)[0]["file"]
    tags = {da.get("Name"): da for da in ET.parse(first).getroot().iter("DataArray")}
    for k in ("strain", "stress"):
        assert [tags[k].get(f"ComponentName{i}") for i in range(9)] == list(TENSOR_COMPONENTS)


def test_sigma_star_frame_against_the_reference_and_hooke(series):
    """At σ*: strains of the independent full-stiffness solver, stress = C : ε by the 3-D
    law (plane stress: σ_zz = 0 fixes ε_zz), grip force in N, Clapeyron in J."""
    pvd, rep, _ = series
    d = rep.data
    f = [f for f in _frames(pvd) if f["name"] == "sigma_star" and f["part"] == "0"][0]
    m = meshio.read(pvd.parent / f["file"])
    mesh = mesh_part(Part.from_file(BAR))
    mat = mesh.material
    assert mat.plane == "stress"
    theta = d["axis"]["angle"]
    normal = np.array([-np.sin(theta), np.cos(theta)])
    ref = reference_pad_solution(mesh, theta, float(normal @ np.array(d["axis"]["point"])),
                                 d["pad"]["width"], d["pad"]["radius"], d["sigma_star"])
    eps = m.cell_data["strain"][0]
    eps_ref = _cst_strains(mesh.nodes, mesh.triangles, ref["u"])
    scale = np.abs(eps_ref).max()
    np.testing.assert_allclose(eps[:, [0, 4, 1]], eps_ref, rtol=0, atol=1e-6 * scale)
    np.testing.assert_array_equal(eps[:, 1], eps[:, 3])           # symmetric
    assert np.all(eps[:, [2, 5, 6, 7]] == 0)
    sig = m.cell_data["stress"][0]
    np.testing.assert_allclose(sig[:, 8], 0, atol=1e-9 * mat.youngs_modulus * scale)
    np.testing.assert_allclose(sig, _hooke_3d(eps, mat.youngs_modulus, mat.poisson_ratio),
                               rtol=0, atol=1e-9 * mat.youngs_modulus * scale)
    # contact forces (N): pad A's axial push is the grip force of the report
    fc = m.point_data["contact_force"][:, :2]
    push = fc @ np.array([np.cos(theta), np.sin(theta)])
    assert push[push > 0].sum() == pytest.approx(d["force"], rel=1e-9)
    u = m.point_data["displacement"][:, :2]
    assert 0.5 * float(np.sum(fc * u)) == pytest.approx(ref["energy"], rel=1e-6)


def test_the_pads_sit_on_the_deformed_part(series):
    """Every loaded node of a frame lies on its pad's face to first order in u (the
    model's linearised gap), and the pads' faces are ``σ`` apart."""
    pvd, rep, _ = series
    d = rep.data
    ax = GraspAxis.at(np.array(d["axis"]["point"]), d["axis"]["angle"])
    pad = Pad(d["pad"]["width"], d["pad"]["radius"])
    frames = _frames(pvd)
    for part, pads in zip(frames[::2], frames[1::2]):
        m, p = meshio.read(pvd.parent / part["file"]), meshio.read(pvd.parent / pads["file"])
        u = m.point_data["displacement"][:, :2]
        fc = m.point_data["contact_force"][:, :2]
        z = []
        for poly in p.cells[0].data:
            s, x = ax.coordinates(p.points[poly, :2])
            z.append(s[np.argmin(np.abs(x))])                 # the face centre (W = 0)
        assert z[1] - z[0] == pytest.approx(float(m.field_data["sigma"][0]), rel=1e-9)
        loaded = np.flatnonzero(np.linalg.norm(fc, axis=1) > 0)
        if not len(loaded):
            continue
        s, x = ax.coordinates(m.points[loaded, :2])
        dd, slope = pad.profile(x, capped=False)
        lin = dd + slope * (u[loaded] @ ax.normal)
        su = s + u[loaded] @ ax.direction
        side = np.where(fc[loaded] @ ax.direction > 0, 0, 1)
        res = np.where(side == 0, su - (z[0] - lin), su - (z[1] + lin))
        np.testing.assert_allclose(res, 0, atol=1e-9 * d["sigma0"])


def test_paper_series_is_linear_in_the_squeeze(tmp_path):
    """The paper model's field is linear in the squeeze: every frame's displacement over
    its time (the squeeze, m) is the same field; no pads file for point jaws."""
    out = tmp_path / "p.pvd"
    assert main(["optimize", str(RECT), "--model", "paper", "--at", "0,10", "12,10",
                 "--export-fields", str(out), "-q"]) == 0
    frames = _frames(out)
    assert {f["part"] for f in frames} == {"0"}
    per = []
    for f in frames[1:]:
        m = meshio.read(out.parent / f["file"])
        per.append(m.point_data["displacement"] / float(f["timestep"]))
    for p in per[1:]:
        np.testing.assert_allclose(p, per[0], rtol=1e-9, atol=1e-12 * np.abs(per[0]).max())
    assert np.all(meshio.read(out.parent / frames[0]["file"]).point_data["displacement"] == 0)


def test_slice_refuses_a_series(tmp_path, capsys):
    assert main(["slice", str(RECT), "--node", "5", "--fingers",
                 str(ROOT / "examples" / "fingers" / "rectangle.json"),
                 "--export-fields", str(tmp_path / "s.pvd")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --export-fields") and err.count("\n") == 1 and ".vtu" in err


def test_a_default_critical_distance_is_no_nan_and_reads_back(tmp_path):
    mesh = mesh_part(Part.from_file(RECT))
    assert mesh.material.critical_distance is None
    write_mesh(mesh, tmp_path / "m.vtu")
    m = meshio.read(tmp_path / "m.vtu")
    assert "critical_distance" not in m.cell_data
    assert all(np.all(np.isfinite(v[0])) for v in m.cell_data.values())
    assert read_mesh(tmp_path / "m.vtu").material == mesh.material
    part = json.loads(RECT.read_text())
    part["material"]["critical_distance"] = 0.5                  # in the part's units
    (tmp_path / "p.json").write_text(json.dumps(part))
    mesh2 = mesh_part(Part.from_file(tmp_path / "p.json"))
    write_mesh(mesh2, tmp_path / "m2.vtu")
    assert read_mesh(tmp_path / "m2.vtu").material == mesh2.material
