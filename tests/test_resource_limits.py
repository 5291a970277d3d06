"""Resource limits (issue 11, item 4): requests that cannot finish or fit in 4 GB are
refused early, from a size estimate, with one line naming the field and the fix; inputs
just under each documented maximum pass the checks (called directly: the heavy jobs at
the maxima are run by ``benchmarks/bench_limits.py``).

Reproduced cases: a max_area that would give 3.9 million triangles, a 20 000-vertex ring,
10 000 mesh.points, ``plan`` on a 3000-vertex circle, ``slice --resolution 4000``, a
10 × 1e-5 mm sliver, a hole 1e-7 mm from the outer ring.
"""

from __future__ import annotations

import json
import re
import time
from types import SimpleNamespace

import numpy as np
import pytest

from deformclosure import limits
from deformclosure.cli.main import main
from deformclosure.errors import DeformClosureError, GraspError, MeshError, PartError
from deformclosure.grasp.size_limits import check_paper_size
from deformclosure.mesh.generate import insert_points_in_ring, mesh_part
from deformclosure.pads.size_limits import check_pads_size
from deformclosure.part import Part

RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
          "elastic_limit_strain": 0.8, "plane": "stress"}


def part_dict(outer, holes=(), **mesh):
    d = {"units": "mm", "outer": np.asarray(outer, float).tolist(),
         "holes": [np.asarray(h, float).tolist() for h in holes], "material": RUBBER}
    if mesh:
        d["mesh"] = mesh
    return d


def circle(k, r=10.0, c=(0.0, 0.0)):
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    return np.column_stack([c[0] + r * np.cos(t), c[1] + r * np.sin(t)])


def one_line_error(capsys, argv, pattern):
    """Run the CLI in-process: exit 2, one ``error:`` line matching ``pattern``."""
    t0 = time.perf_counter()
    assert main(argv) == 2
    took = time.perf_counter() - t0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    assert re.search(pattern, err[0]), err[0]
    return took


# --------------------------------------------------------------------------- the cases
def test_max_area_of_3_9_million_triangles_is_refused_before_meshing(tmp_path, capsys):
    block = [[0, 0], [12, 0], [12, 20], [0, 20]]
    max_area = 240.0 / 3.9e6 * limits._PER_AREA[-3]          # mm²: ≈ 3.9 M triangles
    # in the part file: refused on reading (area / max_area alone is over the limit)
    with pytest.raises(PartError, match=r"^mesh\.max_area = .*triangles \(limit 400,000\)"):
        Part.from_dict(part_dict(block, max_area=max_area))
    # as an override: refused from the estimate, naming the setting and a value that works
    part = Part.from_dict(part_dict(block))
    t0 = time.perf_counter()
    with pytest.raises(PartError, match=r"^max_area = .* mm²: the mesh would have about "
                                        r"3,9\d\d,\d\d\d triangles .*use max_area >= "):
        mesh_part(part, max_area=max_area * 1e-6)
    assert time.perf_counter() - t0 < 1.0
    f = tmp_path / "block.json"
    f.write_text(json.dumps(part_dict(block)))
    took = one_line_error(capsys, ["mesh", str(f), "--max-area", str(max_area)],
                          r"max_area = .*triangles \(limit 400,000\)")
    assert took < 3.0


def test_20000_vertex_ring_reads_and_measures_fast():
    ring = circle(20_000)
    t0 = time.perf_counter()
    part = Part.from_dict(part_dict(ring))
    d = part.diameter
    assert time.perf_counter() - t0 < 3.0
    assert d == pytest.approx(0.020, rel=1e-6)
    t0 = time.perf_counter()
    est = limits.estimate_triangles([part.outer], part.area / 400, 30.0)
    assert time.perf_counter() - t0 < 2.0
    assert est.thin_elements < 1.0                      # a fine ring has no narrow feature
    assert 0.7e5 < est.triangles < 1.8e5                # Triangle makes 118 000


