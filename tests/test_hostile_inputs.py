"""Hostile inputs get one line ``error: …`` and exit code 2, never a traceback (issue 11,
items 1–3), and the readers raise nothing but the package's own errors (fuzzed)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from deformclosure import DeformClosureError, Part
from deformclosure.dspace.fingers import fingers_from_dict
from deformclosure.mesh.io import mesh_from_dict
from deformclosure.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
RECT = ROOT / "examples" / "rectangle.json"
FINGERS = ROOT / "examples" / "fingers" / "rectangle.json"


def _rect_text(**replace) -> str:
    text = RECT.read_text()
    for a, b in replace.items():
        text = text.replace(a, b, 1)
    return text


def _write(tmp, name, data) -> str:
    p = tmp / name
    if isinstance(data, bytes):
        p.write_bytes(data)
    else:
        p.write_text(data)
    return str(p)


CASES = {
    "utf16 garbage": (lambda t: ["mesh", _write(t, "p.json", b"\xff\xfe")], "JSON"),
    "not utf-8": (lambda t: ["mesh", _write(t, "p.json", b"\x80{}")], "UTF-8"),
    "deep nesting": (lambda t: ["mesh", _write(t, "p.json", "[" * 100000 + "]" * 100000)], "nested"),
    "duplicate key": (lambda t: ["mesh", _write(t, "p.json", _rect_text(
        **{'"units": "mm"': '"units": "mm", "units": "m"'}))], "twice"),
    "5000-digit integer": (lambda t: ["mesh", _write(t, "p.json", _rect_text(
        **{"12,": "1" + "0" * 5000 + ","}))], "digits"),
    "400-digit integer": (lambda t: ["mesh", _write(t, "p.json", _rect_text(
        **{"12,": "1" + "0" * 400 + ","}))], "digits"),
    "NaN": (lambda t: ["mesh", _write(t, "p.json", _rect_text(**{"12,": "NaN,"}))], "finite"),
    "fifo": (lambda t: (os.mkfifo(t / "f.json"), ["mesh", str(t / "f.json")])[1], "regular file"),
    "obj zero-based": (lambda t: ["mesh", _write(t, "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")],
                       "count from 1"),
    "obj out of range": (lambda t: ["mesh", _write(t, "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")],
                         "nodes 0..2"),
    "finger radius true": (lambda t: ["check", str(RECT), "--fingers", _write(t, "f.json", json.dumps(
        {"units": "mm", "fingers": [{"type": "disc", "center": [0, 10], "radius": True}]}))], "number"),
    "finger string coordinate": (lambda t: ["check", str(RECT), "--fingers", _write(t, "f.json", json.dumps(
        {"units": "mm", "fingers": [{"type": "point", "at": ["0", 10]}]}))], "number"),
    "half-plane normal 1e308": (lambda t: ["check", str(RECT), "--fingers", _write(t, "f.json", json.dumps(
        {"units": "mm", "fingers": [{"type": "halfplane", "point": [0, 0], "normal": [1e308, 1e308]}]}))],
        "normal"),
    "eps 1e-300": (lambda t: ["optimize", str(RECT), "--model", "paper", "--at", "0,10", "12,10",
                              "--method", "approx", "--eps", "1e-300"], "eps"),
    "at 1e308": (lambda t: ["optimize", str(RECT), "--model", "paper", "--at", "1e308,1e308", "12,10"], "--at"),
    "units empty": (lambda t: ["optimize", str(RECT), "--at", "0,10", "12,10", "--units", ""], "--units"),
    "jaw width 1e308": (lambda t: ["optimize", str(RECT), "--model", "paper", "--at", "0,10", "12,10",
                                   "--jaw-width", "1e308"], "--jaw-width"),
    "pad radius 1e308": (lambda t: ["optimize", str(RECT), "--at", "0,10", "12,10",
                                    "--pad-radius", "1e308"], "--pad-radius"),
    "slice extent 1e300": (lambda t: ["slice", str(RECT), "--node", "5", "--fingers", str(FINGERS),
                                      "--extent=-1e300,1e300,-1e300,1e300"], "--extent"),
}


@pytest.mark.parametrize("name", list(CASES))
def test_hostile_input_is_one_line_exit_2(name, tmp_path):
    make, pattern = CASES[name]
    args = make(tmp_path)
    proc = subprocess.run([sys.executable, "-m", "deformclosure", *args], capture_output=True,
                          text=True, timeout=120, stdin=subprocess.DEVNULL)
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
    assert len(lines) == 1 and lines[0].startswith("error:"), proc.stderr
    assert pattern.lower() in lines[0].lower(), lines[0]


JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=8),
    lambda kids: st.lists(kids, max_size=4) | st.dictionaries(
        st.sampled_from(["units", "outer", "holes", "material", "mesh", "fingers", "type", "at",
                         "radius", "nodes", "triangles", "format", "center", "youngs_modulus",
                         "points", "x"]), kids, max_size=5),
    max_leaves=20)

VALID_PART = json.loads(RECT.read_text())


def _mutations():
    """A valid part with one field replaced by an arbitrary JSON value."""
    return st.tuples(st.sampled_from(["units", "outer", "holes", "material", "mesh", "name"]),
                     JSON).map(lambda kv: {**VALID_PART, kv[0]: kv[1]})


@settings(max_examples=150, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(st.one_of(JSON, _mutations()))
def test_readers_raise_only_their_own_errors(data):
    """Part, mesh, finger and job-list readers on arbitrary JSON: a value or a
    DeformClosureError, nothing else."""
    from deformclosure.batch.lists import _json_specs

    for reader in (Part.from_dict, mesh_from_dict, fingers_from_dict,
                   lambda d: _json_specs(Path("jobs.json"), json.dumps(d))):
        try:
            reader(data)
        except DeformClosureError:
            pass


@pytest.mark.parametrize("change,pattern", [
    (lambda d: d.update(units="m"), "units"),                              # a 12 x 20 m part
    (lambda d: d["material"].update(youngs_modulus=2), "pascals"),         # E = 2 Pa
])
def test_unit_sanity_warning(change, pattern, tmp_path):
    data = json.loads(RECT.read_text())
    change(data)
    p = _write(tmp_path, "p.json", json.dumps(data))
    proc = subprocess.run([sys.executable, "-m", "deformclosure", "mesh", p], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0
    warn = [ln for ln in proc.stderr.splitlines() if ln.startswith("warning:")]
    assert len(warn) == 1 and pattern in warn[0], proc.stderr


def test_unknown_key_names_the_nearest_one(tmp_path, capsys):
    data = json.loads(RECT.read_text())
    data["hole"] = data.pop("holes")
    assert main(["mesh", _write(tmp_path, "p.json", json.dumps(data))]) == 2
    assert "did you mean 'holes'" in capsys.readouterr().err


def test_report_on_stdout_is_pure_json_with_provenance(tmp_path):
    import hashlib

    proc = subprocess.run([sys.executable, "-m", "deformclosure", "optimize", str(RECT), "--model",
                           "paper", "--at", "0,10", "12,10", "-o", "-"], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0
    report = json.loads(proc.stdout)                 # nothing but the JSON on stdout
    assert "sigma0" in proc.stderr                   # the human summary went to stderr
    prov = report["provenance"]
    assert prov["inputs"] == [{"name": "rectangle.json",
                               "sha256": hashlib.sha256(RECT.read_bytes()).hexdigest()}]
