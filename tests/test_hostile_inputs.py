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
    # issue 23 item 3: finger and pad sizes against the part's size (23.3 mm across)
    "disc finger radius 1e-300": (lambda t: ["check", str(RECT), "--fingers", _fingers(t, 1e-300)],
                                  "fingers[0].radius"),
    "disc finger radius 1e-12 x the part": (lambda t: ["check", str(RECT), "--fingers",
                                                       _fingers(t, 1e-12 * 23.3)], "0.002 to 100"),
    "disc finger radius 1e6 x the part": (lambda t: ["check", str(RECT), "--fingers",
                                                     _fingers(t, 1e6 * 23.3)], "fingers[0].radius"),
    "pad radius 1e-300": (lambda t: ["optimize", str(RECT), "--at", "0,10", "12,10",
                                     "--pad-radius", "1e-300"], "--pad-radius"),
    "pad radius 1e-12 x the part (plan)": (lambda t: ["plan", str(RECT), "--pad-radius", "2.3e-11"],
                                           "1e-06 to 100"),
    "pad width 1e308 (plan)": (lambda t: ["plan", str(RECT), "--pad-width", "1e308"], "--pad-width"),
    "pad width -inf": (lambda t: ["optimize", str(RECT), "--at", "0,10", "12,10", "--pad-width",
                                  "-inf"], "--pad-width"),
    # a mesh file above the triangle limit is refused before it is validated
    "mesh file of 500k triangles": (lambda t: ["mesh", _big_mesh(t)], "400,000"),
    "optimize a mesh file of 500k triangles": (lambda t: ["optimize", _big_mesh(t), "--at",
                                                          "0,5", "10,5"], "400,000"),
    # an unknown picture format is one line listing the formats
    "plot x.unknownext": (lambda t: ["mesh", str(RECT), "--plot", str(t / "x.unknownext")], "png"),
    # material values out of range (issue 23 item 4: --material at 1e-300 and 1e308)
    **{f"material {k} = {v}": (lambda t, k=k, v=v: ["mesh", str(RECT), "--material",
                                                    _material(**{k: v})], f"material.{k}")
       for k, v in [("youngs_modulus", 1e-300), ("youngs_modulus", 1e308),
                    ("thickness", 1e-300), ("thickness", 1e308),
                    ("elastic_limit_strain", 1e-300), ("elastic_limit_strain", 1e308),
                    ("critical_distance", 1e308), ("poisson_ratio", 1e308)]},
}


def _fingers(tmp, radius_mm: float) -> str:
    return _write(tmp, "f.json", json.dumps({"units": "mm", "fingers": [
        {"type": "disc", "center": [-radius_mm, 10], "radius": radius_mm},
        {"type": "disc", "center": [14, 10], "radius": 2},
        {"type": "halfplane", "point": [6, 0], "normal": [0, 1]}]}))


def _material(**values) -> str:
    m = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1,
         "elastic_limit_strain": 0.8, "units": "mm", **values}
    return json.dumps(m)


def _big_mesh(tmp) -> str:
    """A mesh JSON of 2 × 500² = 500,000 triangles (above the 400,000 limit)."""
    p = tmp / "big.json"
    if not p.exists():
        import numpy as np

        n = 501
        i = np.arange(n - 1)
        I, J = np.meshgrid(i, i)
        a = (J * n + I).ravel()
        tris = np.vstack([np.column_stack([a, a + 1, a + n + 1]), np.column_stack([a, a + n + 1, a + n])])
        x, y = np.meshgrid(np.linspace(0, 10, n), np.linspace(0, 10, n))
        p.write_text(json.dumps({"format": "deformclosure-mesh/1", "units": "mm",
                                 "nodes": np.column_stack([x.ravel(), y.ravel()]).tolist(),
                                 "triangles": tris.tolist(), "material": json.loads(_material())}))
    return str(p)


# reading a 500k-triangle JSON file takes ~10 s before its size is refused
@pytest.mark.parametrize("name", [pytest.param(k, marks=pytest.mark.slow) if "500k" in k else k
                                  for k in CASES])
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


