"""Part files: reading, unit conversion, ring normalisation, validation (SPEC §1, §5)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure import DeformClosureError, Material, Part, PartError, demo_part
from deformclosure.part import MAX_TRIANGLES

RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
          "elastic_limit_strain": 0.8, "plane": "stress"}


def _signed_area(ring):
    x, y = np.asarray(ring).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


# --------------------------------------------------------------------------- reading
def test_example_files_read_and_are_normalised(examples_dir):
    files = sorted(examples_dir.glob("*.json"))
    assert len(files) >= 5
    for f in files:
        part = Part.from_file(f)
        raw = json.loads(f.read_text())
        assert _signed_area(part.outer) > 0, f.name
        assert len(part.holes) == len(raw.get("holes", []))
        for h in part.holes:
            assert _signed_area(h) < 0, f.name
        assert part.polygon.is_valid


def test_units_are_converted_to_si(make_part):
    part = make_part([[0, 0], [12, 0], [12, 20], [0, 20]], units="mm", points=[[6, 0]],
                     max_area=2.0, thickness=1.5)
    np.testing.assert_allclose(part.outer.max(axis=0), [0.012, 0.020], rtol=1e-15)
    assert part.area == pytest.approx(12e-3 * 20e-3, rel=1e-12)
    assert part.material.thickness == pytest.approx(1.5e-3, rel=1e-15)
    assert part.mesh_options.max_area == pytest.approx(2.0e-6, rel=1e-12)   # mm² -> m²
    np.testing.assert_allclose(part.mesh_options.points, [[0.006, 0.0]], rtol=1e-15)
    # The modulus is in Pa whatever the length unit.
    assert part.material.youngs_modulus == 2e6

    inch = make_part([[0, 0], [1, 0], [1, 1]], units="in", thickness=0.5)
    assert inch.area == pytest.approx(0.5 * 0.0254**2, rel=1e-12)
    assert inch.material.thickness == pytest.approx(0.0127, rel=1e-12)


def test_rings_are_reoriented_and_cleaned(make_part):
    # Outer given clockwise, closed (first point repeated) and with a doubled point;
    # hole given counter-clockwise.
    outer_cw = [[0, 0], [0, 10], [0, 10], [10, 10], [10, 0], [0, 0]]
    hole_ccw = [[4, 4], [6, 4], [6, 6], [4, 6]]
    part = make_part(outer_cw, holes=[hole_ccw])
    assert len(part.outer) == 4
    assert _signed_area(part.outer) == pytest.approx(100e-6, rel=1e-12)
    assert _signed_area(part.holes[0]) == pytest.approx(-4e-6, rel=1e-12)
    assert part.area == pytest.approx(96e-6, rel=1e-12)
    # Same point set as given (only order changed).
    assert {tuple(p) for p in np.round(part.outer * 1e3, 9)} == {(0, 0), (0, 10), (10, 10), (10, 0)}


def test_to_dict_round_trip(plate_part):
    again = Part.from_dict(json.loads(json.dumps(plate_part.to_dict())))
    np.testing.assert_array_equal(again.outer, plate_part.outer)
    assert len(again.holes) == len(plate_part.holes)
    for a, b in zip(again.holes, plate_part.holes):
        np.testing.assert_array_equal(a, b)
    assert again.material == plate_part.material
    assert again.mesh_options.max_area == plate_part.mesh_options.max_area


def test_demo_part_matches_the_paper_example():
    part = demo_part()
    assert part.area == pytest.approx(12e-3 * 20e-3, rel=1e-12)
    mat = part.material
    assert (mat.youngs_modulus, mat.poisson_ratio, mat.elastic_limit_strain) == (2e6, 0.1, 0.8)
    assert mat.thickness == pytest.approx(1e-3)
    assert mat.plane == "stress"
    np.testing.assert_allclose(part.mesh_options.points, [[0, 0.010], [0.012, 0.010]])


# --------------------------------------------------------------------------- errors
def test_errors_form_one_hierarchy():
    assert issubclass(PartError, DeformClosureError)
    assert issubclass(DeformClosureError, ValueError)


@pytest.mark.parametrize("field, value, needle", [
    ("youngs_modulus", 0.0, "youngs_modulus"),
    ("youngs_modulus", math.nan, "youngs_modulus"),
    ("poisson_ratio", 0.5, "poisson_ratio"),
    ("poisson_ratio", -1.0, "poisson_ratio"),
    ("thickness", 0.0, "thickness"),
    ("elastic_limit_strain", -0.1, "elastic_limit_strain"),
    ("plane", "membrane", "plane"),
])
def test_material_is_validated(field, value, needle):
    kw = dict(RUBBER, thickness=1e-3)
    kw[field] = value
    with pytest.raises(PartError, match=needle):
        Material(**kw)


def test_poisson_ratio_just_below_half_is_accepted():
    Material(**dict(RUBBER, poisson_ratio=0.49))


def test_missing_file_is_a_part_error(tmp_path):
    with pytest.raises(PartError, match="cannot read"):
        Part.from_file(tmp_path / "nope.json")


def test_absurd_mesh_request_is_refused_before_meshing(make_part):
    # 1 m² with max_area 1e-8 m² would be 1e8 triangles.
    with pytest.raises(PartError, match="max_area"):
        make_part([[0, 0], [1, 0], [1, 1], [0, 1]], units="m", max_area=1e-8)
    # Just below the limit is fine (the check is on the estimate only).
    make_part([[0, 0], [1, 0], [1, 1], [0, 1]], units="m", max_area=1.01 / MAX_TRIANGLES)


def test_point_on_the_boundary_is_accepted_point_outside_refused(make_part):
    square = [[0, 0], [10, 0], [10, 10], [0, 10]]
    make_part(square, points=[[10, 5], [0, 0], [5, 5]])
    with pytest.raises(PartError, match=r"mesh\.points\[1\]"):
        make_part(square, points=[[5, 5], [10.01, 5]])


# --------------------------------------------------------------------------- random invalid rings
def _circle_points(angles, radius=1.0, center=(0.0, 0.0)):
    a = np.asarray(angles)
    return np.column_stack([center[0] + radius * np.cos(a), center[1] + radius * np.sin(a)])


@st.composite
def bow_ties(draw):
    """A convex quadrilateral on a circle with two vertices swapped: always self-crossing."""
    gaps = draw(st.lists(st.floats(0.3, 2.0), min_size=4, max_size=4))
    angles = np.cumsum(gaps) / np.sum(gaps) * 2 * np.pi
    radius = draw(st.floats(0.1, 100.0))
    quad = _circle_points(angles, radius)
    return quad[[0, 2, 1, 3]]


@st.composite
def collinear_rings(draw):
    """3-8 distinct points on one line, in any order: zero area."""
    k = draw(st.integers(3, 8))
    ts = draw(st.lists(st.integers(-50, 50), min_size=k, max_size=k, unique=True))
    direction = np.array(draw(st.tuples(st.integers(-5, 5), st.integers(-5, 5))), float)
    if not direction.any():
        direction = np.array([1.0, 2.0])
    origin = np.array(draw(st.tuples(st.integers(-20, 20), st.integers(-20, 20))), float)
    return origin + np.asarray(ts, float)[:, None] * direction


@settings(max_examples=30, deadline=None)
@given(ring=bow_ties())
def test_random_bow_ties_are_refused(make_part, ring):
    with pytest.raises(PartError, match="outer"):
        make_part(ring)
    # As a hole inside a big square too.
    big = [[-1000, -1000], [1000, -1000], [1000, 1000], [-1000, 1000]]
    with pytest.raises(PartError, match=r"holes\[0\]"):
        make_part(big, holes=[ring])


@settings(max_examples=30, deadline=None)
@given(ring=collinear_rings())
def test_random_collinear_rings_are_refused(make_part, ring):
    with pytest.raises(PartError, match="outer"):
        make_part(ring)


# --------------------------------------------------------------------------- corrupted files
_JUNK = st.one_of(
    st.none(), st.booleans(), st.integers(-2**70, 2**70),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=5),
    st.lists(st.integers(-3, 3), max_size=3),
    st.lists(st.lists(st.floats(-1e3, 1e3), max_size=3), max_size=4),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)
_PATHS = [("name",), ("units",), ("outer",), ("outer", 1), ("outer", 1, 0), ("holes",),
          ("material",), ("material", "youngs_modulus"), ("material", "poisson_ratio"),
          ("material", "thickness"), ("material", "elastic_limit_strain"),
          ("material", "plane"), ("mesh",), ("mesh", "max_area"), ("mesh", "min_angle"),
          ("mesh", "points"), ("mesh", "points", 0), ("extra",)]


@settings(max_examples=30, deadline=None)
@given(edits=st.lists(st.tuples(st.sampled_from(_PATHS), _JUNK), min_size=1, max_size=3))
def test_corrupted_part_files_fail_only_with_part_error(edits):
    """Whatever is put in a field, reading gives a Part or a PartError, nothing else."""
    data = {"name": "p", "units": "mm", "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
            "holes": [], "material": dict(RUBBER),
            "mesh": {"max_area": 4.0, "min_angle": 30, "points": [[6, 0]]}}
    for path, value in edits:
        node = data
        try:
            for key in path[:-1]:
                node = node[key]
            node[path[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue
    try:
        part = Part.from_dict(data)
    except PartError as err:
        assert "\n" not in str(err)
    else:
        assert part.area > 0 and part.material.youngs_modulus > 0