def _insert_brute_force(ring, points, tol):
    """The former points × edges version of insert_points_in_ring (reference; it now
    inserts the feet of the points on the edges)."""
    a, b = ring, np.roll(ring, -1, axis=0)
    ab = b - a
    L2 = (ab**2).sum(1)
    t = ((points[:, None, :] - a[None]) * ab[None]).sum(-1) / L2[None]
    tc = np.clip(t, 0.0, 1.0)
    dist = np.linalg.norm(points[:, None, :] - (a[None] + tc[..., None] * ab[None]), axis=-1)
    edge = dist.argmin(axis=1)
    on = dist[np.arange(len(points)), edge] <= tol
    tt = tc[np.arange(len(points)), edge]
    Lk = np.sqrt(L2[edge])
    interior = on & (tt * Lk > tol) & ((1 - tt) * Lk > tol)
    if not interior.any():
        return ring, on
    keys = np.concatenate([np.arange(len(ring), dtype=float), edge[interior] + tt[interior]])
    foot = (a[edge] + tt[:, None] * ab[edge])[interior]
    new = np.concatenate([ring, foot])[np.argsort(keys, kind="stable")]
    keep = np.ones(len(new), bool)
    keep[1:] = np.linalg.norm(np.diff(new, axis=0), axis=1) > tol
    return new[keep], on