# --------------------------------------------------------------------------- drawings
# issue 23 item 4: hostile DXF and SVG drawings are one-line PartErrors, quickly.
def _svg(body: str, attrs: str = 'width="20mm" height="10mm" viewBox="0 0 20 10"',
         prolog: str = "") -> bytes:
    return (f'{prolog}<svg xmlns="http://www.w3.org/2000/svg" '
            f'xmlns:xlink="http://www.w3.org/1999/xlink" {attrs}>{body}</svg>').encode()


def _dxf(build) -> bytes:
    import io

    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    build(doc.modelspace())
    s = io.StringIO()
    doc.write(s)
    return s.getvalue().encode()


def _rect(msp):
    msp.add_lwpolyline([(0, 0), (20, 0), (20, 10), (0, 10)], close=True)


def _nested_blocks(msp, levels=7, fan=10):
    b = msp.doc.blocks.new("B0")
    b.add_line((0, 0), (1, 0))
    for i in range(1, levels + 1):
        b = msp.doc.blocks.new(f"B{i}")
        for _ in range(fan):
            b.add_blockref(f"B{i - 1}", (0, 0))
    msp.add_blockref(f"B{levels}", (0, 0))


def _self_block(msp):
    b = msp.doc.blocks.new("S")
    b.add_line((0, 0), (1, 0))
    b.add_blockref("S", (0, 0))
    msp.add_blockref("S", (0, 0))


def _many_lines(n: int) -> bytes:
    """A DXF whose one LINE entity is repeated ``n`` times (built as text: ezdxf would take
    a minute to make it)."""
    text = _dxf(lambda m: m.add_line((0, 0), (1, 0))).decode()
    head, sep, tail = text.partition("\n  0\nLINE\n")
    body, sep2, rest = tail.partition("\n  0\n")
    return (head + (sep + body) * n + sep2 + rest).encode()


_LAUGHS = ('<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY a "aaaaaaaaaa">'
           + "".join(f'<!ENTITY {chr(98 + i)} "' + f"&{chr(97 + i)};" * 10 + '">' for i in range(9))
           + "]>")

