"""Finger placement at rest: depths into the part and the refusal of deep fingers."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure import Part, mesh_part
from deformclosure.cli.main import main
from deformclosure.dspace import DiscFinger, HalfPlaneFinger, PointFinger, PolygonFinger, equilibrium
from deformclosure.dspace.placement import FingerPlacementError, check_finger_placement, finger_depths

W, H = 0.012, 0.020          # rectangle (m); largest inscribed radius W/2


@pytest.fixture(scope="module")
def mesh():
    return mesh_part(Part.from_dict({"units": "m", "outer": [[0, 0], [W, 0], [W, H], [0, H]],
                                     "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3,
                                                  "thickness": 0.001, "elastic_limit_strain": 0.5},
                                     "mesh": {"max_area": W * H / 200}}))


def test_depths_of_simple_placements(mesh):
    fingers = [HalfPlaneFinger((0.0, 0.0), (1.0, 0.0)),           # touching the left side
               PointFinger((W / 2, H / 2)),                        # in the middle: W/2 deep
               DiscFinger((W + 0.002, H / 2), 0.003),              # overlapping the right side by 1 mm
               PolygonFinger(((W / 2 - 0.001, -0.001), (W / 2 + 0.001, -0.001), (W / 2, 0.0005)))]
    d = finger_depths(mesh, fingers)
    assert d[0] == pytest.approx(0.0, abs=1e-15)
    assert d[1] == pytest.approx(W / 2, rel=1e-9)
    assert d[2] == pytest.approx(0.001, rel=1e-9)
    assert d[3] == pytest.approx(0.0005, rel=1e-9)


@settings(max_examples=30, deadline=None)
@given(st.floats(0.0, 0.45), st.sampled_from([0, 1, 2, 3]))
def test_half_plane_overlap_depth_is_exact_and_accepted(mesh, frac, side):
    """A jaw pushed into one side by d (< half the inscribed radius) has depth d."""
    d = frac * W / 2
    point, normal = [((d, 0), (1, 0)), ((W - d, 0), (-1, 0)), ((0, d), (0, 1)), ((0, H - d), (0, -1))][side]
    depth = check_finger_placement(mesh, [HalfPlaneFinger(point, normal)])
    assert depth[0] == pytest.approx(d, abs=1e-15)


@pytest.mark.parametrize("finger", [PointFinger((W / 2, H / 2)), DiscFinger((W / 2, H / 2), 0.002),
                                    HalfPlaneFinger((W / 2, 0), (1, 0))])
def test_deep_fingers_are_refused(mesh, finger):
    with pytest.raises(FingerPlacementError, match=r"fingers\[0\].*inscribed radius"):
        equilibrium(mesh, [finger])


def test_cli_check_refuses_a_finger_inside_the_part(tmp_path):
    part = tmp_path / "p.json"
    part.write_text(json.dumps({"units": "mm", "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
                                "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 1,
                                             "elastic_limit_strain": 0.5}}))
    fingers = tmp_path / "f.json"
    fingers.write_text(json.dumps({"units": "mm", "fingers": [{"type": "point", "at": [6, 10]}]}))
    assert main(["check", str(part), "--fingers", str(fingers)]) == 2
