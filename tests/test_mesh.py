"""Meshes: quality, inserted points, boundary loops, validation, file I/O (SPEC §1, §5)."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from deformclosure import (FreeBodySolver, Mesh, MeshError, Part, mesh_part, read_mesh,
                           rigid_modes, stiffness_matrix, write_mesh)
from deformclosure.mesh.io import mesh_from_dict, mesh_to_dict


# --------------------------------------------------------------------------- helpers
def _signed_area(ring):
    x, y = np.asarray(ring).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def boundary_edges_from_triangles(triangles) -> set[tuple[int, int]]:
    """Directed edges of CCW triangles whose reverse belongs to no triangle (brute force)."""
    directed = {(int(t[i]), int(t[(i + 1) % 3])) for t in triangles for i in range(3)}
    return {(a, b) for a, b in directed if (b, a) not in directed}


def assert_loops_are_correct(mesh: Mesh, part: Part) -> None:
    """Certificate for the boundary loops of ``mesh`` against the triangles and the part."""
    loops = mesh.loops
    assert len(loops) == 1 + len(part.holes)
    # Each loop lists its nodes once, and no node is on two loops.
    allnodes = np.concatenate(loops)
    assert len(np.unique(allnodes)) == len(allnodes)
    for lp in loops:
        assert lp.dtype == np.int64 and len(lp) >= 3
    # Every boundary edge of the triangles is in exactly one loop, with the interior on
    # its left, and the loops contain no other edge.
    loop_edges = [(int(a), int(b)) for lp in loops for a, b in zip(lp, np.roll(lp, -1))]
    assert len(loop_edges) == len(set(loop_edges))
    assert set(loop_edges) == boundary_edges_from_triangles(mesh.triangles)
    assert {tuple(e) for e in mesh.boundary_edges.tolist()} == set(loop_edges)
    # Outer counter-clockwise with the area of the part's outer ring; holes clockwise
    # with the areas of the part's holes.
    assert _signed_area(mesh.nodes[loops[0]]) == pytest.approx(_signed_area(part.outer), rel=1e-12)
    got = sorted(_signed_area(mesh.nodes[lp]) for lp in loops[1:])
    want = sorted(_signed_area(h) for h in part.holes)
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert all(a < 0 for a in got)
    # Loop nodes lie on the part's boundary; all other nodes are strictly inside.
    tol = 1e-12 * part.diameter
    on_boundary = shapely.distance(shapely.points(mesh.nodes), part.polygon.boundary) <= tol
    expected = np.zeros(mesh.n_nodes, bool)
    expected[allnodes] = True
    np.testing.assert_array_equal(on_boundary, expected)


def assert_quality(mesh: Mesh, min_angle: float, max_area: float, part: Part) -> None:
    assert mesh.min_angles().min() >= min_angle - 1e-9
    assert mesh.areas.max() <= max_area * (1 + 1e-9)
    assert np.all(mesh.areas > 0)
    # Polygonal boundaries are meshed exactly: the triangles tile the part.
    assert mesh.area == pytest.approx(part.area, rel=1e-12)


# --------------------------------------------------------------------------- quality
def test_example_meshes_meet_the_requested_quality(examples_dir):
    for f in sorted(examples_dir.glob("*.json")):
        part = Part.from_file(f)
        mesh = mesh_part(part)
        opts = part.mesh_options
        max_area = opts.max_area if opts.max_area is not None else part.area / 400
        assert_quality(mesh, opts.min_angle, max_area, part)
        assert_loops_are_correct(mesh, part)
        assert mesh.material == part.material


@pytest.mark.parametrize("min_angle", [20.0, 28.0, 33.0])
def test_min_angle_and_max_area_overrides(plate_part, min_angle):
    max_area = 0.5e-6   # 0.5 mm²
    mesh = mesh_part(plate_part, max_area=max_area, min_angle=min_angle)
    assert_quality(mesh, min_angle, max_area, plate_part)
    assert_loops_are_correct(mesh, plate_part)


def test_finer_max_area_gives_more_triangles(plate_part):
    n = [mesh_part(plate_part, max_area=a * 1e-6).n_triangles for a in (4.0, 1.0, 0.25)]
    assert n[0] < n[1] < n[2]
    # Roughly inversely proportional to max_area (Triangle fills well).
    assert 2.0 < n[2] / n[1] < 8.0


# --------------------------------------------------------------------------- inserted points
def test_inserted_points_become_nodes_on_the_right_loop(make_part):
    hexagon = [[20 + 4 * np.cos(a), 10 + 4 * np.sin(a)] for a in np.arange(6) * np.pi / 3]
    square_hole = [[5, 5], [9, 5], [9, 9], [5, 9]]
    outer = [[0, 0], [30, 0], [30, 20], [0, 20]]
    on_outer = [[15, 0], [30, 7.3], [0, 0], [11.11, 20]]          # edges and a vertex
    h0, h1 = np.array(hexagon[0]), np.array(hexagon[1])
    on_hex = [list(0.3 * h0 + 0.7 * h1), hexagon[3]]              # hole edge and vertex
    on_square = [[7, 5], [9, 6.5]]
    interior = [[2.5, 17.5], [15, 10], [25.5, 3.25], [7, 7.5 + 3]]
    points = on_outer + on_hex + on_square + interior
    part = make_part(outer, holes=[square_hole, hexagon], points=points, max_area=6.0)
    mesh = mesh_part(part)
    assert_loops_are_correct(mesh, part)
    assert_quality(mesh, 30.0, 6e-6, part)
    loop_of = mesh.loop_of()
    pts = np.asarray(points, float) * 1e-3
    ids = [mesh.find_node(p, tol=1e-12) for p in pts]
    # Which loop each point must be on: outer 0, holes in the order the mesh lists them.
    hole_index = {}
    for k, lp in enumerate(mesh.hole_loops, start=1):
        c = mesh.nodes[lp].mean(axis=0) * 1e3
        hole_index["hex" if c[0] > 12 else "square"] = k
    want = ([0] * len(on_outer) + [hole_index["hex"]] * len(on_hex)
            + [hole_index["square"]] * len(on_square) + [-1] * len(interior))
    np.testing.assert_array_equal(loop_of[ids], want)


def test_points_given_to_mesh_part_are_inserted(plate_part):
    extra = np.array([[0.0, 0.0123], [0.03, 0.0077], [0.005, 0.005], [0.015, 0.005]])
    mesh = mesh_part(plate_part, points=extra)
    for p in extra:
        mesh.find_node(p, tol=1e-12)
    assert_loops_are_correct(mesh, plate_part)


def test_find_node_refuses_far_points(plate_mesh):
    with pytest.raises(MeshError, match="no mesh node"):
        plate_mesh.find_node([0.0101234, 0.0101234], tol=1e-9)


# --------------------------------------------------------------------------- from_arrays
SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5]], float)
SQUARE_TRIS = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])


def test_hand_mesh_loops():
    mesh = Mesh.from_arrays(SQUARE, SQUARE_TRIS)
    assert len(mesh.loops) == 1
    np.testing.assert_array_equal(mesh.outer_loop, [0, 1, 2, 3])
    np.testing.assert_array_equal(mesh.perimeter_nodes, [0, 1, 2, 3])
    assert mesh.area == pytest.approx(1.0)
    assert mesh.diameter == pytest.approx(np.sqrt(2))
    np.testing.assert_allclose(mesh.centroid, [0.5, 0.5])


def test_clockwise_mesh_is_reoriented():
    mesh = Mesh.from_arrays(SQUARE, SQUARE_TRIS[:, ::-1])
    assert np.all(mesh.areas > 0)
    np.testing.assert_array_equal(mesh.outer_loop, [0, 1, 2, 3])


def test_two_components_are_refused():
    nodes = np.vstack([SQUARE, SQUARE + [3.0, 0.0]])
    tris = np.vstack([SQUARE_TRIS, SQUARE_TRIS + 5])
    with pytest.raises(MeshError, match="2 separate pieces"):
        Mesh.from_arrays(nodes, tris)


@pytest.mark.parametrize("nodes, tris, needle", [
    (SQUARE, [[0, 1, 4], [1, 4, 2], [2, 3, 4], [3, 0, 4]], "inverted"),
    (SQUARE, [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [0, 1, 2]], "non-manifold|overlapping"),
    ([[0, 0], [1, 0], [0.5, 0.5], [0, 1], [1, 1]], [[0, 1, 2], [2, 4, 3]], "touches itself"),
    ([[0, 0], [1, 0], [2, 0], [1, 1]], [[0, 1, 3], [1, 2, 3], [0, 1, 2]], "zero area"),
    (SQUARE, [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 5]], "node ids"),
    (np.vstack([SQUARE, [[3, 3]]]), SQUARE_TRIS, "used by no triangle"),
    (SQUARE, [[0, 1, 1], [1, 2, 4], [2, 3, 4], [3, 0, 4]], "repeats a node"),
])
def test_invalid_meshes_are_refused(nodes, tris, needle):
    with pytest.raises(MeshError, match=needle):
        Mesh.from_arrays(np.asarray(nodes, float), np.asarray(tris))


def test_hole_loops_of_an_annulus_mesh(examples_dir):
    part = Part.from_file(examples_dir / "ring.json")
    mesh = mesh_part(part)
    assert len(mesh.hole_loops) == 1
    assert_loops_are_correct(mesh, part)
    # Rebuilding from the arrays alone recovers the same loops.
    again = Mesh.from_arrays(mesh.nodes, mesh.triangles)
    for a, b in zip(again.loops, mesh.loops):
        np.testing.assert_array_equal(a, b)


# --------------------------------------------------------------------------- files
def test_mesh_json_round_trip_is_exact(plate_mesh, tmp_path):
    path = tmp_path / "m.json"
    write_mesh(plate_mesh, path)
    data = json.loads(path.read_text())
    assert data["format"] == "deformclosure-mesh/1" and data["units"] == "m"
    back = read_mesh(path)
    np.testing.assert_array_equal(back.nodes, plate_mesh.nodes)
    np.testing.assert_array_equal(back.triangles, plate_mesh.triangles)
    assert back.triangles.dtype == np.int64
    assert len(back.loops) == len(plate_mesh.loops)
    for a, b in zip(back.loops, plate_mesh.loops):
        np.testing.assert_array_equal(a, b)
    assert back.material == plate_mesh.material
    assert back.name == plate_mesh.name


def test_mesh_json_in_millimetres_is_scaled(plate_mesh):
    d = mesh_to_dict(plate_mesh)
    d["units"] = "mm"
    d["nodes"] = (plate_mesh.nodes * 1e3).tolist()
    d["material"]["thickness"] = plate_mesh.material.thickness * 1e3
    mesh = mesh_from_dict(d)
    np.testing.assert_allclose(mesh.nodes, plate_mesh.nodes, rtol=1e-14, atol=1e-18)
    assert mesh.material.thickness == pytest.approx(plate_mesh.material.thickness, rel=1e-14)


def test_boundary_in_mesh_json_is_checked(plate_mesh):
    d = mesh_to_dict(plate_mesh)
    # Starting the loop at another node is the same loop.
    d["boundary"]["outer"] = np.roll(plate_mesh.outer_loop, 5).tolist()
    mesh_from_dict(d)
    # Reversed (clockwise) outer loop.
    d["boundary"]["outer"] = plate_mesh.outer_loop[::-1].tolist()
    with pytest.raises(MeshError, match=r"boundary\.outer"):
        mesh_from_dict(d)
    # A node missing from the outer loop.
    d["boundary"]["outer"] = plate_mesh.outer_loop[:-1].tolist()
    with pytest.raises(MeshError, match=r"boundary\.outer"):
        mesh_from_dict(d)
    # Holes missing, or a hole listed counter-clockwise.
    d = mesh_to_dict(plate_mesh)
    d["boundary"]["holes"] = []
    with pytest.raises(MeshError, match=r"boundary\.holes"):
        mesh_from_dict(d)
    d["boundary"]["holes"] = [plate_mesh.hole_loops[0][::-1].tolist()]
    with pytest.raises(MeshError, match=r"boundary\.holes"):
        mesh_from_dict(d)


@pytest.mark.parametrize("suffix, fmt", [(".vtk", "vtk"), (".msh", "gmsh22"), (".vtu", "vtu")])
def test_meshio_import_drops_unused_points(plate_mesh, tmp_path, suffix, fmt):
    # A geometry point used by no triangle goes first, so every id shifts by one; a
    # boundary-line block rides along as in files written by Gmsh.
    extra = np.array([[1.0, 2.0, 0.0]])
    pts = np.vstack([extra, np.column_stack([plate_mesh.nodes, np.zeros(plate_mesh.n_nodes)])])
    cells = [("triangle", plate_mesh.triangles + 1),
             ("line", plate_mesh.boundary_edges + 1)]
    path = tmp_path / f"m{suffix}"
    meshio.write(path, meshio.Mesh(pts, cells), file_format=fmt)
    back = read_mesh(path)
    np.testing.assert_array_equal(back.nodes, plate_mesh.nodes)
    np.testing.assert_array_equal(back.triangles, plate_mesh.triangles)
    for a, b in zip(back.loops, plate_mesh.loops):
        np.testing.assert_array_equal(a, b)
    assert back.material is None
    assert read_mesh(path, material=plate_mesh.material).material == plate_mesh.material


def test_meshio_import_in_millimetres_and_clockwise(plate_mesh, tmp_path):
    path = tmp_path / "cw.vtk"
    meshio.write_points_cells(path, plate_mesh.nodes * 1e3,
                              [("triangle", plate_mesh.triangles[:, ::-1])])
    back = read_mesh(path, units="mm")
    np.testing.assert_allclose(back.nodes, plate_mesh.nodes, rtol=1e-14, atol=1e-18)
    assert np.all(back.areas > 0)
    np.testing.assert_array_equal(back.outer_loop, plate_mesh.outer_loop)


def test_meshio_file_with_other_cells_is_refused(tmp_path):
    path = tmp_path / "q.vtk"
    meshio.write_points_cells(path, np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]]),
                              [("quad", np.array([[0, 1, 2, 3]]))])
    with pytest.raises(MeshError, match="triangle"):
        read_mesh(path)


# --------------------------------------------------------------------------- random polygons
@st.composite
def star_parts(draw):
    """Star-shaped polygons about the origin, optionally with a small polygonal hole.

    Angular gaps stay below 2π/3, so every edge is at least ``0.5 r_min`` from the
    origin and a hole of radius ``0.2 r_min`` is strictly inside.
    """
    k = draw(st.integers(3, 12))
    gaps = np.array(draw(st.lists(st.floats(0.2, 1.0), min_size=k, max_size=k)))
    gaps = gaps / gaps.sum() * 2 * np.pi
    if gaps.max() >= 2 * np.pi / 3:
        gaps = np.full(k, 2 * np.pi / k) if k > 3 else np.full(3, 2 * np.pi / 3 - 1e-9)
        k = len(gaps)
    angles = np.cumsum(gaps) + draw(st.floats(0, 2 * np.pi))
    radii = np.array(draw(st.lists(st.floats(0.3, 1.0), min_size=k, max_size=k)))
    scale = draw(st.sampled_from([1e-3, 1.0, 50.0]))
    outer = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)]) * scale
    holes = []
    if draw(st.booleans()):
        kh = draw(st.integers(3, 8))
        a = np.arange(kh) * 2 * np.pi / kh + draw(st.floats(0, 1))
        rh = 0.2 * radii.min() * scale * draw(st.floats(0.3, 1.0))
        holes.append(np.column_stack([rh * np.cos(a), rh * np.sin(a)]))
    nu = draw(st.floats(-0.5, 0.49))
    plane = draw(st.sampled_from(["stress", "strain"]))
    return outer, holes, nu, plane


@settings(max_examples=25, deadline=None)
@given(spec=star_parts())
def test_random_star_parts_mesh_and_assemble(make_part, spec):
    outer, holes, nu, plane = spec
    part = make_part(outer, holes=holes, units="m", poisson_ratio=nu, plane=plane,
                     min_angle=25.0)
    mesh = mesh_part(part, max_area=part.area / 60)
    assert_loops_are_correct(mesh, part)
    assert mesh.area == pytest.approx(part.area, rel=1e-9)
    assert mesh.min_angles().min() > 0
    K = stiffness_matrix(mesh)
    R = rigid_modes(mesh.nodes) / np.array([1.0, 1.0, mesh.diameter])
    Kmax = abs(K).max()
    assert abs(K @ R).max() <= 1e-10 * Kmax
    # The free-body solver factorises and solves self-equilibrated loads exactly.
    solver = FreeBodySolver(K, mesh.nodes)
    rng = np.random.default_rng(0)
    f = rng.standard_normal(2 * mesh.n_nodes)
    Rn = rigid_modes(mesh.nodes)
    f -= Rn @ np.linalg.lstsq(Rn, f, rcond=None)[0]          # remove net force and moment
    u = solver.solve(f)
    np.testing.assert_allclose(K @ u, f, atol=1e-8 * np.abs(f).max())
    assert f @ u > 0


# --------------------------------------------------------------------------- corrupted files
_JUNK = st.one_of(
    st.none(), st.booleans(), st.integers(-2**70, 2**70),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=4),
    st.lists(st.integers(-3, 300), max_size=4),
    st.lists(st.lists(st.floats(-1e300, 1e300), max_size=3), max_size=3),
)


@settings(max_examples=30, deadline=None)
@given(edits=st.lists(st.tuples(st.sampled_from(
    [("format",), ("units",), ("nodes",), ("nodes", 3), ("nodes", 3, 1), ("triangles",),
     ("triangles", 2), ("triangles", 2, 0), ("boundary",), ("boundary", "outer"),
     ("boundary", "outer", 1), ("boundary", "holes"), ("material",),
     ("material", "poisson_ratio"), ("material", "plane"), ("name",), ("junk",)]), _JUNK),
    min_size=1, max_size=3))
def test_corrupted_mesh_files_fail_only_with_mesh_error(plate_mesh, edits):
    data = json.loads(json.dumps(mesh_to_dict(plate_mesh)))
    for path, value in edits:
        node = data
        try:
            for key in path[:-1]:
                node = node[key]
            node[path[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue
    try:
        mesh = mesh_from_dict(data)
    except MeshError as err:
        assert "\n" not in str(err)
    else:
        assert np.all(mesh.areas > 0)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 5), st.integers(0, 5), st.integers(0, 5)),
                min_size=1, max_size=8))
def test_edge_checks_agree_with_counting(tris):
    """The manifold/overlap test of ``Mesh`` (sorted integer edge keys) against counting
    the edges one by one with a Counter: the same error, or none, on random triangle sets
    (connectivity aside)."""
    from collections import Counter

    from deformclosure.mesh.core import _check_manifold_and_connected

    tri = np.array([t for t in tris if len(set(t)) == 3] or [(0, 1, 2)])
    directed = Counter((int(t[k]), int(t[(k + 1) % 3])) for t in tri for k in range(3))
    undirected = Counter(tuple(sorted(d)) for d in directed.elements())
    if max(undirected.values()) > 2:
        expect = "non-manifold"
    elif max(directed.values()) > 1:
        expect = "overlapping"
    else:
        expect = None
    try:
        _check_manifold_and_connected(tri, 6)
        got = None
    except MeshError as err:
        got = ("non-manifold" if "non-manifold" in str(err) else
               "overlapping" if "overlapping" in str(err) else "pieces")
    if expect is None:
        assert got in (None, "pieces")
    else:
        assert got == expect