DRAWINGS = {
    # name: (file name, bytes or a function of tmp_path giving them, kwargs, words)
    "svg empty": ("a.svg", b"", {}, "not a readable SVG"),
    "svg binary": ("a.svg", bytes(range(256)) * 8, {}, "not a readable SVG"),
    "svg unknown encoding": ("a.svg", b'<?xml version="1.0" encoding="UTF-8X"?><svg '
                             b'xmlns="http://www.w3.org/2000/svg"><rect width="2" height="1"/></svg>',
                             {}, "unknown encoding"),        # found by the fuzz test
    "svg nan viewBox": ("a.svg", _svg('<rect width="20" height="10"/>',
                                      'width="20mm" height="10mm" viewBox="0 0 nan 10"'), {},
                        "not a finite number"),
    "svg nan in path": ("a.svg", _svg('<path d="M0 0 L nan 0 L 10 10 Z"/>'), {}, "not a finite"),
    "svg wrong namespace": ("a.svg", b'<svg xmlns="ttp://x"><rect width="2" height="1"/></svg>', {},
                            "namespace"),
    "svg no shapes": ("a.svg", _svg(""), {}, "no lines"),
    "svg unclosed": ("a.svg", _svg('<path d="M0 0 L 10 0 L 10 10"/>'), {}, "open outline"),
    "svg self-intersecting": ("a.svg", _svg('<path d="M0 0 L 10 10 L 10 0 L 0 10 Z"/>'), {},
                              "crosses itself"),
    "svg inf in path": ("a.svg", _svg('<path d="M0 0 L 1e400 0 L 10 10 Z"/>'), {}, "larger than"),
    "svg 1e308 transform": ("a.svg", _svg('<rect width="20" height="10" transform="scale(1e308)"/>'),
                            {}, "transform"),
    "svg 1e308 arc radius": ("a.svg", _svg('<path d="M0 0 A 1e308 1e308 0 0 1 10 0 L 10 10 Z"/>'),
                             {}, "larger than"),
    "svg 1e308 width": ("a.svg", _svg('<rect width="20" height="10"/>',
                                      'width="1e308mm" height="1e308mm" viewBox="0 0 20 10"'), {},
                        "width"),
    "svg overflow by nesting": ("a.svg", _svg('<g transform="scale(1e15)"><g transform="scale(1e15)">'
                                              '<rect width="1e15" height="1e15"/></g></g>'), {},
                                "larger than"),
    "svg billion laughs": ("a.svg", (_LAUGHS + '<svg xmlns="http://www.w3.org/2000/svg">'
                                     '<rect id="&j;" width="20" height="10"/></svg>').encode(), {},
                           "entity"),
    "svg deep nesting": ("a.svg", _svg("<g>" * 100_000 + "</g>" * 100_000), {}, "nest"),
    "svg use cycle": ("a.svg", _svg('<g id="a"><use xlink:href="#b"/></g><g id="b">'
                                    '<use xlink:href="#a"/></g>'), {}, "refers back"),
    "svg use fan-out": ("a.svg", _svg('<defs><rect id="r0" width="1" height="1"/>' + "".join(
        f'<g id="r{i + 1}">' + f'<use xlink:href="#r{i}"/>' * 10 + "</g>" for i in range(7))
        + '</defs><use xlink:href="#r7"/>'), {}, "50,000 SVG elements"),
    "svg a million sub-paths": ("a.svg", _svg('<path d="' + "M0 0 " * 1_000_000 + '"/>'), {},
                                "numbers of path data"),
    "svg 20k sub-paths": ("a.svg", _svg('<path d="' + "M0 0 L1 1 " * 20_000 + '"/>'), {}, "sub-paths"),
    "svg 60k elements": ("a.svg", _svg('<line x1="0" y1="0" x2="1" y2="0"/>' * 60_000), {},
                         "SVG elements"),
    "svg tolerance 1e-300": ("a.svg", _svg('<circle cx="5" cy="5" r="4"/>'), {"tolerance": 1e-300},
                             "--tolerance"),
    "svg tolerance 1e308": ("a.svg", _svg('<circle cx="5" cy="5" r="4"/>'), {"tolerance": 1e308},
                            "--tolerance"),
    "dxf empty": ("a.dxf", b"", {}, "not a readable DXF"),
    "dxf binary": ("a.dxf", bytes(range(256)) * 8, {}, "not a readable DXF"),
    "dxf truncated": ("a.dxf", lambda: _dxf(_rect)[:3000], {}, "not a readable DXF"),
    "dxf unclosed": ("a.dxf", lambda: _dxf(lambda m: m.add_lwpolyline([(0, 0), (20, 0), (20, 10)])),
                     {}, "open outline"),
    "dxf self-intersecting": ("a.dxf", lambda: _dxf(lambda m: m.add_lwpolyline(
        [(0, 0), (10, 10), (10, 0), (0, 10)], close=True)), {}, "crosses itself"),
    "dxf 1e308 vertex": ("a.dxf", lambda: _dxf(lambda m: m.add_lwpolyline(
        [(0, 0), (1e308, 0), (1e308, 1e308)], close=True)), {}, "larger than 1e+12"),
    "dxf nan vertex": ("a.dxf", lambda: _dxf(lambda m: m.add_lwpolyline(
        [(0, 0), (12345.5, 0), (20, 10)], close=True)).replace(b"12345.5", b"nan"), {},
        "non-finite"),
    "dxf circle radius 1e308": ("a.dxf", lambda: _dxf(lambda m: m.add_circle((0, 0), 1e308)), {},
                                "larger than"),
    "dxf circle radius 0": ("a.dxf", lambda: _dxf(lambda m: (_rect(m), m.add_circle((5, 5), 0))),
                            {}, "radius 0"),
    "dxf bulge nan": ("a.dxf", lambda: _dxf(lambda m: m.add_lwpolyline(
        [(0, 0, 0), (20, 0, 0.123), (20, 10, 0), (0, 10, 0)], format="xyb", close=True))
        .replace(b"0.123", b"nan"), {}, "bulge"),
    "dxf tolerance 1e-300": ("a.dxf", lambda: _dxf(lambda m: m.add_circle((0, 0), 5)),
                             {"tolerance": 1e-300}, "--tolerance"),
    "dxf spline tolerance 1e-300": ("a.dxf", lambda: _dxf(lambda m: m.add_spline(
        [(0, 0), (10, 5), (20, 0), (10, -5), (0, 0)])), {"tolerance": 1e-300}, "--tolerance"),
    "dxf 200k lines": ("a.dxf", lambda: _many_lines(200_000), {}, "DXF entities"),
    "dxf 1e7 entities by block fan-out": pytest.param(
        "a.dxf", lambda: _dxf(lambda m: _nested_blocks(m, 7, 10)), {}, "block references exploded",
        marks=pytest.mark.slow),                  # ~10 s: 50,000 entities exploded, then refused
    "dxf block holding itself": ("a.dxf", lambda: _dxf(_self_block), {}, "nest more than"),
}


