"""Length units (``deformclosure.units``): the factors against hand values, round trips
through part files, and one-line errors naming the field for unknown units."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from deformclosure import Part
from deformclosure.errors import DeformClosureError
from deformclosure.units import LENGTH_UNITS, SI_UNITS, length_scale

#: Metres per unit, by hand: the international inch is exactly 25.4 mm (1959).
HAND = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 25.4 / 1000}

RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
          "elastic_limit_strain": 0.8}


def test_the_accepted_units_are_exactly_m_cm_mm_in():
    assert set(LENGTH_UNITS) == set(HAND)


@pytest.mark.parametrize("unit", sorted(HAND))
def test_factor_against_hand_value(unit):
    assert length_scale(unit) == pytest.approx(HAND[unit], rel=1e-15)
    assert LENGTH_UNITS[unit] == pytest.approx(HAND[unit], rel=1e-15)


def test_factors_against_each_other():
    s = length_scale
    assert s("in") / s("mm") == pytest.approx(25.4, rel=1e-15)
    assert s("in") / s("cm") == pytest.approx(2.54, rel=1e-15)
    assert s("m") / s("cm") == pytest.approx(100.0, rel=1e-15)
    assert s("cm") / s("mm") == pytest.approx(10.0, rel=1e-15)
    assert 12 * 3 * s("in") == pytest.approx(0.9144, rel=1e-15)   # the yard, by definition


def test_si_units_of_reports():
    assert SI_UNITS == {"length": "m", "energy": "J", "stiffness": "N/m",
                        "strain_per_length": "1/m", "force": "N"}


@pytest.mark.parametrize("bad", ["furlong", "MM", "mm ", "", "metre", None, 3, 1e-3, ["mm"]])
@pytest.mark.parametrize("field", ["units", "material.units", "fingers[2].units"])
def test_unknown_unit_is_one_line_naming_the_field(bad, field):
    with pytest.raises(DeformClosureError) as info:
        length_scale(bad, field)
    msg = str(info.value)
    assert msg.startswith(f"{field}: "), msg
    assert "\n" not in msg
    for u in HAND:                          # says how to fix it
        assert repr(u) in msg


def test_unknown_unit_in_a_part_file_names_units():
    with pytest.raises(DeformClosureError) as info:
        Part.from_dict({"name": "p", "units": "ft", "outer": [[0, 0], [1, 0], [1, 1]],
                        "material": RUBBER})
    msg = str(info.value)
    assert msg.startswith("units:") and "'ft'" in msg and "\n" not in msg


@settings(max_examples=60, deadline=None)
@given(x=st.floats(-1e6, 1e6, allow_nan=False), a=st.sampled_from(sorted(HAND)),
       b=st.sampled_from(sorted(HAND)))
def test_round_trip_between_units(x, a, b):
    metres = x * length_scale(a)
    in_b = metres / length_scale(b)
    back = in_b * length_scale(b) / length_scale(a)
    assert back == pytest.approx(x, rel=1e-12, abs=1e-300)
    assert in_b == pytest.approx(x * HAND[a] / HAND[b], rel=1e-12, abs=1e-300)


def _part(unit, w, h, t, area, pt):
    return Part.from_dict({
        "name": "box", "units": unit,
        "outer": [[0, 0], [w, 0], [w, h], [0, h]],
        "material": dict(RUBBER, thickness=t),
        "mesh": {"max_area": area, "points": [pt]},
    })


@settings(max_examples=25, deadline=None)
@given(unit=st.sampled_from(sorted(HAND)), w=st.floats(1.0, 500.0), h=st.floats(1.0, 500.0),
       t=st.floats(0.1, 10.0), fx=st.floats(0.0, 1.0), fy=st.floats(0.0, 1.0))
def test_part_in_any_unit_is_the_same_part_in_metres(unit, w, h, t, fx, fy):
    """A part written in ``unit`` is the part written in metres with every length times
    the factor (areas times its square), and ``to_dict`` (SI) reads back to it."""
    s = HAND[unit]
    area = w * h / 50
    p = _part(unit, w, h, t, area, [fx * w, fy * h])
    q = _part("m", w * s, h * s, t * s, area * s * s, [fx * w * s, fy * h * s])
    np.testing.assert_allclose(p.outer, q.outer, rtol=1e-12)
    np.testing.assert_allclose(np.ptp(p.outer, axis=0), [w * s, h * s], rtol=1e-12)
    assert p.material.thickness == pytest.approx(t * s, rel=1e-12)
    assert p.mesh_options.max_area == pytest.approx(area * s * s, rel=1e-12)
    np.testing.assert_allclose(p.mesh_options.points, q.mesh_options.points, rtol=1e-12,
                               atol=1e-15)
    assert p.area == pytest.approx(w * h * s * s, rel=1e-12)
    back = Part.from_dict(p.to_dict())
    assert back.units == "m"
    np.testing.assert_allclose(back.outer, p.outer, rtol=1e-15)
    assert back.material.thickness == pytest.approx(p.material.thickness, rel=1e-15)
    assert back.mesh_options.max_area == pytest.approx(p.mesh_options.max_area, rel=1e-15)
    assert math.isclose(back.area, p.area, rel_tol=1e-12)
