"""Critical-distance maxima without the full operator (SPEC §6; issue 25 item 1).

:class:`DiscAverage` must give the numbers of the full averaging operator ``W`` — the
maximum over the elements of the averaged strain magnitude, the averaged tensors, and the
elastic-limit crossing along a path — while building only the rows the bound cannot
exclude. The reference is the operator as it was built before (``query_pairs`` over every
centroid pair, a full CSR matrix), copied here so the comparison stays independent of the
package's code; ``W @ E`` and numpy's max/argmax give the expected values.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

import deformclosure.elasticity.critical_distance as cd
from deformclosure import Part, mesh_part
from deformclosure.elasticity.critical_distance import (DiscAverage, averaged_strain_maximum,
                                                        averaged_strains, disc_average)
from deformclosure.landscape.limit import first_limit_crossing, path_elastic_limit
from deformclosure.mesh.core import Mesh

REL = 1e-12


# --------------------------------------------------------------------------- the reference
def reference_operator(mesh, ell: float) -> sp.csr_matrix:
    """The averaging operator as the package built it before issue 25: every centroid pair
    within ``ell`` (``cKDTree.query_pairs``), area weights normalised per row."""
    tri, nodes = np.asarray(mesh.triangles), np.asarray(mesh.nodes, float)
    m = len(tri)
    c = nodes[tri].mean(axis=1)
    d1, d2 = nodes[tri[:, 1]] - nodes[tri[:, 0]], nodes[tri[:, 2]] - nodes[tri[:, 0]]
    areas = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    diag = np.arange(m)
    if ell > 0.0:
        pairs = cKDTree(c).query_pairs(ell, output_type="ndarray")
        rows = np.concatenate([diag, pairs[:, 0], pairs[:, 1]])
        cols = np.concatenate([diag, pairs[:, 1], pairs[:, 0]])
    else:
        rows = cols = diag
    w = areas[cols]
    w /= np.bincount(rows, weights=w, minlength=m)[rows]
    return sp.csr_matrix((w, (rows, cols)), shape=(m, m))


def magnitude(T: np.ndarray) -> np.ndarray:
    """Largest absolute eigenvalue of the 2×2 strain tensors (numpy's eigvalsh)."""
    e = np.asarray(T).reshape(-1, 3)
    M = np.empty((len(e), 2, 2))
    M[:, 0, 0], M[:, 1, 1] = e[:, 0], e[:, 1]
    M[:, 0, 1] = M[:, 1, 0] = 0.5 * e[:, 2]
    return np.abs(np.linalg.eigvalsh(M)).max(axis=1).reshape(np.shape(T)[:-1])


def reference_averages(W, E: np.ndarray) -> np.ndarray:
    return np.stack([W @ E[f] for f in range(len(E))])


def assert_maxima(disc: DiscAverage, W, E: np.ndarray) -> None:
    """Values within REL of ``max(W @ E)``; each element attains its maximum (within REL:
    mirror elements of a symmetric part tie up to rounding)."""
    ref = magnitude(reference_averages(W, E))                         # (k, m)
    want = ref.max(axis=1)
    scale = magnitude(E).max(axis=1)
    values, elements = disc.maxima(E)
    np.testing.assert_allclose(values, want, rtol=REL, atol=1e-14 * scale.max(initial=0))
    got = ref[np.arange(len(E)), elements]
    np.testing.assert_allclose(got, want, rtol=REL, atol=1e-14 * scale.max(initial=0))
    single_v, single_e = disc.maxima(E[0])
    assert single_v == values[0] and single_e == elements[0]


# --------------------------------------------------------------------------- random meshes
def grid_mesh(rng, nx: int, ny: int, jitter: float, hole: bool, scale: float,
              offset: float, stretch: float) -> Mesh:
    """A jittered ``nx × ny`` grid of cells split into triangles, optionally with a
    rectangular hole, scaled and moved (far from the origin when ``offset`` is large)."""
    x, y = np.meshgrid(np.arange(nx + 1.0), np.arange(ny + 1.0), indexing="ij")
    p = np.column_stack([x.ravel(), y.ravel()])
    inner = (p[:, 0] > 0) & (p[:, 0] < nx) & (p[:, 1] > 0) & (p[:, 1] < ny)
    p[inner] += rng.uniform(-jitter, jitter, size=(inner.sum(), 2))
    idx = np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)
    skip = set()
    if hole and nx >= 3 and ny >= 3:
        i0, j0 = rng.integers(1, nx - 1), rng.integers(1, ny - 1)
        i1, j1 = rng.integers(i0 + 1, nx), rng.integers(j0 + 1, ny)
        skip = {(i, j) for i in range(i0, i1) for j in range(j0, j1)}
    tri = []
    for i in range(nx):
        for j in range(ny):
            if (i, j) in skip:
                continue
            a, b, c, d = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
            tri += [[a, b, c], [a, c, d]] if (i + j) % 2 else [[a, b, d], [b, c, d]]
    tri = np.array(tri)
    used = np.unique(tri)
    remap = np.full(len(p), -1)
    remap[used] = np.arange(len(used))
    nodes = p[used] * [scale * stretch, scale] + offset
    return Mesh.from_arrays(nodes, remap[tri])


