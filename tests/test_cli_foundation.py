"""The CLI of the foundation: ``--version``, ``--help``, ``demo``, ``mesh`` and bad input.

Every malformed file in ``tests/bad_inputs`` must give exactly one line on stderr,
starting with ``error:`` and naming the offending field, no traceback, and exit code 2.
The check runs in a subprocess (the real entry point, a fresh interpreter) for the
files listed in ``SUBPROCESS`` and in-process through ``main()`` for all of them.
"""

from __future__ import annotations

import atexit
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import deformclosure
from deformclosure import Part, mesh_part, read_mesh
from deformclosure.cli.main import main

BAD = Path(__file__).resolve().parent / "bad_inputs"

#: Every malformed file and a regular expression its error line must match (the field).
EXPECTED = {
    # part files: geometry
    "part_self_intersecting_outer.json": r"^error: outer: .*self-intersecting",
    "part_self_intersecting_hole.json": r"^error: holes\[0\]: .*self-intersecting",
    "part_hole_outside.json": r"^error: holes\[0\]: .*not strictly inside",
    "part_hole_crossing_outer.json": r"^error: holes\[0\]: .*not strictly inside",
    "part_overlapping_holes.json": r"^error: holes\[0\] and holes\[1\] overlap",
    "part_collinear_outer.json": r"^error: outer: ",
    "part_empty_outer.json": r"^error: outer: .*at least 3",
    "part_two_point_outer.json": r"^error: outer: .*at least 3",
    "part_three_coordinate_point.json": r"^error: outer: .*pair",
    "part_nan_coordinate.json": r"^error: outer\[1\]: .*not finite",
    "part_huge_coordinate.json": r"^error: outer\[2\]: .*larger than",
    "part_outer_string.json": r"^error: outer: ",
    # part files: material
    "part_poisson_half.json": r"^error: material\.poisson_ratio",
    "part_youngs_zero.json": r"^error: material\.youngs_modulus",
    "part_youngs_negative.json": r"^error: material\.youngs_modulus",
    "part_infinite_modulus.json": r"^error: material\.youngs_modulus",
    "part_thickness_negative.json": r"^error: material\.thickness",
    "part_elastic_limit_zero.json": r"^error: material\.elastic_limit_strain",
    "part_plane_unknown.json": r"^error: material\.plane",
    "part_material_missing.json": r"^error: material: .*missing",
    "part_string_for_number.json": r"^error: material\.youngs_modulus: .*number",
    "part_bool_for_number.json": r"^error: material\.thickness: .*number",
    "part_unknown_material_key.json": r"^error: material\.density: unknown key",
    # part files: top level, units, mesh options
    "part_unknown_unit.json": r"^error: units: unknown length unit 'furlong'",
    "part_units_number.json": r"^error: units: ",
    "part_unknown_key.json": r"^error: colour: unknown key",
    "part_max_area_tiny.json": r"^error: mesh\.max_area = 1e-09: .*triangles",
    "part_max_area_zero.json": r"^error: mesh\.max_area",
    "part_max_area_denormal.json": r"^error: mesh\.max_area = 1e-320",
    "part_min_angle_40.json": r"^error: mesh\.min_angle = 40",
    "part_point_outside.json": r"^error: mesh\.points\[1\]: .*outside",
    "part_point_in_hole.json": r"^error: mesh\.points\[0\]: .*outside",
    "part_invalid_syntax.json": r"^error: .*part_invalid_syntax\.json: not valid JSON .*line 2",
    "part_empty_file.json": r"^error: .*part_empty_file\.json: not valid JSON",
    "part_top_level_list.json": r"^error: part file: top level",
    # mesh files
    "mesh_inverted_triangle.json": r"^error: triangles\[1\]: inverted",
    "mesh_two_components.json": r"^error: triangles: mesh has 2 separate pieces",
    "mesh_nonmanifold_edge.json": r"^error: triangles: .*non-manifold edge",
    "mesh_nonmanifold_vertex.json": r"^error: triangles: .*touches itself at node 2",
    "mesh_degenerate_triangle.json": r"^error: triangles\[2\]: zero area",
    "mesh_node_id_out_of_range.json": r"^error: triangles: node ids must be in 0\.\.4",
    "mesh_float_triangle_ids.json": r"^error: triangles: .*integers",
    "mesh_unused_node.json": r"^error: nodes\[5\]: .*no triangle",
    "mesh_nan_node.json": r"^error: nodes\[1\]: .*not finite",
    "mesh_boundary_mismatch.json": r"^error: boundary\.outer: does not match",
    "mesh_boundary_not_a_list.json": r"^error: boundary: expected",
    "mesh_bad_material.json": r"^error: material\.poisson_ratio",
    "mesh_unknown_key.json": r"^error: comment: unknown key",
    "mesh_unknown_units.json": r"^error: units: unknown length unit 'parsec'",
    "mesh_garbage.vtk": r"^error: .*mesh_garbage\.vtk: meshio cannot read",
}