@pytest.mark.parametrize("name", [pytest.param(k, marks=v.marks) if hasattr(v, "marks") else k
                                  for k, v in DRAWINGS.items()])
def test_hostile_drawing_is_one_line_part_error(name):
    import time

    from deformclosure.drawing import read_drawing
    from deformclosure.errors import PartError
    from deformclosure.jsonfile import Source

    case = DRAWINGS[name]
    fname, data, kw, words = case.values if hasattr(case, "values") else case
    data = data() if callable(data) else data
    t0 = time.perf_counter()
    with pytest.raises(PartError) as err:
        read_drawing(Source(fname, data), **kw)
    # bounded: each is refused from a count or a scan, not after the work
    assert time.perf_counter() - t0 < 15
    msg = str(err.value)
    assert "\n" not in msg and words.lower() in msg.lower(), msg


def test_zero_and_huge_stroke_widths_do_not_change_the_outline():
    """Strokes are paint, not geometry: the outline is the path's, whatever the width."""
    from deformclosure.drawing import read_drawing
    from deformclosure.jsonfile import Source

    for w in ("0", "1e308", "nan", "-5"):
        d = read_drawing(Source("a.svg", _svg(f'<rect width="20" height="10" stroke="black" '
                                              f'stroke-width="{w}"/>')))
        assert abs(shapely_area(d.outer) - 200.0) < 1e-9
    for w in (0.0, 1e308):                         # DXF polyline widths likewise
        d = read_drawing(Source("a.dxf", _dxf(lambda m: m.add_lwpolyline(
            [(0, 0), (20, 0), (20, 10), (0, 10)], close=True, dxfattribs={"const_width": w}))))
        assert abs(shapely_area(d.outer) - 200.0) < 1e-9