def fields(rng, mesh: Mesh, k: int, kind: str) -> np.ndarray:
    """``k`` strain fields (k, m, 3) of one kind: noise, a few spikes, smooth, a 1/√r
    corner-like concentration, or zero."""
    m = mesh.n_triangles
    c = mesh.nodes[mesh.triangles].mean(axis=1)
    c = (c - c.mean(0)) / max(np.ptp(c, axis=0).max(), 1e-300)
    E = np.empty((k, m, 3))
    for f in range(k):
        if kind == "noise":
            E[f] = rng.normal(size=(m, 3))
        elif kind == "spikes":
            E[f] = 1e-3 * rng.normal(size=(m, 3))
            hit = rng.integers(0, m, rng.integers(1, 6))
            E[f, hit] = rng.normal(size=(len(hit), 3)) * rng.uniform(1, 100, (len(hit), 1))
        elif kind == "smooth":
            a = rng.normal(size=(3, 3))
            E[f] = a[0] + c[:, :1] * a[1] + c[:, 1:] * a[2]
        elif kind == "corner":
            x0 = c[rng.integers(0, m)]
            r = np.linalg.norm(c - x0, axis=1) + 1e-3
            E[f] = rng.normal(size=3) / np.sqrt(r)[:, None] + 0.1 * rng.normal(size=(m, 3))
        else:
            E[f] = 0.0
    return E * 10.0 ** rng.uniform(-6, 0)


mesh_args = st.fixed_dictionaries({
    "nx": st.integers(1, 14), "ny": st.integers(1, 14), "jitter": st.floats(0.0, 0.3),
    "hole": st.booleans(), "scale": st.sampled_from([1e-3, 1.0, 7.3]),
    "offset": st.sampled_from([0.0, -2.5, 1e3]), "stretch": st.floats(0.3, 3.0)})
# ℓ in cells: 0, within an element, a few elements, the whole part and more
ell_cells = st.one_of(st.just(0.0), st.floats(0.05, 1.0), st.floats(1.0, 6.0),
                      st.floats(15.0, 60.0))
kinds = st.sampled_from(["noise", "spikes", "smooth", "corner", "zero"])


@settings(max_examples=120, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), args=mesh_args, cells=ell_cells,
       k=st.integers(1, 4), kind=kinds, chunk=st.sampled_from([None, 7, 300]))
def test_maxima_and_averages_equal_the_full_operator(seed, args, cells, k, kind, chunk):
    rng = np.random.default_rng(seed)
    mesh = grid_mesh(rng, **args)
    ell = cells * args["scale"] * min(1.0, args["stretch"])
    E = fields(rng, mesh, k, kind)
    if kind != "zero" and k > 1 and rng.random() < 0.3:
        E[rng.integers(0, k)] = 0.0                      # a field at rest in the stack
    W = reference_operator(mesh, ell)
    old = cd.CHUNK_PAIRS
    try:
        if chunk is not None:
            cd.CHUNK_PAIRS = chunk                       # many chunks, one row each at 7
        disc = DiscAverage(mesh, ell)
        assert_maxima(disc, W, E)
        avg = disc.averaged(E)
        ref = reference_averages(W, E)
        scale = np.abs(E).max(initial=0.0)
        np.testing.assert_allclose(avg, ref, rtol=0, atol=REL * scale)
        rows = rng.permutation(mesh.n_triangles)[: rng.integers(1, mesh.n_triangles + 1)]
        np.testing.assert_allclose(disc.averaged(E, rows), ref[:, rows], rtol=0,
                                   atol=REL * scale)
        np.testing.assert_allclose(disc.averaged(E[0], rows), ref[0, rows], rtol=0,
                                   atol=REL * scale)
    finally:
        cd.CHUNK_PAIRS = old


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), args=mesh_args, cells=ell_cells)
def test_grid_bounds_hold_every_disc(seed, args, cells):
    """The cell-grid bounds: no disc holds more elements than its size bound, and no
    element of a disc has a larger magnitude than the disc's bound."""
    rng = np.random.default_rng(seed)
    mesh = grid_mesh(rng, **args)
    ell = cells * args["scale"] * min(1.0, args["stretch"])
    W = reference_operator(mesh, ell)
    disc = DiscAverage(mesh, ell)
    mag = rng.random(mesh.n_triangles) ** 8
    most = np.array([mag[W.indices[W.indptr[i]:W.indptr[i + 1]]].max()
                     for i in range(mesh.n_triangles)])
    assert np.all(disc.bound(mag) >= most)
    if ell > 0:
        assert np.all(disc.disc_size_bound >= np.diff(W.indptr))
    # the pattern of the rows is the reference's exactly
    R = disc.operator_rows(np.arange(mesh.n_triangles))
    assert (R != 0).nnz == W.nnz and abs((R != 0) - (W != 0)).nnz == 0


