"""Each finger kind answers the D-space modules' geometric questions itself (issue 10):
its distance, normal and segment tests agree with independent computations (shapely,
or the hand formula of a half-plane) on random points; and the finger file reader reads
a :class:`deformclosure.jsonfile.Source` exactly as it reads the file."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from deformclosure.dspace import (DiscFinger, HalfPlaneFinger, PointFinger, PolygonFinger, as_fingers,
                                  fingers_from_dict, load_fingers)
from deformclosure.errors import FingerError
from deformclosure.jsonfile import Source

L = 0.01                                  # scale of the fingers and points (m)
coord = st.floats(-2 * L, 2 * L, allow_nan=False, allow_infinity=False)
point = st.tuples(coord, coord)


# ----------------------------------------------------------------------------- reader

GOOD = {"units": "mm", "fingers": [
    {"type": "point", "at": [1, 2]},
    {"type": "disc", "center": [3, 4], "radius": 5},
    {"type": "polygon", "vertices": [[0, 0], [0, 10], [10, 0]]},
    {"type": "halfplane", "point": [0, -1], "normal": [0, 2]},
]}


def test_reader_reads_a_source_as_it_reads_the_file(tmp_path):
    p = tmp_path / "f.json"
    p.write_text(json.dumps(GOOD))
    assert load_fingers(Source("f.json", p.read_bytes())) == load_fingers(p) == fingers_from_dict(GOOD)


@pytest.mark.parametrize("data,match", [
    (b'{"units": "mm", "fingers": []}', r"^jobs/fingers\.json: fingers: the list is empty"),
    (b'{"units": "mm", "fingers": [{"type": "disc", "center": [0, 0], "radius": -1}]}',
     r"^jobs/fingers\.json: fingers\[0\]\.radius"),
    (b'{"units": "mm", "fingers": [', r"^jobs/fingers\.json: not valid JSON"),
])
def test_reader_errors_name_the_source(data, match):
    with pytest.raises(FingerError, match=match):
        load_fingers(Source("jobs/fingers.json", data))


def test_as_fingers_names_the_entry_that_is_not_a_finger():
    assert as_fingers([PointFinger((0.0, 0.0))]) == (PointFinger((0.0, 0.0)),)
    with pytest.raises(FingerError, match=r"fingers\[1\]: expected a Finger"):
        as_fingers([PointFinger((0.0, 0.0)), {"type": "point", "at": [0, 0]}])
    with pytest.raises(FingerError, match=r"fingers: expected a sequence"):
        as_fingers(PointFinger((0.0, 0.0)))


# ----------------------------------------------------------------------------- fingers


@st.composite
def fingers(draw):
    kind = draw(st.sampled_from(["point", "disc", "polygon", "halfplane"]))
    c = draw(st.tuples(st.floats(-L, L), st.floats(-L, L)))
    if kind == "point":
        return PointFinger(c)
    if kind == "disc":
        return DiscFinger(c, draw(st.floats(0.05 * L, L)))
    if kind == "halfplane":
        t = draw(st.floats(0, 2 * math.pi))
        return HalfPlaneFinger(c, (math.cos(t), math.sin(t)))
    pts = np.asarray(draw(st.lists(point, min_size=3, max_size=8)))
    hull = shapely.MultiPoint(pts).convex_hull
    assume(hull.geom_type == "Polygon" and hull.area > 0.05 * L**2 and hull.minimum_clearance > 0.02 * L)
    ring = np.asarray(hull.exterior.coords)[:-1]
    return fingers_from_dict({"units": "m", "fingers": [{"type": "polygon", "vertices": ring.tolist()}]})[0]


def reference_distance(f, p) -> float:
    """Signed distance of ``p`` from the finger body, computed independently."""
    q = shapely.Point(p)
    if isinstance(f, PointFinger):
        return shapely.Point(f.at).distance(q)
    if isinstance(f, DiscFinger):
        return shapely.Point(f.center).distance(q) - f.radius
    if isinstance(f, HalfPlaneFinger):       # hand formula: (p - point) . normal
        return (p[0] - f.point[0]) * f.normal[0] + (p[1] - f.point[1]) * f.normal[1]
    poly = shapely.Polygon(f.vertices)
    return -poly.exterior.distance(q) if poly.contains(q) else poly.distance(q)


@settings(max_examples=150, deadline=None)
@given(f=fingers(), pts=st.lists(point, min_size=1, max_size=6))
def test_signed_distance_agrees_with_an_independent_computation(f, pts):
    P = np.asarray(pts)
    sd = f.signed_distance(P)
    assert sd.shape == (len(P),)
    ref = np.array([reference_distance(f, p) for p in P])
    np.testing.assert_allclose(sd, ref, rtol=0, atol=1e-12 * L)
    np.testing.assert_allclose(f.signed_distance(P[0]), sd[0], rtol=1e-14, atol=1e-16)   # one point


@settings(max_examples=150, deadline=None)
@given(f=fingers(), p=point)
def test_outward_normal_is_the_gradient_of_the_independent_distance(f, p):
    p = np.asarray(p)
    sd = float(reference_distance(f, p))
    # on the boundary the normal is one-sided, and at a corner not a gradient at all
    assume(abs(sd) > 1e-6 * L)
    n = f.outward_normal(p)
    assert abs(np.linalg.norm(n) - 1.0) < 1e-12
    # moving along the normal raises the distance at unit rate (one-sided at kinks)
    h = 1e-7 * L
    slope = (reference_distance(f, p + h * n) - sd) / h
    assert abs(slope - 1.0) < 1e-4, (slope, sd)
    # and the foot point p - sd n lies on the body's boundary
    foot = p - sd * n
    assert abs(reference_distance(f, foot)) < 1e-9 * L


def reference_hits(f, a, b, tol) -> tuple[bool, float]:
    """Does the segment meet the open body eroded by ``tol``? Also the margin by which
    the answer is decided (m), to skip segments that only graze it."""
    seg = shapely.LineString([a, b])
    if isinstance(f, PointFinger):
        return False, math.inf
    if isinstance(f, DiscFinger):
        d = shapely.Point(f.center).distance(seg)
        return d < f.radius - tol, abs(d - (f.radius - tol))
    if isinstance(f, HalfPlaneFinger):
        depth = max(-reference_distance(f, a), -reference_distance(f, b))   # linear: ends decide
        return depth > tol, abs(depth - tol)
    body = shapely.Polygon(f.vertices).buffer(-tol, join_style="mitre")
    if body.is_empty:
        return False, math.inf
    if seg.intersects(body):                 # decided when it reaches inside beyond round-off
        inner = body.buffer(-1e-9 * L, join_style="mitre")
        return True, (math.inf if not inner.is_empty and seg.intersects(inner) else 0.0)
    return False, seg.distance(body)


@settings(max_examples=150, deadline=None)
@given(f=fingers(), a=point, b=point, tol=st.sampled_from([0.0, 1e-9 * L, 1e-3 * L]))
def test_segment_hits_agree_with_shapely(f, a, b, tol):
    a, b = np.asarray(a), np.asarray(b)
    assume(np.linalg.norm(b - a) > 1e-6 * L)
    hit, margin = reference_hits(f, a, b, tol)
    assume(margin > 1e-9 * L)
    out = f.segment_hits(a[None], b[None], tol)
    assert out.shape == (1,)
    assert bool(out[0]) == hit


@pytest.mark.parametrize("finger, field", [
    (DiscFinger((0.0, 0.0), -1.0), "radius"),
    (DiscFinger((0.0, float("nan")), 1.0), "center"),
    (HalfPlaneFinger((0.0, 0.0), (0.0, 2.0)), "normal"),
    (PolygonFinger(((0.0, 0.0), (1.0, 0.0), (2.0, 0.0))), "corners"),
])
def test_fingers_built_in_code_are_checked_like_the_file_reader(finger, field):
    """A finger made in Python with a negative radius, a NaN, a non-unit normal or a
    flat polygon is refused by every entry point (one line naming the field), never used."""
    with pytest.raises(FingerError, match=rf"fingers\[0\]\.{field}: "):
        as_fingers([finger])


# ----------------------------------------------------------------------------- one profile
@settings(max_examples=60, deadline=None)
@given(st.floats(1e-4, 1e-2), st.floats(0.0, 2 * np.pi), st.floats(-0.49, 1.0),
       st.floats(-0.99, 0.99))
def test_compiled_disc_gap_is_the_capsule_profile(r, angle, s_frac, x_frac):
    """The placement kernel's disc rows (compiled) use the same surface as the pads: the
    gap along the disc's axis to ``Capsule(0, r).profile`` at the node's cross coordinate,
    scaled to a unit gradient, and no contact beyond the capsule's reach (nodes in front
    of the disc's back along its axis: ``s ≥ −0.98 r`` here; within round-off of ``s = −r``
    the node is on the disc's back, where the kernel measures the true distance instead,
    and hypothesis finds both ``s = −r`` and the float next to it)."""
    from deformclosure.contact.bodies import Capsule, DiscFinger
    from deformclosure.dspace.placement_energy import _body_sd

    a = np.array([np.cos(angle), np.sin(angle)])
    n = np.array([-a[1], a[0]])
    disc = DiscFinger((0.01, -0.02), r)
    t, par, _, _ = disc.kernel_encoding(a)
    shape = disc.shape
    x = x_frac * shape.half_span
    s = s_frac * 2 * r
    p = np.asarray(disc.center) + s * a + x * n
    empty2, empty1, none = np.zeros((0, 2)), np.zeros(0), np.zeros(0, np.int64)
    no_part = (empty2, none, none, empty2, empty1, none, none, np.zeros(0, bool))   # unused for s ≥ −r
    g, nx, ny = _body_sd(t, par, 0, 0, empty2, empty2, empty1, p[0], p[1], a[0], a[1], no_part)
    d, slope = shape.profile(np.array([x]))
    if abs(x) >= shape.reach:
        assert not np.isfinite(d[0]) and g == np.inf
        return
    # the disc's front surface at cross coordinate x lies r − d(x) ahead of its centre
    gap_axis = s - (r - d[0])
    norm = np.hypot(1.0, slope[0])
    assert g == pytest.approx(gap_axis / norm, rel=1e-9, abs=1e-15)
    assert np.hypot(nx, ny) == pytest.approx(1.0, abs=1e-12)
