"""Imported meshes get units and a material (issue 11, item 2), the material survives a
meshio round trip, and every command has ``--quiet``/``--verbose`` (item 7)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure import DeformClosureError, mesh_part
from deformclosure.cli.main import cli, main
from deformclosure.mesh.io import read_mesh, write_mesh
from deformclosure.part import Material, Part, read_material

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

RECT = EXAMPLES / "rectangle.json"
RUBBER_MM = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1,
             "elastic_limit_strain": 0.8, "units": "mm"}


@pytest.fixture(scope="module")
def rect_mesh():
    return mesh_part(Part.from_file(RECT))


materials = st.builds(
    Material,
    youngs_modulus=st.floats(1e3, 1e12),
    poisson_ratio=st.floats(-0.99, 0.49),
    thickness=st.floats(1e-5, 1.0),
    elastic_limit_strain=st.floats(1e-4, 2.0),
    plane=st.sampled_from(["stress", "strain"]),
    critical_distance=st.one_of(st.none(), st.floats(0.0, 1e-2)),
)


@settings(max_examples=25, deadline=None)
@given(material=materials, suffix=st.sampled_from([".vtu", ".vtk", ".json"]))
def test_material_survives_a_round_trip(rect_mesh, tmp_path_factory, material, suffix):
    path = tmp_path_factory.mktemp("rt") / f"m{suffix}"
    assert write_mesh(rect_mesh.with_material(material), path)
    back = read_mesh(path)
    assert back.material == material
    np.testing.assert_array_equal(back.triangles, rect_mesh.triangles)
    np.testing.assert_allclose(back.nodes, rect_mesh.nodes, rtol=1e-10, atol=0)


def test_formats_without_cell_data_say_the_material_is_lost(rect_mesh, tmp_path):
    assert not write_mesh(rect_mesh, tmp_path / "m.obj")
    assert read_mesh(tmp_path / "m.obj").material is None


def test_a_mesh_cannot_mix_materials(rect_mesh, tmp_path):
    path = tmp_path / "m.vtu"
    write_mesh(rect_mesh, path)
    m = meshio.read(path)
    E = m.cell_data["youngs_modulus"][0]
    E[0] *= 2
    meshio.write(path, m)
    with pytest.raises(DeformClosureError, match="youngs_modulus.*differs"):
        read_mesh(path)


def test_read_material_sources(tmp_path):
    inline = read_material(json.dumps(RUBBER_MM))
    assert inline.thickness == pytest.approx(1e-3)
    # a part file: its material block in its own units (mm)
    assert read_material(str(RECT)) == Part.from_file(RECT).material
    # no units in the source: the command's
    no_units = {k: v for k, v in RUBBER_MM.items() if k != "units"}
    assert read_material(json.dumps(no_units), "cm").thickness == pytest.approx(1e-2)
    f = tmp_path / "mat.json"
    f.write_text(json.dumps(RUBBER_MM))
    assert read_material(str(f)) == inline
    for bad, words in (({**RUBBER_MM, "thicknes": 1}, "did you mean 'thickness'"),
                       ({**RUBBER_MM, "units": "furlong"}, "--material.units"),
                       ({**RUBBER_MM, "poisson_ratio": 0.5}, "--material.poisson_ratio")):
        with pytest.raises(DeformClosureError, match=words):
            read_material(json.dumps(bad))
    with pytest.raises(DeformClosureError, match="twice"):
        read_material('{"youngs_modulus": 1, "youngs_modulus": 2}')


def _quality(capsys, args) -> float:
    capsys.readouterr()
    assert main([*args, "-q", "-o", "-"]) == 0
    return json.loads(capsys.readouterr().out)["quality"]


def test_imported_mesh_with_units_and_material_gives_the_same_answer(rect_mesh, tmp_path, capsys):
    """The same mesh, three ways: mesh JSON with its material (reference); .obj in m with
    --material; .obj in mm with --units mm. Q* must agree to round-off."""
    ref = tmp_path / "ref.json"
    write_mesh(rect_mesh, ref)
    pts = np.column_stack([rect_mesh.nodes, np.zeros(rect_mesh.n_nodes)])
    meshio.write_points_cells(tmp_path / "m.obj", pts, [("triangle", rect_mesh.triangles)])
    meshio.write_points_cells(tmp_path / "mm.obj", pts * 1e3, [("triangle", rect_mesh.triangles)])
    axis = ["--axis", "0.006,0.01,0", "--pad-radius", "0.002"]
    q_ref = _quality(capsys, ["optimize", str(ref), *axis])
    assert q_ref > 0
    q_m = _quality(capsys, ["optimize", str(tmp_path / "m.obj"), *axis,
                            "--material", json.dumps(RUBBER_MM)])
    q_mm = _quality(capsys, ["optimize", str(tmp_path / "mm.obj"), "--axis", "6,10,0",
                             "--pad-radius", "2", "--units", "mm", "--material",
                             json.dumps({k: v for k, v in RUBBER_MM.items() if k != "units"})])
    assert q_m == pytest.approx(q_ref, rel=1e-9)
    assert q_mm == pytest.approx(q_ref, rel=1e-9)


def test_mesh_file_without_material_names_the_option(rect_mesh, tmp_path, capsys):
    write_mesh(rect_mesh, tmp_path / "m.obj")
    for args in (["optimize", str(tmp_path / "m.obj"), "--axis", "0.006,0.01,0"],
                 ["check", str(tmp_path / "m.obj"), "--fingers",
                  str(EXAMPLES / "fingers" / "rectangle.json")]):
        capsys.readouterr()
        assert main(args) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error:") and "--material" in err and "\n" not in err


def test_mesh_command_converts_with_material(rect_mesh, tmp_path, capsys):
    pts = np.column_stack([rect_mesh.nodes * 1e3, np.zeros(rect_mesh.n_nodes)])
    meshio.write_points_cells(tmp_path / "in.off", pts, [("triangle", rect_mesh.triangles)])
    out = tmp_path / "out.vtu"
    assert main(["mesh", str(tmp_path / "in.off"), "--units", "mm", "--material", str(RECT),
                 "-o", str(out)]) == 0
    back = read_mesh(out)
    assert back.material == Part.from_file(RECT).material
    np.testing.assert_allclose(back.nodes, rect_mesh.nodes, rtol=1e-12, atol=1e-15)
    capsys.readouterr()
    assert main(["mesh", str(out), "-o", str(tmp_path / "again.obj")]) == 0
    assert "cannot hold the material" in capsys.readouterr().err


# --------------------------------------------------------------------------- verbosity
@pytest.mark.parametrize("name", sorted(cli.commands))
def test_every_command_has_quiet_and_verbose(name):
    opts = {o for p in cli.commands[name].params for o in getattr(p, "opts", ())}
    assert {"--quiet", "-q", "--verbose", "-v"} <= opts


def test_quiet_prints_nothing_but_the_report(tmp_path, capsys):
    capsys.readouterr()
    assert main(["mesh", str(RECT), "--quiet", "-o", str(tmp_path / "m.json")]) == 0
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""
    assert (tmp_path / "m.json").exists()
    assert main(["mesh", str(RECT), "-q", "-o", "-"]) == 0
    assert json.loads(capsys.readouterr().out)["format"] == "deformclosure-mesh/1"


def test_verbose_logs_the_steps_with_times(capsys):
    capsys.readouterr()
    assert main(["optimize", str(EXAMPLES / "notched_bar.json"), "--at", "15,0", "15,12",
                 "--pad-radius", "2", "--grid-angles", "8", "--grid-offsets", "8", "-v"]) == 0
    err = capsys.readouterr().err
    steps = [ln for ln in err.splitlines() if ln.startswith("deformclosure: ")]
    assert any("factorised K" in ln for ln in steps)
    seconds = [float(ln.rsplit("[", 1)[1].split()[0]) for ln in steps if ln.endswith(" s]")]
    assert seconds and all(math.isfinite(s) and s >= 0 for s in seconds)
    # the handler is removed afterwards: a normal run logs nothing
    assert main(["mesh", str(RECT)]) == 0
    assert "deformclosure: " not in capsys.readouterr().err


def test_quiet_and_verbose_together_is_an_error(capsys):
    assert main(["mesh", str(RECT), "-q", "-v"]) == 2
    assert "--quiet/--verbose" in capsys.readouterr().err


def test_batch_jobs_on_imported_meshes_take_the_material(rect_mesh, tmp_path):
    """A job list names a .obj mesh and a material file: the file is an input of the job
    (hashed into its key, like --fingers); inline JSON is part of the options."""
    from deformclosure.batch import load_jobs, read_results, run_batch

    write_mesh(rect_mesh, tmp_path / "m.obj")
    (tmp_path / "rubber.json").write_text(json.dumps(RUBBER_MM))
    common = ["--axis", "0.006,0.01,0", "--pad-radius", "0.002", "--grid-angles", "8",
              "--grid-offsets", "8"]
    (tmp_path / "jobs.json").write_text(json.dumps([
        {"part": "m.obj", "command": "optimize", "options": [*common, "--material", "rubber.json"]},
        {"part": "m.obj", "command": "optimize",
         "options": [*common, "--material", json.dumps(RUBBER_MM)]}]))
    jobs = load_jobs(tmp_path / "jobs.json")
    assert [len(j.inputs) for j in jobs] == [1, 0]
    run_batch(jobs, tmp_path / "r.sqlite", workers=1)
    rows = read_results(tmp_path / "r.sqlite")
    assert [r["status"] for r in rows] == ["ok", "ok"]
    q = [json.loads(r["result"])["quality"] if isinstance(r["result"], str)
         else r["result"]["quality"] for r in rows]
    assert q[0] == pytest.approx(q[1], rel=1e-12)
    # the material file is hashed: changing it changes the first job's key only
    (tmp_path / "rubber.json").write_text(json.dumps({**RUBBER_MM, "youngs_modulus": 3e6}))
    again = load_jobs(tmp_path / "jobs.json")
    assert again[0].key != jobs[0].key and again[1].key == jobs[1].key


def test_results_to_stdout_with_dash(tmp_path, capsys):
    from deformclosure.batch import Job, run_batch

    run_batch([Job.from_spec(EXAMPLES / "rectangle.json", "mesh")], tmp_path / "r.sqlite",
              scheduler="inline", progress=False)
    capsys.readouterr()
    assert main(["results", str(tmp_path / "r.sqlite"), "--format", "json", "-o", "-"]) == 0
    out = capsys.readouterr()
    assert json.loads(out.out)[0]["status"] == "ok" and out.err == ""