# --------------------------------------------------------------------------- the limit rule
@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), args=mesh_args, cells=ell_cells,
       k=st.integers(2, 6), from_rest=st.booleans(), level=st.floats(0.05, 1.5))
def test_path_limit_equals_the_rule_on_every_averaged_element(seed, args, cells, k,
                                                              from_rest, level):
    rng = np.random.default_rng(seed)
    mesh = grid_mesh(rng, **args)
    ell = cells * args["scale"] * min(1.0, args["stretch"])
    # a loading path: the strains grow from (or near) rest along k breakpoints
    steps = np.cumsum(rng.uniform(0.2, 1.0, size=(k, 1, 1)), axis=0)
    E = fields(rng, mesh, 1, rng.choice(["spikes", "smooth", "corner", "noise"]))[0] * steps
    E = E + rng.normal(size=E.shape) * 0.2 * np.abs(E).max() * np.arange(k)[:, None, None] / k
    if from_rest:
        E[0] = 0.0
    W = reference_operator(mesh, ell)
    Ebar = reference_averages(W, E)
    e_bp = magnitude(Ebar).max(axis=1)
    e_L = level * e_bp.max() if e_bp.max() > 0 else 1.0
    # a breakpoint exactly at e_L: which side it falls on is rounding, in both codes
    assume(np.all(np.abs(e_bp - e_L) > 1e-9 * e_L))
    want = first_limit_crossing(Ebar, e_L)
    got = path_elastic_limit(DiscAverage(mesh, ell), E, e_L)
    np.testing.assert_allclose(got.e_breakpoints, e_bp, rtol=REL, atol=1e-300)
    assert got.crossing.piece == want.piece and got.crossing.reached == want.reached
    assert got.crossing.fraction == pytest.approx(want.fraction, rel=REL, abs=1e-15)
    at = want.interpolate(Ebar) if want.reached else Ebar[-1]
    ref = magnitude(at)
    assert ref[got.critical_element] == pytest.approx(ref.max(), rel=1e-9)
    elem = magnitude(want.interpolate(E) if want.reached else E[-1]).max()
    assert got.element_max == pytest.approx(elem, rel=REL)


# --------------------------------------------------------------------------- real parts
def _holed_part() -> Part:
    return Part.from_dict({
        "name": "plate", "units": "mm",
        "outer": [[0, 0], [20, 0], [20, 10], [0, 10]],
        "holes": [[[5, 3], [8, 3], [8, 7], [5, 7]], [[13, 5], [15, 3], [17, 5], [15, 7]]],
        "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 1.0,
                     "elastic_limit_strain": 0.1, "plane": "stress"},
    })


@pytest.mark.parametrize("frac", [0.0, 0.005, 0.02, 0.1, 1.5])
def test_holed_and_notched_parts_and_their_solved_strains(frac):
    """Meshes from the mesher (holes, a notch) and strain fields of solved loads."""
    from deformclosure import notched_part
    from deformclosure.elasticity import FreeBodySolver, element_strains, stiffness_matrix

    rng = np.random.default_rng(3)
    for part, area in ((_holed_part(), 0.4e-6), (notched_part(), 0.5e-6)):
        mesh = mesh_part(part, max_area=area)
        ell = frac * mesh.diameter
        solver = FreeBodySolver(stiffness_matrix(mesh), mesh.nodes)
        b = mesh.perimeter_nodes
        E = []
        for _ in range(3):        # balanced random loads on the boundary
            f = np.zeros((mesh.n_nodes, 2))
            f[b] = rng.normal(size=(len(b), 2))
            f[b] -= f[b].mean(0)
            E.append(element_strains(mesh, solver.solve(f.ravel())))
        E = np.stack(E)
        W = reference_operator(mesh, ell)
        assert_maxima(DiscAverage(mesh, ell), W, E)
        np.testing.assert_allclose(averaged_strain_maximum(mesh, E, ell),
                                   magnitude(reference_averages(W, E)).max(axis=1), rtol=REL)
        np.testing.assert_allclose(averaged_strains(mesh, E, ell), reference_averages(W, E),
                                   rtol=0, atol=REL * np.abs(E).max())