#: Files also checked through a fresh interpreter (one per kind of failure in issue 2).
SUBPROCESS = [
    "part_self_intersecting_outer.json", "part_hole_outside.json",
    "part_overlapping_holes.json", "part_nan_coordinate.json", "part_poisson_half.json",
    "part_youngs_zero.json", "part_unknown_unit.json", "part_two_point_outer.json",
    "part_string_for_number.json", "part_unknown_key.json", "part_max_area_tiny.json",
    "part_invalid_syntax.json", "part_min_angle_40.json", "part_point_outside.json",
    "mesh_inverted_triangle.json", "mesh_two_components.json", "mesh_nonmanifold_edge.json",
]


def _required_cases() -> dict[str, tuple[str, str, str]]:
    """Every required option of every command, each left out: ``{id: (command, input,
    flag)}`` — from the option table (``check``/``slice`` ``--fingers``, ``import -o``),
    and ``batch -o`` (a click option of its own)."""
    from deformclosure.reports.options import OPTIONS

    ex = Path(__file__).resolve().parents[1] / "examples"
    inputs = {"import": ex / "drawings" / "gasket.dxf", "batch": ex}
    cases = {f"{cmd} without {o.flags[-1]}": (cmd, str(inputs.get(cmd, ex / "rectangle.json")),
                                              o.flags[-1])
             for cmd, table in OPTIONS.items() for o in table if o.required}
    cases["batch without --output"] = ("batch", str(inputs["batch"]), "--output")
    return cases


#: Missing required options (issue 23: ``check part.json`` without ``--fingers`` was a
#: TypeError traceback): through a fresh interpreter, one usage line and exit code 2.
REQUIRED = _required_cases()


def _script() -> list[str]:
    """The installed ``deformclosure`` console script, else ``python -m deformclosure``."""
    exe = Path(sys.executable).with_name("deformclosure")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "deformclosure"]


