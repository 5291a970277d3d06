"""Parts from DXF and SVG drawings (issue 13, item 1): areas and holes against closed-form
values, units from the headers, and one-line errors naming the entity."""

from __future__ import annotations

import json
import math
from pathlib import Path

import ezdxf
import numpy as np
import pytest
import shapely
from ezdxf.math import rational_bspline_from_arc

from deformclosure import DeformClosureError, Part
from deformclosure.cli.main import main
from deformclosure.drawing import read_drawing
from deformclosure.part import part_from_drawing

ROOT = Path(__file__).resolve().parents[1]
RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1,
          "elastic_limit_strain": 0.8}


def _area(d) -> float:
    return shapely.Polygon(d.outer, [h for h in d.holes]).area


def _perimeter(d) -> float:
    return sum(shapely.LinearRing(r).length for r in (d.outer, *d.holes))


def _segment_area(chord: float, bulge: float) -> float:
    """Area between a chord and the arc of DXF bulge ``bulge`` (= tan(θ/4))."""
    theta = 4 * math.atan(abs(bulge))
    R = chord / (2 * math.sin(theta / 2))
    return R * R / 2 * (theta - math.sin(theta))


def _plate_area() -> float:
    """10 × 5 plate, right edge bulging out (bulge 0.5), semicircular tab r = 2 on top,
    circular hole r = 1."""
    return 50 + _segment_area(5, 0.5) + math.pi * 4 / 2 - math.pi * 1


@pytest.fixture()
def plate(tmp_path):
    doc = ezdxf.new(units=4)
    msp = doc.modelspace()
    # outer: an open polyline with an arc segment, closed by a rational spline (exact arc)
    msp.add_lwpolyline([(3, 5, 0), (0, 5, 0), (0, 0, 0), (10, 0, 0.5), (10, 5, 0), (7, 5, 0)],
                       format="xyb")
    spline = msp.add_spline()
    spline.apply_construction_tool(
        rational_bspline_from_arc(center=(5, 5), radius=2, start_angle=0, end_angle=180))
    msp.add_circle((5, 2.5), 1)
    path = tmp_path / "plate.dxf"
    doc.saveas(path)
    return path


def test_dxf_polyline_arc_spline_and_circle_hole(plate):
    d = read_drawing(plate)
    assert d.units == "mm" and len(d.holes) == 1
    x0, y0, x1, y1 = shapely.Polygon(d.outer).bounds
    tol = 1e-3 * math.hypot(x1 - x0, y1 - y0)        # the default: 0.1 % of the diagonal
    # chords inside a convex arc lose at most tol × length; the hole gains as much
    assert abs(_area(d) - _plate_area()) <= _perimeter(d) * tol
    # a finer tolerance converges on the exact area
    fine = read_drawing(plate, tolerance=1e-5)
    assert abs(_area(fine) - _plate_area()) < 1e-3
    assert abs(_area(fine) - _plate_area()) < abs(_area(d) - _plate_area())


def test_dxf_units_from_the_header(tmp_path):
    for code, metres in ((4, 1e-3), (1, 0.0254), (5, 1e-2), (6, 1.0)):
        doc = ezdxf.new(units=code)
        doc.modelspace().add_lwpolyline([(0, 0), (4, 0), (4, 3), (0, 3)], close=True)
        path = tmp_path / f"u{code}.dxf"
        doc.saveas(path)
        part = part_from_drawing(path, material=json.dumps(RUBBER))
        assert part.area == pytest.approx(12 * metres**2, rel=1e-12)
        # thickness 1 in the drawing's units
        assert part.material.thickness == pytest.approx(metres, rel=1e-12)


def test_dxf_lines_and_arcs_chain_in_any_order_and_direction(tmp_path):
    doc = ezdxf.new(units=4)
    msp = doc.modelspace()
    # a slot: two lines and two half circles (r = 1), drawn scrambled
    msp.add_arc((4, 1), 1, -90, 90)
    msp.add_line((0, 0), (4, 0))
    msp.add_line((0, 2), (4, 2))           # reversed relative to the loop
    msp.add_arc((0, 1), 1, 90, 270)
    path = tmp_path / "slot.dxf"
    doc.saveas(path)
    d = read_drawing(path, tolerance=1e-6)
    assert len(d.holes) == 0
    assert _area(d) == pytest.approx(8 + math.pi, abs=1e-4)