def shapely_area(ring) -> float:
    import shapely

    return float(shapely.Polygon(ring).area)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_a_drawing_never_reads_a_file_it_names(tmp_path):
    """External entities, an external DTD, <image>, <use> of another file, a DXF xref: each
    names a FIFO that would block whoever opened it; import must finish (exit 2 or 0)
    without opening one, and never put the named file's content into the part."""
    fifo = tmp_path / "named.fifo"
    os.mkfifo(fifo)
    uri = fifo.as_uri()
    rect = '<rect width="20" height="10"/>'
    cases = {
        "entity.svg": _svg(rect.replace("/>", ' id="&x;"/>'),
                           prolog=f'<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY x SYSTEM "{uri}">]>'),
        "param.svg": _svg(rect, prolog=f'<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY % p SYSTEM '
                                       f'"{uri}"> %p;]>'),
        "dtd.svg": _svg(rect, prolog=f'<?xml version="1.0"?><!DOCTYPE svg SYSTEM "{uri}">'),
        "image.svg": _svg(f'<image xlink:href="{uri}" width="5" height="5"/>{rect}'),
        "use.svg": _svg(f'<use xlink:href="{uri}#r"/>{rect}'),
        "style.svg": _svg(f"<style>@import url({uri});</style>{rect}"),
        "xref.dxf": _dxf(lambda m: (m.doc.blocks.new("X", dxfattribs={"flags": 4,
                                                                      "xref_path": str(fifo)}),
                                    _rect(m), m.add_blockref("X", (0, 0)))),
    }
    for name, data in cases.items():
        _write(tmp_path, name, data)
    # one interpreter imports every drawing (a blocked open would stop it: the timeout)
    script = (
        "import contextlib, io, json, sys\n"
        "from deformclosure.cli.main import main\n"
        "out = {}\n"
        "for name in sys.argv[2:]:\n"
        "    err = io.StringIO()\n"
        "    with contextlib.redirect_stderr(err):\n"
        "        rc = main(['import', name, '--material', sys.argv[1], '-o', name + '.json', '-q'])\n"
        "    out[name] = [rc, err.getvalue()]\n"
        "print(json.dumps(out))\n")
    mat = ('{"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1, '
           '"elastic_limit_strain": 0.8, "units": "mm"}')
    proc = subprocess.run([sys.executable, "-c", script, mat, *(str(tmp_path / n) for n in cases)],
                          capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr
    results = {Path(k).name: v for k, v in json.loads(proc.stdout).items()}
    assert sorted(results) == sorted(cases)
    for name, (rc, err) in results.items():
        assert "Traceback" not in err, (name, err)
        if name in ("entity.svg", "param.svg"):
            assert rc == 2 and "entity" in err, (name, err)
        else:
            assert rc == 0, (name, err)
            assert len(json.loads((tmp_path / f"{name}.json").read_text())["outer"]) == 4, name


def test_batch_over_a_folder_of_hostile_drawings(tmp_path, capsys):
    """A folder's drawings are jobs with their material files (which are no jobs of their
    own); a hostile drawing fails its job with the reader's one line, the rest run."""
    import shutil

    from deformclosure.batch import load_jobs

    gasket = ROOT / "examples" / "drawings"
    shutil.copy(gasket / "gasket.dxf", tmp_path / "gasket.dxf")
    for stem in ("gasket", "laughs", "truncated"):
        shutil.copy(gasket / "gasket.material.json", tmp_path / f"{stem}.material.json")
    (tmp_path / "laughs.svg").write_bytes((_LAUGHS + '<svg xmlns="http://www.w3.org/2000/svg">'
                                           '<rect id="&j;" width="20" height="10"/></svg>').encode())
    (tmp_path / "truncated.dxf").write_bytes((gasket / "gasket.dxf").read_bytes()[:3000])
    jobs = load_jobs(tmp_path, "mesh")
    assert sorted(Path(j.part).name for j in jobs) == ["gasket.dxf", "laughs.svg", "truncated.dxf"]
    db = str(tmp_path / "b.sqlite")
    rc = main(["batch", str(tmp_path), "-o", db, "--command", "mesh", "--scheduler", "inline", "-q"])
    assert rc == 1                                   # some jobs failed
    capsys.readouterr()
    assert main(["results", db]) == 0
    cap = capsys.readouterr()
    table = cap.out + cap.err
    # rows in the folder's order (the part column is cut to its width)
    gasket, laughs, truncated = table.splitlines()[1:4]
    rows = {"gasket.dxf": gasket, "laughs.svg": laughs, "truncated.dxf": truncated}
    assert " ok " in rows["gasket.dxf"]
    assert "failed" in rows["laughs.svg"] and "entity" in rows["laughs.svg"]
    assert "failed" in rows["truncated.dxf"] and "not a readable DXF" in rows["truncated.dxf"]


def test_ezdxf_structure_warnings_do_not_add_lines(tmp_path):
    """A damaged DXF that ezdxf reads with a logged warning ("DXF Structure Warning") still
    gives the CLI's output alone: nothing on stderr when it succeeds, one line when not."""
    gasket = (ROOT / "examples" / "drawings" / "gasket.dxf").read_bytes()
    mat = ('{"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1, '
           '"elastic_limit_strain": 0.8, "units": "mm"}')
    for data, rc in ((b"  0\nLINE\n" + gasket, 0),
                     (b"  0\nLINE\n" + gasket.replace(b"LWPOLYLINE", b"LWPOLYLINX", 1), None)):
        p = _write(tmp_path, "w.dxf", data)
        proc = subprocess.run([sys.executable, "-m", "deformclosure", "import", p, "--material",
                               mat, "-o", str(tmp_path / "p.json"), "-q"],
                              capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
        lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
        assert "DXF Structure" not in proc.stderr, proc.stderr
        if rc == 0:
            assert proc.returncode == 0 and not lines, proc.stderr
        else:
            assert proc.returncode == 2 and len(lines) == 1, proc.stderr
