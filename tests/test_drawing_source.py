"""Drawings read from a :class:`~deformclosure.jsonfile.Source` (a file's name and bytes,
read once): the same part as from the file itself, messages naming the Source, and the
material file beside a drawing used only for a real path."""

from __future__ import annotations

from pathlib import Path

import ezdxf
import numpy as np
import pytest

from deformclosure import PartError
from deformclosure.drawing import is_drawing_file, material_file_beside, read_drawing
from deformclosure.jsonfile import Source
from deformclosure.part import part_from_drawing

ROOT = Path(__file__).resolve().parents[1]
GASKET = ROOT / "examples" / "drawings" / "gasket.dxf"
SIDE = GASKET.with_name("gasket.material.json")
RUBBER = ('{"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1, '
          '"elastic_limit_strain": 0.8}')

# A plate 40 × 20 mm (physical size, viewBox in user units) with a cubic-Bézier edge,
# a circular hole and a square hole drawn as a path.
SVG = """<?xml version="1.0" encoding="UTF-8"?>
<svg xmlns="http://www.w3.org/2000/svg" width="40mm" height="20mm" viewBox="0 0 80 40">
  <path id="outline" d="M 0 0 L 60 0 C 90 0 90 40 60 40 L 0 40 Z"/>
  <circle id="hole" cx="20" cy="20" r="8"/>
  <path id="slot" d="M 45 15 h 10 v 10 h -10 z"/>
</svg>
"""


def _same_part(a, b) -> None:
    assert (a.name, a.units) == (b.name, b.units)
    np.testing.assert_array_equal(a.outer, b.outer)
    assert len(a.holes) == len(b.holes)
    for h1, h2 in zip(a.holes, b.holes):
        np.testing.assert_array_equal(h1, h2)
    assert a.material == b.material
    assert a.mesh_options.max_area == b.mesh_options.max_area
    assert a.mesh_options.min_angle == b.mesh_options.min_angle


def test_dxf_source_gives_the_same_part_as_the_file():
    from_file = part_from_drawing(GASKET)                       # material file beside it
    src = Source(str(GASKET), GASKET.read_bytes())
    assert is_drawing_file(src)
    from_src = part_from_drawing(src, material_file=Source(str(SIDE), SIDE.read_bytes()))
    _same_part(from_file, from_src)
    assert len(from_file.holes) >= 1 and from_file.mesh_options.max_area is not None


def test_dxf_source_with_crlf_line_ends_reads_as_the_file_does(tmp_path):
    # readfile reads text with universal newlines: so must the bytes reader
    path = tmp_path / "gasket.dxf"
    path.write_bytes(GASKET.read_bytes().replace(b"\n", b"\r\n"))
    a = read_drawing(path)
    b = read_drawing(Source("crlf.dxf", path.read_bytes()))
    np.testing.assert_array_equal(a.outer, b.outer)
    assert a.units == b.units and len(a.holes) == len(b.holes)


def test_binary_dxf_source_reads_as_the_file_does(tmp_path):
    doc = ezdxf.new(units=4)
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (10, 0), (10, 6), (0, 6)], close=True)
    msp.add_circle((5, 3), 1.5)
    path = tmp_path / "binary.dxf"
    doc.saveas(path, fmt="bin")
    assert path.read_bytes().startswith(b"AutoCAD Binary DXF")
    a = read_drawing(path)
    b = read_drawing(Source("binary.dxf", path.read_bytes()))
    np.testing.assert_array_equal(a.outer, b.outer)
    np.testing.assert_array_equal(a.holes[0], b.holes[0])
    assert a.units == b.units == "mm"


def test_legacy_dxf_encoding_from_its_header(tmp_path):
    # An R2000 file in its code page (cp1252): layer names with accents decode as from disk.
    doc = ezdxf.new("R2000", units=4)
    doc.layers.add("Kontur_äöü")
    doc.modelspace().add_lwpolyline([(0, 0), (4, 0), (4, 3), (0, 3)], close=True,
                                    dxfattribs={"layer": "Kontur_äöü"})
    path = tmp_path / "legacy.dxf"
    doc.saveas(path, encoding="cp1252")
    assert "äöü".encode("cp1252") in path.read_bytes()
    a = read_drawing(path, layer="Kontur_äöü")
    b = read_drawing(Source("legacy.dxf", path.read_bytes()), layer="Kontur_äöü")
    np.testing.assert_array_equal(a.outer, b.outer)


def test_svg_source_gives_the_same_part_as_the_file(tmp_path):
    path = tmp_path / "plate.svg"
    path.write_text(SVG, encoding="utf-8")
    from_file = part_from_drawing(path, material=RUBBER)
    from_src = part_from_drawing(Source(str(path), SVG.encode()), material=RUBBER)
    _same_part(from_file, from_src)
    assert from_file.units == "mm" and len(from_file.holes) == 2
    # a Source's name need not exist anywhere: it only names the part and the messages
    other = part_from_drawing(Source("elsewhere/plate.svg", SVG.encode()), material=RUBBER)
    _same_part(from_file, other)


def test_material_file_beside_applies_to_a_path_only():
    assert material_file_beside(GASKET) == SIDE
    src = Source(str(GASKET), GASKET.read_bytes())
    assert material_file_beside(src) is None
    with pytest.raises(PartError) as err:
        part_from_drawing(src)
    msg = str(err.value)
    assert msg.startswith(f"{GASKET}: a drawing has no material") and "beside" not in msg
    # a material given as a Source is read like a material file
    part = part_from_drawing(src, material=Source("rubber.json", RUBBER.encode()))
    assert part.material.youngs_modulus == 2e6


@pytest.mark.parametrize("name,data,match", [
    ("upload.dxf", b"not a drawing at all\n", "upload.dxf: not a readable DXF file"),
    ("upload.dxf", b"\xff\xfe\x00garbage", "upload.dxf: not a readable DXF file"),
    ("upload.svg", b"<svg><path d='M 0 0 L", "upload.svg: not a readable SVG file"),
    ("upload.txt", b"0\nSECTION\n", "upload.txt: not a drawing"),
])
def test_bad_bytes_are_one_line_errors_naming_the_source(name, data, match):
    with pytest.raises(PartError, match=match) as err:
        read_drawing(Source(name, data))
    assert "\n" not in str(err.value)


def test_open_outline_error_names_the_source():
    doc = ezdxf.new(units=4)
    doc.modelspace().add_lwpolyline([(0, 0), (4, 0), (4, 3)])
    import io

    text = io.StringIO()
    doc.write(text)
    with pytest.raises(PartError, match=r"^job-17\.dxf: open outline"):
        read_drawing(Source("job-17.dxf", text.getvalue().encode()))