def test_dxf_blocks_and_layers(tmp_path):
    doc = ezdxf.new(units=4)
    blk = doc.blocks.new("HOLE")
    blk.add_circle((0, 0), 0.5)
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (10, 0), (10, 10), (0, 10)], close=True, dxfattribs={"layer": "CUT"})
    for x in (3, 7):
        msp.add_blockref("HOLE", (x, 5), dxfattribs={"layer": "CUT"})
    msp.add_lwpolyline([(20, 0), (30, 0), (30, 10)], dxfattribs={"layer": "NOTES"})
    path = tmp_path / "b.dxf"
    doc.saveas(path)
    d = read_drawing(path, layer="CUT", tolerance=1e-6)
    assert len(d.holes) == 2
    assert _area(d) == pytest.approx(100 - 2 * math.pi * 0.25, abs=1e-4)
    with pytest.raises(DeformClosureError, match="open outline: LWPOLYLINE"):
        read_drawing(path)
    with pytest.raises(DeformClosureError, match="layers in the drawing: CUT, NOTES"):
        read_drawing(path, layer="OUTLINE")


@pytest.mark.parametrize("build,words", [
    (lambda m: m.add_lwpolyline([(0, 0), (4, 0), (4, 3)]), r"open outline: LWPOLYLINE #\w+ ends"),
    (lambda m: m.add_lwpolyline([(0, 0), (4, 3), (4, 0), (0, 3)], close=True), "crosses itself"),
    (lambda m: (m.add_circle((0, 0), 1), m.add_circle((5, 0), 1)), "two outer outlines"),
    (lambda m: (m.add_circle((0, 0), 2), m.add_circle((1.5, 0), 1)), "crosses the outer outline"),
    (lambda m: (m.add_line((0, 0), (1, 0)), m.add_line((1, 0), (1, 1)), m.add_line((1, 0), (2, 0)),
                m.add_line((1, 1), (0, 0))), "branches"),
    (lambda m: m.add_text("hello"), "no lines, arcs"),
    (lambda m: m.add_3dface([(0, 0), (1, 0), (1, 1)]), "3DFACE #"),
])
def test_dxf_problems_are_one_line_errors_naming_the_entity(tmp_path, build, words):
    doc = ezdxf.new(units=4)
    build(doc.modelspace())
    path = tmp_path / "bad.dxf"
    doc.saveas(path)
    with pytest.raises(DeformClosureError, match=words) as err:
        read_drawing(path)
    assert "\n" not in str(err.value)


def test_unitless_dxf_needs_units(tmp_path):
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 0
    doc.modelspace().add_circle((0, 0), 1)
    path = tmp_path / "nounits.dxf"
    doc.saveas(path)
    with pytest.raises(DeformClosureError, match="unitless.*--units"):
        read_drawing(path)
    assert read_drawing(path, default_units="in").units == "in"


def test_garbage_dxf_and_svg(tmp_path):
    for name, data in (("x.dxf", b"\x00\x01garbage"), ("x.svg", b"<svg><path d='M 0 0 L")):
        p = tmp_path / name
        p.write_bytes(data)
        with pytest.raises(DeformClosureError, match="not a readable|no lines"):
            read_drawing(p)


SVG = """<svg xmlns="http://www.w3.org/2000/svg" {size} viewBox="0 0 100 60">
  <g id="part">
    <path id="outline" d="M 0 0 H 80 A 20 20 0 0 1 80 40 V 60 H 0 Z"/>
    <circle id="hole" cx="30" cy="30" r="10"/>
    <rect id="slot" x="50" y="45" width="20" height="5"/>
  </g>
  <path id="stray" d="M 200 200 L 230 200 L 215 180 Z"/>
</svg>"""