def test_pad_elastic_limit_is_unchanged_and_prunes():
    """A pads grasp of the notched bar: the default (pruned) limit equals the limit with
    the full operator given, and averages a fraction of the operator's rows."""
    from deformclosure import notched_part
    from deformclosure.pads import GraspAxis, Pad, PadContact
    from deformclosure.pads.limit import critical_distance_of, pad_elastic_limit, pad_strain_at

    mesh = mesh_part(notched_part(), max_area=0.2e-6)
    pc = PadContact(mesh)
    curve = pc.curve(GraspAxis.through([0.015, 0.0], [0.015, 0.012]), Pad(0.0, 0.002), 0.0)
    ell = critical_distance_of(mesh)
    W = reference_operator(mesh, ell)
    e_L = mesh.material.elastic_limit_strain
    disc = disc_average(mesh, ell)
    built = []
    for level in (e_L, 0.3 * e_L, 0.05 * e_L):
        old = pad_elastic_limit(pc, curve, level, operator=W)
        before = disc.pairs_built
        new = pad_elastic_limit(pc, curve, level)
        built.append(disc.pairs_built - before)
        assert new.sigma_L == pytest.approx(old.sigma_L, rel=REL, abs=1e-15)
        assert new.critical_element == old.critical_element
        np.testing.assert_allclose(new.e_breakpoints, old.e_breakpoints, rtol=REL)
        assert new.element_max_at_limit == pytest.approx(old.element_max_at_limit, rel=REL)
    assert disc is disc_average(mesh, ell)                   # kept with the mesh
    assert max(built) < 0.5 * W.nnz, (built, W.nnz)         # each limit: a fraction
    sigma = 0.5 * (curve.sigma0 + curve.sigma_end)
    u = pc.displacement(pc.load_vector(curve, curve.path.multipliers(curve.delta(sigma))))
    E = pc.element_strains(u[:, None])[0]
    assert pad_strain_at(pc, curve, sigma) == pytest.approx(magnitude(W @ E).max(), rel=REL)


def test_edge_cases_of_the_maximum():
    mesh = Mesh.from_arrays(np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
                            np.array([[0, 1, 2], [0, 2, 3]]))
    gap = math.sqrt(5) / 3                                   # centroid distance
    e = np.array([[0.03, 0.0, 0.0], [0.0, 0.0, 0.06]])
    # separate discs: the element magnitudes; one disc: the area-weighted mean 2/3, 1/3
    assert DiscAverage(mesh, gap - 1e-9).maxima(e) == (0.03, 0)
    v, i = DiscAverage(mesh, gap + 1e-9).maxima(e)
    assert v == pytest.approx(0.01 * (1 + math.sqrt(2)), rel=1e-14) and i == 0
    # all-zero field: 0 at the first element, like numpy's argmax
    assert DiscAverage(mesh, 1.0).maxima(np.zeros((2, 3))) == (0.0, 0)
    # non-finite strains propagate like W @ E
    bad = e.copy()
    bad[1, 0] = np.nan
    assert math.isnan(DiscAverage(mesh, 1.0).maxima(bad)[0])
    with pytest.raises(cd.MeshError, match="strains"):
        DiscAverage(mesh, 1.0).maxima(np.zeros((3, 3)))
    with pytest.raises(cd.GraspError, match="critical_distance"):
        DiscAverage(mesh, -1.0)


def test_a_full_operator_beyond_the_memory_budget_is_refused_but_averages_are_not():
    """10 880 triangles with one disc over the whole part: W would hold 1.2e8 non-zeros
    (7 GB); the maximum needs none of them stored."""
    from deformclosure import notched_part
    from deformclosure.errors import GraspError

    mesh = mesh_part(notched_part(), max_area=0.05e-6)
    with pytest.raises(GraspError, match="full averaging operator.*DiscAverage") as info:
        cd.averaging_operator(mesh, 1.0)
    assert "\n" not in str(info.value)
    E = np.broadcast_to([1e-3, -2e-3, 5e-4], (mesh.n_triangles, 3))   # homogeneous
    assert averaged_strain_maximum(mesh, E, 1.0) == pytest.approx(magnitude(E[:1])[0],
                                                                  rel=1e-12)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), args=mesh_args, cells=ell_cells,
       k=st.integers(2, 9), kind=kinds, group=st.integers(1, 4))