def _points_on_and_in(ring, n_on, n_in, rng):
    k = len(ring)
    e = rng.choice(k, n_on, replace=False)
    s = rng.uniform(0, 1, n_on)
    s[: n_on // 10] = 0.0                                # some exactly at vertices
    on = ring[e] + s[:, None] * (np.roll(ring, -1, axis=0)[e] - ring[e])
    inner = rng.uniform(-5, 5, (n_in, 2))
    return np.concatenate([on, inner])


def test_10000_mesh_points_need_no_points_by_edges_table():
    rng = np.random.default_rng(1)
    # same result as the brute-force reference on a small case
    small = circle(500) * 1e-3
    pts = _points_on_and_in(small / 1e-3, 150, 150, rng) * 1e-3
    got = insert_points_in_ring(small, pts, 1e-11)
    ref = _insert_brute_force(small, pts, 1e-11)
    np.testing.assert_array_equal(got[1], ref[1])
    np.testing.assert_allclose(got[0], ref[0], rtol=0, atol=1e-15)
    # 10 000 points on a 20 000-vertex ring: was a 10 000 × 20 000 table (gigabytes)
    ring = circle(20_000)
    pts = _points_on_and_in(ring, 5_000, 5_000, rng)
    t0 = time.perf_counter()
    part = Part.from_dict(part_dict(ring, points=pts.tolist()))
    new, on = insert_points_in_ring(part.outer, part.mesh_options.points, 1e-9 * part.diameter)
    assert time.perf_counter() - t0 < 5.0
    assert on.sum() == 5_000 and len(new) == 20_000 + 5_000 - 500  # 500 were at vertices


def test_too_many_mesh_points_are_refused():
    pts = np.zeros((limits.MAX_MESH_POINTS + 1, 2)).tolist()
    with pytest.raises(PartError, match=r"^mesh\.points: 50,001 points, more than the limit"):
        Part.from_dict(part_dict([[0, 0], [1, 0], [1, 1], [0, 1]], points=pts))
    limits.check_mesh_points(limits.MAX_MESH_POINTS)        # just at the limit: accepted


def test_paper_plan_on_3000_vertex_circle_is_refused_before_the_work(tmp_path, capsys):
    f = tmp_path / "circle3000.json"
    f.write_text(json.dumps(part_dict(circle(3000))))
    took = one_line_error(capsys, ["plan", str(f), "--model", "paper", "--quiet"],
                          r"^error: --model paper: the mesh has 3,000 jaw nodes on its boundary, "
                          r"more than the limit 1,200 .*coarsen the boundary")
    assert took < 8.0


def test_slice_resolution_4000_is_refused_before_meshing(capsys, examples_dir, tmp_path):
    fingers = tmp_path / "f.json"
    fingers.write_text(json.dumps({"units": "mm", "fingers": [{"type": "point", "at": [0, 5]}]}))
    took = one_line_error(capsys, ["slice", str(examples_dir / "rectangle.json"), "--node", "0",
                                   "--fingers", str(fingers), "--resolution", "4000"],
                          r"^error: --resolution 4000: use 2\.\.2,000 pixels per axis")
    assert took < 3.0


def test_sliver_10_by_1e5_mm_is_refused_from_its_geometry(tmp_path, capsys):
    sliver = [[0, 0], [10, 0], [10, 1e-5], [0, 1e-5]]
    part = Part.from_dict(part_dict(sliver))
    t0 = time.perf_counter()
    with pytest.raises(PartError, match=r"^outer: the part is only 1e-05 mm wide along a 10 mm "
                                        r"edge; .*widen or remove"):
        mesh_part(part)
    assert time.perf_counter() - t0 < 1.0
    f = tmp_path / "sliver.json"
    f.write_text(json.dumps(part_dict(sliver)))
    assert one_line_error(capsys, ["mesh", str(f)], r"^error: outer: .*wide") < 3.0


def test_hole_1e7_mm_from_the_outer_ring_is_refused_on_reading(tmp_path, capsys):
    hole = circle(64, 5.0, (10.0, 5.0 + 1e-7))          # lowest point 1e-7 mm above y = 0
    square = [[0, 0], [20, 0], [20, 20], [0, 20]]
    t0 = time.perf_counter()
    with pytest.raises(PartError, match=r"^holes\[0\]: only 1e-07 mm from the outer ring \(at "
                                        r"least 2\.83e-05 mm"):
        Part.from_dict(part_dict(square, [hole]))
    assert time.perf_counter() - t0 < 1.0
    # two holes nearly touching: both named
    h1 = [[2, 2], [2, 8], [8, 8], [8, 2]]
    h2 = [[8 + 1e-8, 2], [8 + 1e-8, 8], [12, 8], [12, 2]]
    with pytest.raises(PartError, match=r"^holes\[0\] and holes\[1\]: only 1e-08 mm apart"):
        Part.from_dict(part_dict(square, [h1, h2[::-1]]))
    f = tmp_path / "hole.json"
    f.write_text(json.dumps(part_dict(square, [hole])))
    assert one_line_error(capsys, ["mesh", str(f)], r"^error: holes\[0\]: only 1e-07 mm") < 3.0


# --------------------------------------------------------------------------- just under
def test_mesh_estimate_tracks_the_mesher_on_small_parts():
    cases = [
        ([np.array([[0, 0], [12, 0], [12, 20], [0, 20]], float)], 0.05),
        ([circle(2000)], 314.0 / 400),
        ([np.array([[0, 0], [10, 0], [10, 0.01], [0, 0.01]], float)], 0.1 / 400),
        ([np.array([[0, 0], [20, 0], [20, 20], [0, 20]], float), circle(200, 5, (10, 5.001))[::-1]],
         1.0),
    ]
    for rings, max_area in cases:
        est = limits.estimate_triangles(rings, max_area, 30.0).triangles
        n = mesh_part(Part.from_dict(part_dict(rings[0], rings[1:], max_area=max_area))).n_triangles
        assert 0.6 < est / n < 1.8, (est, n)


def test_mesh_just_under_the_limits_is_accepted_by_the_check():
    block = [np.array([[0, 0], [12, 0], [12, 20], [0, 20]], float) * 1e-3]
    per_area = limits._PER_AREA[-3]
    ma = 240e-6 * per_area / (0.99 * limits.MAX_TRIANGLES)
    est = limits.check_mesh_size(block, ma, 30.0)
    assert 0.95 * limits.MAX_TRIANGLES < est.triangles <= limits.MAX_TRIANGLES
    with pytest.raises(PartError, match="max_area"):
        limits.check_mesh_size(block, ma * 0.9, 30.0)
    # a strip whose narrow feature needs just under MAX_THIN_ELEMENTS boundary elements
    L = 10e-3
    w = 2 * L / (limits.MAX_THIN_ELEMENTS * 0.98)
    strip = [np.array([[0, 0], [L, 0], [L, w], [0, w]])]
    est = limits.check_mesh_size(strip, L * w / 400, 30.0)
    assert 0.9 * limits.MAX_THIN_ELEMENTS < est.thin_elements <= limits.MAX_THIN_ELEMENTS
    with pytest.raises(PartError, match="^outer: the part is only"):
        limits.check_mesh_size([strip[0] * [1, 0.9]], L * w / 400, 30.0)


def test_hole_just_farther_than_the_minimum_gap_is_accepted():
    square = [[0, 0], [20, 0], [20, 20], [0, 20]]
    gap = 2 * limits.MIN_GAP_FRACTION * 20 * np.sqrt(2)   # 2 × the minimum, mm
    hole = [[5, gap], [5, 6], [15, 6], [15, gap]]
    part = Part.from_dict(part_dict(square, [hole]))
    assert len(part.holes) == 1
    with pytest.raises(PartError, match=r"^holes\[0\]: only"):
        Part.from_dict(part_dict(square, [[[5, gap / 3], [5, 6], [15, 6], [15, gap / 3]]]))


def test_the_mesher_is_capped_and_its_result_checked(monkeypatch):
    """A low estimate cannot run away: Triangle's Steiner points are capped and a mesh
    above the maximum is refused after meshing."""
    part = Part.from_dict(part_dict([[0, 0], [12, 0], [12, 20], [0, 20]], max_area=0.2))
    monkeypatch.setattr(limits, "MAX_TRIANGLES", 500)
    monkeypatch.setattr(limits, "check_mesh_size", lambda *a, **k: None)
    with pytest.raises(MeshError, match=r"^mesh\.max_area = 0\.2 mm²: the mesh has .* triangles, "
                                        r"more than the limit 500"):
        mesh_part(part)
    with pytest.raises(MeshError, match="limit 500"):
        limits.check_mesh_result(501, 1e-6)
    limits.check_mesh_result(500, 1e-6)


def _fake_mesh(n_outer, n_nodes, n_triangles, n_hole=0, area=1e-4, diameter=0.0125):
    loops = [np.arange(n_outer)] + ([np.arange(n_outer, n_outer + n_hole)] if n_hole else [])
    return SimpleNamespace(loops=loops, n_nodes=n_nodes, n_triangles=n_triangles,
                           areas=np.full(4, area / 4), diameter=diameter, material=None)


def test_plan_sizes_just_under_the_limits_are_accepted():
    P = limits.MAX_BOUNDARY_NODES_PAPER
    check_paper_size(_fake_mesh(P, 3 * P, 5 * P), plan=True)
    with pytest.raises(GraspError, match=r"^--model paper: the mesh has 1,201 jaw nodes"):
        check_paper_size(_fake_mesh(P + 1, 3 * P, 5 * P))
    # expanding grasps pair the nodes of every loop
    with pytest.raises(GraspError, match="jaw nodes"):
        check_paper_size(_fake_mesh(P, 3 * P, 5 * P, n_hole=10), mode="expanding")
    Q = limits.MAX_BOUNDARY_NODES_PADS
    check_pads_size(_fake_mesh(Q, 3 * Q, 5 * Q), solvers=2, n_axes=36 * 40)
    with pytest.raises(GraspError, match=r"^--model pads: the mesh has 2,001 boundary nodes"):
        check_pads_size(_fake_mesh(Q + 1, 3 * Q, 5 * Q), solvers=2)
    with pytest.raises(GraspError, match=r"--grid-angles"):      # a plan over 2000 x 2000 axes
        check_pads_size(_fake_mesh(Q, 3 * Q, 5 * Q), n_axes=2000 * 2000)
    check_pads_size(_fake_mesh(Q, 3 * Q, 5 * Q), solvers=3, what="check")
    with pytest.raises(GraspError, match=r"^check: the mesh has 2,001 boundary nodes"):
        check_pads_size(_fake_mesh(Q + 1, 3 * Q, 5 * Q), solvers=3, what="check")
    # the averages are built in chunks (issue 25): the notched bar at 80 000 nodes with the
    # default critical distance (~1e8 element pairs) is accepted with its twin; a critical
    # distance a quarter of the part's size is refused for its work, not its memory
    bar = _fake_mesh(1500, 80_000, 160_000, area=3.42e-4, diameter=0.0323)
    est = check_pads_size(bar, solvers=2)
    assert est["averaging"] < 0.1 * limits.GB
    with pytest.raises(GraspError, match="critical distance.*the work of one evaluation"):
        check_pads_size(_fake_mesh(1500, 80_000, 160_000, area=3.42e-4, diameter=0.3))
    # --refine 3 on a 30 000-triangle mesh: the finest has 480 000 triangles
    with pytest.raises(GraspError, match=r"^--refine 3: the finest mesh would have about 480,000"):
        check_pads_size(_fake_mesh(200, 15_000, 30_000), refine=3)
    # strain responses of the planner: what the budget leaves after the model
    limits.check_strain_responses(P, 5_000, 8_000)
    with pytest.raises(GraspError, match="strain responses of 1,200 perimeter nodes"):
        limits.check_strain_responses(P, 50_000, 100_000)


def test_estimated_memory_of_each_documented_maximum_fits_the_budget():
    P = limits.MAX_BOUNDARY_NODES_PAPER
    paper = limits.estimate_model_bytes("paper", n_nodes=4 * P, n_triangles=7 * P, n_boundary=P,
                                        plan=True)
    assert paper["total"] <= limits.MEMORY_BUDGET
    Q = limits.MAX_BOUNDARY_NODES_PADS
    pads = limits.estimate_model_bytes("pads", n_nodes=int(3.2 * Q), n_triangles=int(5.3 * Q),
                                       n_boundary=Q, solvers=2, n_axes=36 * 40)
    assert pads["total"] <= limits.MEMORY_BUDGET
    check = limits.estimate_model_bytes("pads", n_nodes=int(3.2 * Q), n_triangles=int(5.3 * Q),
                                        n_boundary=Q, solvers=3)
    assert check["total"] <= limits.MEMORY_BUDGET
    n = limits.MAX_TRIANGLES // 2
    mesh_only = limits.estimate_model_bytes("paper", n_nodes=n, n_triangles=2 * n, n_boundary=2000,
                                            n_jaw_nodes=0)
    assert mesh_only["total"] <= limits.MEMORY_BUDGET


def test_slice_just_under_the_limits_is_accepted():
    R = limits.MAX_SLICE_RESOLUTION
    limits.check_slice_size(R, n_fingers=4)
    limits.check_slice_size(R, n_fingers=4, json_output=True)
    with pytest.raises(DeformClosureError, match=r"^--resolution 2001: use 2\.\.2,000"):
        limits.check_slice_size(R + 1)
    with pytest.raises(DeformClosureError, match=r"^--resolution 2000: .*use --resolution <= "):
        limits.check_slice_size(R, n_fingers=200, json_output=True)


def test_slice_in_blocks_equals_one_block(monkeypatch, plate_mesh):
    from deformclosure.dspace import slices
    from deformclosure.dspace.fingers import DiscFinger, PointFinger

    node = int(plate_mesh.loops[0][3])                 # on the bottom edge
    x0 = plate_mesh.nodes[node]
    fingers = [PointFinger(tuple(x0 + [1e-4, 0])), DiscFinger(tuple(x0 + [0, -1.5e-3]), 5e-4)]
    ext = (x0[0] - 2e-3, x0[0] + 2e-3, x0[1] - 2e-3, x0[1] + 2e-3)
    one = slices.dfree_slice(plate_mesh, None, node, fingers, extent=ext, resolution=(23, 17))
    monkeypatch.setattr(slices, "_SLICE_BLOCK_BYTES", 1.0)     # one row per block
    many = slices.dfree_slice(plate_mesh, None, node, fingers, extent=ext, resolution=(23, 17))
    for name in ("free", "in_dt", "obstacles"):
        np.testing.assert_array_equal(getattr(one, name), getattr(many, name))
    # the energy's matrix products see other shapes per block: BLAS kernels may round
    # the last digit differently (another CPU), a wrong block would be far off
    np.testing.assert_allclose(many.energy, one.energy, rtol=1e-12, atol=0)
    for img in (one.free, one.in_dt, one.obstacles[0], one.obstacles[1]):
        assert img.any() and not img.all()