def _svg_area_user() -> float:
    # 80 × 60 rectangle + half disc r = 20 on the right (x ∈ [80, 100], y ∈ [0, 40]),
    # less the hole and the slot
    return 80 * 60 + math.pi * 400 / 2 - math.pi * 100 - 100


@pytest.mark.parametrize("size,mm_per_user", [('width="100mm" height="60mm"', 1.0),
                                              ('width="10cm" height="6cm"', 1.0),
                                              ('width="200mm" height="120mm"', 2.0),
                                              ("", 25.4 / 96)])
def test_svg_paths_shapes_and_units(tmp_path, size, mm_per_user):
    p = tmp_path / "part.svg"
    p.write_text(SVG.format(size=size))
    d = read_drawing(p, layer="part", tolerance=1e-4)
    assert d.units == "mm" and len(d.holes) == 2
    assert _area(d) == pytest.approx(_svg_area_user() * mm_per_user**2, rel=1e-5)
    # --units: one user unit is one unit
    d_in = read_drawing(p, layer="part", units="in", tolerance=1e-4)
    assert d_in.units == "in"
    assert _area(d_in) == pytest.approx(_svg_area_user(), rel=1e-5)
    # without the layer, the stray path is a second outer outline
    with pytest.raises(DeformClosureError, match="two outer outlines.*stray"):
        read_drawing(p)


def test_svg_open_path_is_named(tmp_path):
    p = tmp_path / "open.svg"
    p.write_text('<svg xmlns="http://www.w3.org/2000/svg"><path id="edge" d="M 0 0 L 10 0 L 10 10"/></svg>')
    with pytest.raises(DeformClosureError, match="open outline: path 'edge'"):
        read_drawing(p)


def test_drawings_are_accepted_wherever_a_part_file_is(plate, tmp_path, capsys):
    rubber = tmp_path / "rubber.json"
    rubber.write_text(json.dumps(RUBBER))
    out = tmp_path / "plate.json"
    assert main(["import", str(plate), "-o", str(out), "--material", str(rubber), "-q"]) == 0
    imported = Part.from_file(out)
    direct = part_from_drawing(plate, material=json.dumps(RUBBER))
    np.testing.assert_allclose(imported.outer, direct.outer, rtol=1e-15, atol=0)
    assert imported.material == direct.material
    # a command on the drawing gives the same mesh as on the imported part file
    capsys.readouterr()
    assert main(["mesh", str(plate), "--material", str(rubber), "-q",
                 "-o", str(tmp_path / "a.json")]) == 0
    assert main(["mesh", str(out), "-q", "-o", str(tmp_path / "b.json")]) == 0
    a, b = (json.loads((tmp_path / f).read_text()) for f in ("a.json", "b.json"))
    assert a["triangles"] == b["triangles"]
    np.testing.assert_allclose(a["nodes"], b["nodes"], rtol=1e-12, atol=1e-18)
    # the material beside the drawing
    with pytest.raises(DeformClosureError, match="plate.material.json"):
        Part.from_file(plate)
    (tmp_path / "plate.material.json").write_text(json.dumps({**RUBBER, "mesh": {"min_angle": 25}}))
    beside = Part.from_file(plate)
    assert beside.material == direct.material and beside.mesh_options.min_angle == 25


@pytest.mark.parametrize("width, expected_mm", [("20mm", 20.0), ("2cm", 20.0), ("2in", 50.8),
                                                 ("144pt", 50.8)])
def test_svg_physical_width_converts_exactly(width, expected_mm):
    """svgelements turns mm into px with a 7-digit factor (a 20 mm drawing came out
    20.0000108 mm); the physical width as written fixes the scale exactly."""
    from deformclosure.drawing import read_drawing
    from deformclosure.jsonfile import Source

    svg = (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="1in" '
           f'viewBox="0 0 20 10"><rect width="20" height="10"/></svg>').encode()
    d = read_drawing(Source("plate.svg", svg))
    assert d.units == "mm"
    np.testing.assert_allclose(np.ptp(d.outer[:, 0]), expected_mm, rtol=1e-13)
