"""User-supplied stiffness matrices: Matrix Market and Harwell-Boeing, with checks (SPEC §1)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

from deformclosure import Mesh, StiffnessError, read_stiffness, stiffness_matrix
from deformclosure.elasticity import assemble, check_stiffness, element_stiffness


@pytest.fixture(scope="module")
def K(plate_mesh):
    return stiffness_matrix(plate_mesh)


def _rel(A, B) -> float:
    return abs(sp.csr_matrix(A) - sp.csr_matrix(B)).max() / abs(B).max()


# --------------------------------------------------------------------------- round trips
@pytest.mark.parametrize("symmetry", ["general", "symmetric"])
def test_matrix_market_round_trip(tmp_path, plate_mesh, K, symmetry):
    path = tmp_path / "K.mtx"
    scipy.io.mmwrite(str(path), K, symmetry=symmetry)
    back = read_stiffness(path, plate_mesh)
    assert sp.isspmatrix_csr(back) or isinstance(back, sp.csr_array)
    assert back.shape == K.shape
    assert _rel(back, K) <= 1e-15


@pytest.mark.parametrize("suffix", [".rua", ".rb", ".hb"])
def test_harwell_boeing_round_trip(tmp_path, plate_mesh, K, suffix):
    path = tmp_path / f"K{suffix}"
    scipy.io.hb_write(str(path), K.tocsc())
    assert _rel(read_stiffness(path, plate_mesh), K) <= 1e-15


def test_harwell_boeing_symmetric_lower_triangle(tmp_path, plate_mesh, K):
    """FEM codes write symmetric stiffness as RSA: one triangle stored."""
    path = tmp_path / "K.rsa"
    scipy.io.hb_write(str(path), sp.tril(K).tocsc())
    lines = path.read_text().splitlines(keepends=True)
    assert lines[2].startswith("RUA")
    lines[2] = "RSA" + lines[2][3:]
    path.write_text("".join(lines))
    assert _rel(read_stiffness(path, plate_mesh), K) <= 1e-15


# --------------------------------------------------------------------------- refusals
def test_wrong_shape(tmp_path, plate_mesh, K):
    path = tmp_path / "K.mtx"
    scipy.io.mmwrite(str(path), K[:-2, :-2])
    with pytest.raises(StiffnessError, match="shape"):
        read_stiffness(path, plate_mesh)


def test_asymmetric(tmp_path, plate_mesh, K):
    bad = K.tolil()
    bad[0, 5] += 1e-3 * abs(K).max()
    path = tmp_path / "K.mtx"
    scipy.io.mmwrite(str(path), bad.tocsr())
    with pytest.raises(StiffnessError, match="not symmetric"):
        read_stiffness(path, plate_mesh)


def test_missing_rigid_modes(plate_mesh, K):
    # A grounded spring at every DOF: SPD, so no rigid mode is left.
    with pytest.raises(StiffnessError, match="rigid modes"):
        check_stiffness(K + 1e-3 * abs(K).max() * sp.eye(K.shape[0]), plate_mesh.nodes)
    # Row and column of one DOF zeroed: symmetric, but rigid motions now load the others.
    bad = K.tolil()
    bad[7, :] = 0
    bad[:, 7] = 0
    with pytest.raises(StiffnessError, match="rigid modes"):
        check_stiffness(bad.tocsr(), plate_mesh.nodes)
    # The stiffness of another mesh with the same number of nodes.
    other = plate_mesh.rotated(0.7)
    with pytest.raises(StiffnessError, match="rigid modes"):
        check_stiffness(stiffness_matrix(other), plate_mesh.nodes)


def test_two_disconnected_pieces_have_extra_zero_modes(plate_mesh):
    """Each piece has rigid modes, so K r = 0 holds; the 3 extra zero modes must be found."""
    n = plate_mesh.n_nodes
    nodes = np.vstack([plate_mesh.nodes, plate_mesh.nodes + [0.04, 0.0]])
    tris = np.vstack([plate_mesh.triangles, plate_mesh.triangles + n])
    K2 = assemble(tris, element_stiffness(nodes, tris, plate_mesh.material), 2 * n)
    with pytest.raises(StiffnessError, match="singular"):
        check_stiffness(K2, nodes)


def test_node_without_elements_is_an_extra_zero_mode(plate_mesh):
    """Drop the elements of one boundary node: K r = 0 still holds, the node is free."""
    node = int(plate_mesh.outer_loop[3])
    Ke = element_stiffness(plate_mesh.nodes, plate_mesh.triangles, plate_mesh.material)
    Ke[np.any(plate_mesh.triangles == node, axis=1)] = 0.0
    K = assemble(plate_mesh.triangles, Ke, plate_mesh.n_nodes)
    with pytest.raises(StiffnessError, match="singular"):
        check_stiffness(K, plate_mesh.nodes)


def test_non_finite_and_zero(plate_mesh, K):
    bad = K.copy()
    bad.data[3] = np.nan
    with pytest.raises(StiffnessError, match="non-finite"):
        check_stiffness(bad, plate_mesh.nodes)
    with pytest.raises(StiffnessError, match="all zero"):
        check_stiffness(sp.csr_matrix(K.shape), plate_mesh.nodes)


def test_unreadable_files(tmp_path, plate_mesh):
    p = tmp_path / "K.mtx"
    p.write_text("%%MatrixMarket matrix coordinate real general\n3 3 1\n1 1 oops\n")
    with pytest.raises(StiffnessError, match="cannot read"):
        read_stiffness(p, plate_mesh)
    p = tmp_path / "K.rua"
    p.write_text("not a Harwell-Boeing file\n")
    with pytest.raises(StiffnessError):
        read_stiffness(p, plate_mesh)
    p = tmp_path / "K.csv"
    p.write_text("1,2\n")
    with pytest.raises(StiffnessError, match="unknown stiffness format"):
        read_stiffness(p, plate_mesh)
    with pytest.raises(StiffnessError, match="cannot read"):
        read_stiffness(tmp_path / "missing.mtx", plate_mesh)


def test_supplied_k_of_a_far_away_mesh_is_accepted(plate_mesh):
    """The rigid-mode check must not be fooled by coordinates far from the origin."""
    far: Mesh = plate_mesh.translated([250.0, -400.0])
    K = stiffness_matrix(far)
    assert _rel(check_stiffness(K, far.nodes), K) == 0.0