def _start_background_runs():
    """Start every subprocess of this module, two at a time, in the background.

    Interpreter start-up (about 1 s each) dominates these checks; running them in the
    background while the rest of the suite runs keeps the suite fast. The tests that
    read the results are marked ``late`` (see conftest) so they run last.
    """
    tmp = Path(tempfile.mkdtemp(prefix="deformclosure-cli-"))
    atexit.register(shutil.rmtree, tmp, ignore_errors=True)
    env = dict(os.environ, MPLBACKEND="Agg", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    # The demo runs the whole pipeline: start it first.
    jobs = {
        "demo": _script() + ["demo", "--out", str(tmp / "demo")],
        "version": _script() + ["--version"],
        "help": _script() + ["--help"],
    }
    for name in SUBPROCESS:
        jobs[name] = [sys.executable, "-m", "deformclosure", "mesh", str(BAD / name),
                      "-o", str(tmp / f"{name}.out.json")]

    for name, (cmd, inp, _) in REQUIRED.items():
        jobs[name] = [sys.executable, "-m", "deformclosure", cmd, inp]

    def run(cmd):
        return subprocess.run(cmd, capture_output=True, text=True, cwd=tmp, env=env, timeout=900)

    pool = ThreadPoolExecutor(max_workers=2)
    futures = {k: pool.submit(run, cmd) for k, cmd in jobs.items()}
    pool.shutdown(wait=False)
    return tmp, futures


#: ``{"tmp": folder, "futures": {name: future}}`` once :func:`start_background_runs` ran.
_BACKGROUND: dict = {}


def start_background_runs() -> None:
    """Start the background subprocesses once; called by conftest at the end of
    collection when a ``late`` test of this module is selected. A run that deselects them
    all (``-m slow``) starts none: they cost ~30 s of CPU that no test would read."""
    if not _BACKGROUND:
        _BACKGROUND["tmp"], _BACKGROUND["futures"] = _start_background_runs()


@pytest.fixture(scope="module")
def runs():
    """Results of the background subprocesses (waits for them)."""
    start_background_runs()                     # already started unless a plugin skipped it
    results = {k: f.result() for k, f in _BACKGROUND["futures"].items()}
    results["tmp"] = _BACKGROUND["tmp"]
    return results


def _assert_one_error_line(stderr: str, pattern: str) -> None:
    assert "Traceback" not in stderr
    lines = stderr.splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith("error: ")
    assert re.search(pattern, lines[0]), lines[0]


# --------------------------------------------------------------------------- bad input
def test_every_bad_input_has_an_expectation():
    files = sorted(p.name for p in BAD.iterdir() if p.is_file())
    assert files == sorted(EXPECTED)
    assert len(files) >= 15
    assert set(SUBPROCESS) <= set(EXPECTED) and len(SUBPROCESS) >= 15


@pytest.mark.late
@pytest.mark.parametrize("name", SUBPROCESS)
def test_bad_input_subprocess(runs, name):
    proc = runs[name]
    assert proc.returncode == 2, proc.stderr
    _assert_one_error_line(proc.stderr, EXPECTED[name])
    assert proc.stdout == ""
    assert not (runs["tmp"] / f"{name}.out.json").exists()


@pytest.mark.late
@pytest.mark.parametrize("name", sorted(REQUIRED))
def test_a_missing_required_option_is_one_usage_line(runs, name):
    assert len(REQUIRED) >= 4 and "check without --fingers" in REQUIRED
    proc = runs[name]
    flag = REQUIRED[name][2]
    assert proc.returncode == 2, proc.stderr
    _assert_one_error_line(proc.stderr, rf"{flag}: required for |[Mm]issing option .*{flag}")
    assert proc.stdout == ""


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bad_input_in_process(capsys, tmp_path, name):
    out = tmp_path / "out.json"
    assert main(["mesh", str(BAD / name), "-o", str(out)]) == 2
    captured = capsys.readouterr()
    _assert_one_error_line(captured.err, EXPECTED[name])
    assert captured.out == ""
    assert not out.exists()


def test_missing_file(capsys, tmp_path):
    assert main(["mesh", str(tmp_path / "nope.json")]) == 2
    _assert_one_error_line(capsys.readouterr().err, r"nope\.json: cannot read")


def test_unknown_output_suffix(capsys, examples_dir, tmp_path):
    out = tmp_path / "mesh.unknown"
    assert main(["mesh", str(examples_dir / "rectangle.json"), "-o", str(out)]) == 2
    _assert_one_error_line(capsys.readouterr().err, r"mesh\.unknown: cannot write mesh file")


def test_mesh_json_to_stdout(capsys, examples_dir):
    assert main(["mesh", str(examples_dir / "rectangle.json"), "-o", "-"]) == 0
    out = capsys.readouterr().out
    data = json.loads(out[out.index("{"):])
    assert data["format"] == "deformclosure-mesh/1"


def test_max_area_override_on_a_mesh_file_is_refused(capsys):
    path = str(BAD / "mesh_two_components.json")
    assert main(["mesh", path, "--max-area", "1"]) == 2
    _assert_one_error_line(capsys.readouterr().err, r"^error: --max-area/--min-angle")


# --------------------------------------------------------------------------- commands
@pytest.mark.late
def test_version(runs):
    proc = runs["version"]
    assert proc.returncode == 0, proc.stderr
    assert deformclosure.__version__ in proc.stdout
    assert "deformclosure" in proc.stdout


@pytest.mark.late
def test_help(runs, capsys):
    proc = runs["help"]
    assert proc.returncode == 0, proc.stderr
    for word in ("demo", "mesh", "Usage", "--version"):
        assert word in proc.stdout
    assert main(["mesh", "--help"]) == 0
    out = capsys.readouterr().out
    for word in ("--max-area", "--min-angle", "--plot", "-o, --output"):
        assert word in out


@pytest.mark.late
def test_demo_writes_mesh_png(runs):
    proc = runs["demo"]
    assert proc.returncode == 0, proc.stderr
    png = runs["tmp"] / "demo" / "mesh.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size > 1000
    assert "mesh:" in proc.stdout


def test_mesh_command_writes_the_mesh_of_the_library(examples_dir, tmp_path, capsys):
    src = examples_dir / "plate_with_hole.json"
    out, plot = tmp_path / "mesh.json", tmp_path / "mesh.png"
    assert main(["mesh", str(src), "-o", str(out), "--plot", str(plot)]) == 0
    assert "nodes" in capsys.readouterr().out
    data = json.loads(out.read_text())
    assert data["format"] == "deformclosure-mesh/1" and data["units"] == "m"
    want = mesh_part(Part.from_file(src))
    got = read_mesh(out)
    np.testing.assert_array_equal(got.nodes, want.nodes)
    np.testing.assert_array_equal(got.triangles, want.triangles)
    assert got.material == want.material
    assert plot.read_bytes()[:4] == b"\x89PNG"
    # --max-area is in the part's units² (mm² here), --min-angle in degrees.
    fine = tmp_path / "fine.json"
    assert main(["mesh", str(src), "-o", str(fine), "--max-area", "0.5", "--min-angle", "32"]) == 0
    m = read_mesh(fine)
    assert m.areas.max() <= 0.5e-6 * (1 + 1e-9)
    assert m.min_angles().min() >= 32 - 1e-9
    assert m.n_triangles > got.n_triangles


def test_mesh_command_converts_a_meshio_file(plate_mesh, tmp_path, capsys):
    import meshio

    vtk, out = tmp_path / "in.vtk", tmp_path / "out.json"
    meshio.write_points_cells(vtk, plate_mesh.nodes, [("triangle", plate_mesh.triangles)])
    assert main(["mesh", str(vtk), "-o", str(out)]) == 0
    back = read_mesh(out)
    np.testing.assert_array_equal(back.nodes, plate_mesh.nodes)
    np.testing.assert_array_equal(back.triangles, plate_mesh.triangles)
