"""Finger bodies and the finger file (SPEC §5)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely

from deformclosure.dspace import (DiscFinger, HalfPlaneFinger, PointFinger, PolygonFinger, fingers_from_dict,
                                  fingers_to_dict, load_fingers, write_fingers)
from deformclosure.errors import DeformClosureError, FingerError

GOOD = {"units": "mm", "fingers": [
    {"type": "point", "at": [1, 2]},
    {"type": "disc", "center": [3, 4], "radius": 5},
    {"type": "polygon", "vertices": [[0, 0], [0, 10], [10, 0]]},  # clockwise on purpose
    {"type": "halfplane", "point": [0, -1], "normal": [0, 2]},
]}


def test_load_converts_to_si(tmp_path):
    p = tmp_path / "f.json"
    p.write_text(json.dumps(GOOD))
    f = load_fingers(p)
    assert f[0] == PointFinger((0.001, 0.002))
    assert f[1] == DiscFinger((0.003, 0.004), 0.005)
    assert isinstance(f[2], PolygonFinger)
    v = f[2].vertices
    area2 = np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1])
    assert area2 > 0  # stored counter-clockwise
    assert f[3] == HalfPlaneFinger((0.0, -0.001), (0.0, 1.0))


def test_round_trip(tmp_path):
    f = fingers_from_dict(GOOD)
    def flat(fs):
        return np.concatenate([np.ravel([v for k, v in sorted(g.to_dict().items()) if k != "type"][0])
                               if len(g.to_dict()) == 2 else
                               np.concatenate([np.ravel(v) for k, v in sorted(g.to_dict().items()) if k != "type"])
                               for g in fs])

    for units in ("m", "mm", "cm", "in"):
        back = fingers_from_dict(fingers_to_dict(f, units))
        assert [g.type for g in back] == [g.type for g in f]
        assert np.allclose(flat(back), flat(f), rtol=1e-12, atol=0)
    write_fingers(f, tmp_path / "g.json", units="cm")
    assert [g.type for g in load_fingers(tmp_path / "g.json")] == ["point", "disc", "polygon", "halfplane"]


BAD = [
    ({"units": "mm", "fingers": [{"type": "disc", "center": [0, 0], "radius": -1}]}, r"fingers\[0\]\.radius"),
    ({"units": "mm", "fingers": [{"type": "disc", "centre": [0, 0], "radius": 1}]}, r"fingers\[0\]\.centre: unknown field"),
    ({"units": "mm", "fingers": [{"type": "circle", "center": [0, 0], "radius": 1}]}, r"unknown finger type 'circle'"),
    ({"units": "mm", "fingers": [{"center": [0, 0], "radius": 1}]}, r'missing "type"'),
    ({"units": "km", "fingers": [{"type": "point", "at": [0, 0]}]}, r"units: 'km'"),
    ({"fingers": [{"type": "point", "at": [0, 0]}]}, r"units: missing"),
    ({"units": "m", "fingers": []}, r"fingers: the list is empty"),
    ({"units": "m", "fingers": [{"type": "point", "at": [0]}]}, r"fingers\[0\]\.at: expected \[x, y\]"),
    ({"units": "m", "fingers": [{"type": "point", "at": ["a", 0]}]}, r"fingers\[0\]\.at\[0\]"),
    ({"units": "m", "fingers": [{"type": "polygon", "vertices": [[0, 0], [2, 0], [1, 0.2], [1, 2]]}]}, r"not convex"),
    ({"units": "m", "fingers": [{"type": "polygon", "vertices": [[0, 0], [1, 1]]}]}, r"at least 3"),
    ({"units": "m", "fingers": [{"type": "polygon", "vertices": [[0, 0], [1, 1], [2, 2]]}]}, r"zero area"),
    ({"units": "m", "fingers": [{"type": "halfplane", "point": [0, 0], "normal": [0, 0]}]}, r"normal: must be non-zero"),
    ({"units": "m", "fingers": [{"type": "halfplane", "point": [0, 0]}]}, r"fingers\[0\]\.normal: missing"),
    ({"units": "m", "fingers": [{"type": "point", "at": [0, 0]}], "extra": 1}, r"extra: unknown field"),
    ({"units": "m", "fingers": [3]}, r"fingers\[0\]"),
    ([1, 2], r"expected a JSON object"),
]


@pytest.mark.parametrize("data,pattern", BAD, ids=[p for _, p in BAD])
def test_bad_finger_dicts(data, pattern):
    with pytest.raises(FingerError, match=pattern) as err:
        fingers_from_dict(data, source="F.json")
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("F.json")
    assert isinstance(err.value, DeformClosureError)


def test_nan_and_bad_json(tmp_path):
    p = tmp_path / "f.json"
    p.write_text('{"units": "m", "fingers": [{"type": "point", "at": [NaN, 0]}]}')
    with pytest.raises(FingerError, match="finite"):
        load_fingers(p)
    p.write_text('{"units": "m", "fingers": [')
    with pytest.raises(FingerError, match="not valid JSON"):
        load_fingers(p)
    with pytest.raises(FingerError, match="cannot read"):
        load_fingers(tmp_path / "missing.json")


def _cli(argv):
    from deformclosure.cli.main import main

    return main(argv)


@pytest.mark.parametrize("data,pattern", BAD[:6] + [("{not json", "not valid JSON")])
@pytest.mark.parametrize("cmd", ["check", "slice"])
def test_cli_bad_finger_file_exit_2(tmp_path, capsys, examples_dir, data, pattern, cmd):
    p = tmp_path / "f.json"
    p.write_text(data if isinstance(data, str) else json.dumps(data))
    args = [cmd, str(examples_dir / "rectangle.json"), "--fingers", str(p)]
    if cmd == "slice":
        args += ["--node", "0", "--resolution", "4"]
    assert _cli(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and len(err.splitlines()) == 1


# ----------------------------------------------------------------------------- geometry


def _shape(f):
    if isinstance(f, DiscFinger):
        return shapely.Point(f.center).buffer(f.radius, quad_segs=512)
    if isinstance(f, PolygonFinger):
        return shapely.Polygon(f.vertices)
    raise TypeError


@pytest.mark.parametrize("f", [DiscFinger((0.1, -0.2), 0.5), PolygonFinger(((0, 0), (1, 0), (1.2, 0.8), (0.1, 1)))])
def test_signed_distance_matches_shapely(f):
    rng = np.random.default_rng(6)
    P = rng.uniform(-1.5, 2, size=(300, 2))
    sd = f.signed_distance(P)
    s = _shape(f)
    ref = np.where(shapely.contains_xy(s, P[:, 0], P[:, 1]), -1, 1) * shapely.distance(s.exterior,
                                                                                   shapely.points(P))
    assert np.allclose(sd, ref, atol=2e-5)
    # outward normal is the gradient of the signed distance
    h = 1e-7
    g = np.stack([(f.signed_distance(P + [h, 0]) - f.signed_distance(P - [h, 0])) / (2 * h),
                  (f.signed_distance(P + [0, h]) - f.signed_distance(P - [0, h])) / (2 * h)], axis=1)
    keep = np.abs(sd) > 1e-3
    assert np.allclose(f.outward_normal(P)[keep], g[keep], atol=1e-5)


def test_halfplane_and_point():
    hp = HalfPlaneFinger((0.0, 1.0), (0.0, 1.0))
    assert hp.signed_distance([[5.0, 3.0], [0.0, 0.0]]).tolist() == [2.0, -1.0]
    pf = PointFinger((1.0, 1.0))
    assert pf.signed_distance([[4.0, 5.0]])[0] == 5.0 and not pf.has_interior