def test_maxima_in_groups_of_fields_equal_all_at_once(seed, args, cells, k, kind, group):
    """Fields taken in groups (bounded memory for many breakpoints, issue 25) give the
    same maxima and elements, bit for bit, as all fields at once, and both equal the full
    operator's."""
    rng = np.random.default_rng(seed)
    mesh = grid_mesh(rng, **args)
    ell = cells * args["scale"] * min(1.0, args["stretch"])
    E = fields(rng, mesh, k, kind)
    disc = DiscAverage(mesh, ell)
    old = cd.FIELD_CHUNK_BYTES
    try:
        cd.FIELD_CHUNK_BYTES = 1e300
        v_all, e_all = disc.maxima(E)
        ncells = disc._grid_shape[0] * disc._grid_shape[1] if ell > 0 else 1
        cd.FIELD_CHUNK_BYTES = group * cd.FIELD_BYTES_PER_CELL * ncells
        v_grp, e_grp = disc.maxima(E)
    finally:
        cd.FIELD_CHUNK_BYTES = old
    np.testing.assert_array_equal(v_grp, v_all)
    np.testing.assert_array_equal(e_grp, e_all)
    assert_maxima(disc, reference_operator(mesh, ell), E)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), args=mesh_args, cells=ell_cells,
       cap=st.sampled_from([0, 200, 5_000, 10**9]), requests=st.integers(1, 6))
def test_kept_rows_equal_the_full_operator(seed, args, cells, cap, requests):
    """Rows of ``W`` reused by :meth:`DiscAverage.reusing_rows` — with a pool that holds
    everything, one that fills and starts again (200 pairs), one that holds nothing — are
    the reference operator's rows, in the order asked (repeats included), and the maxima of
    a sequence of stacks are the reference's."""
    rng = np.random.default_rng(seed)
    mesh = grid_mesh(rng, **args)
    ell = cells * args["scale"] * min(1.0, args["stretch"])
    W = reference_operator(mesh, ell)
    m = mesh.n_triangles
    disc = DiscAverage(mesh, ell)
    with disc.reusing_rows(max_bytes=12 * cap):
        with disc.reusing_rows():                       # nested: the outer pool serves
            pass
        for _ in range(requests):
            rows = rng.integers(0, m, int(rng.integers(1, 2 * m + 1)))
            got = disc.operator_rows(rows)
            want = W[rows]
            assert got.shape == want.shape
            np.testing.assert_allclose(got.toarray(), want.toarray(), rtol=1e-14, atol=0)
            assert_maxima(disc, W, fields(rng, mesh, int(rng.integers(1, 4)), "corner"))
    assert disc._pool is None                           # dropped at the end


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), args=mesh_args, cells=ell_cells, k=st.integers(1, 6),
       kind=kinds)
def test_maxima_of_a_field_fastest_stack_equal_field_by_field(seed, args, cells, k, kind):
    """A stack laid out field-fastest (a view of a ``(3m, k)`` product, as the solver's
    strains are) gives the same maxima bit for bit whether its magnitudes are taken in one
    pass or one field at a time (the memory bound), and they are the full operator's."""
    rng = np.random.default_rng(seed)
    mesh = grid_mesh(rng, **args)
    ell = cells * args["scale"] * min(1.0, args["stretch"])
    E = fields(rng, mesh, k, kind)
    view = np.ascontiguousarray(E.transpose(1, 2, 0)).reshape(-1, k).reshape(-1, 3, k) \
        .transpose(2, 0, 1)
    assert not view.flags.c_contiguous or k == 1
    disc = DiscAverage(mesh, ell)
    old = cd.FIELD_CHUNK_BYTES
    try:
        one_pass = disc.maxima(view)
        cd.FIELD_CHUNK_BYTES = 8.0 * k * mesh.n_triangles - 1.0     # field by field
        by_field = disc.maxima(view)
    finally:
        cd.FIELD_CHUNK_BYTES = old
    np.testing.assert_array_equal(one_pass[0], by_field[0])
    np.testing.assert_array_equal(one_pass[1], by_field[1])
    assert_maxima(disc, reference_operator(mesh, ell), view)
