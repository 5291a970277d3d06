"""Readers accept a :class:`~deformclosure.jsonfile.Source` (a file's name and bytes, read
once) wherever they accept a path, and give the same part, material and mesh; errors name
the Source, never a temporary copy."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from deformclosure import Part, mesh_part
from deformclosure.errors import MeshError, PartError
from deformclosure.jsonfile import Source
from deformclosure.mesh.io import is_mesh_file, read_mesh, write_mesh
from deformclosure.part import read_material

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def _same_part(p: Part, q: Part) -> None:
    assert (p.name, p.units, p.material) == (q.name, q.units, q.material)
    np.testing.assert_array_equal(p.outer, q.outer)
    assert len(p.holes) == len(q.holes)
    for a, b in zip(p.holes, q.holes):
        np.testing.assert_array_equal(a, b)
    assert p.mesh_options.max_area == q.mesh_options.max_area
    assert p.mesh_options.min_angle == q.mesh_options.min_angle
    np.testing.assert_array_equal(p.mesh_options.points, q.mesh_options.points)


def _same_mesh(m, n) -> None:
    np.testing.assert_array_equal(m.nodes, n.nodes)
    np.testing.assert_array_equal(m.triangles, n.triangles)
    assert len(m.loops) == len(n.loops)
    for a, b in zip(m.loops, n.loops):
        np.testing.assert_array_equal(a, b)
    assert m.material == n.material
    assert m.name == n.name


@pytest.mark.parametrize("name", ["rectangle", "ring", "plate_with_hole"])
def test_part_from_a_source_is_the_part_from_its_file(name):
    path = EXAMPLES / f"{name}.json"
    src = Source(f"elsewhere/{name}.json", path.read_bytes())    # no such file on disk
    _same_part(Part.from_file(src), Part.from_file(path))


def test_part_source_errors_name_the_source():
    with pytest.raises(PartError, match=r"^jobs/broken\.json: not valid JSON"):
        Part.from_file(Source("jobs/broken.json", b'{"units": "mm",'))


def test_read_material_from_a_source_is_the_material_from_its_file(tmp_path):
    path = tmp_path / "rubber.json"
    path.write_text('{"units": "mm", "youngs_modulus": 2e6, "poisson_ratio": 0.1, '
                    '"thickness": 2, "elastic_limit_strain": 0.8}')
    from_source = read_material(Source("virtual/rubber.json", path.read_bytes()))
    assert from_source == read_material(str(path)) == read_material(path)
    assert from_source.thickness == pytest.approx(0.002)
    part_file = EXAMPLES / "rectangle.json"      # a whole part file: its material
    assert read_material(Source("p.json", part_file.read_bytes())) == \
        Part.from_file(part_file).material


@pytest.fixture(scope="module")
def ring_mesh():
    return mesh_part(Part.from_file(EXAMPLES / "ring.json"))


@pytest.mark.parametrize("suffix", [".json", ".vtu", ".msh", ".obj"])
def test_mesh_from_a_source_is_the_mesh_from_its_file(ring_mesh, tmp_path, suffix):
    path = tmp_path / f"ring{suffix}"
    write_mesh(ring_mesh, path)
    src = Source(f"far/away/ring{suffix}", path.read_bytes())
    _same_mesh(read_mesh(src), read_mesh(path))
    assert is_mesh_file(src) and is_mesh_file(path)


def test_a_part_source_is_not_a_mesh():
    src = Source("part.json", (EXAMPLES / "rectangle.json").read_bytes())
    assert not is_mesh_file(src)


def test_meshio_source_errors_name_the_source_not_a_temporary_file(tmp_path):
    src = Source("inbox/garbage.vtu", b"this is not a VTU file\x00\x01")
    with pytest.raises(MeshError) as info:
        read_mesh(src)
    msg = str(info.value)
    assert msg.startswith("inbox/garbage.vtu: meshio cannot read this file"), msg
    assert "deformclosure-" not in msg and "/tmp" not in msg and "\n" not in msg


def test_meshio_source_with_units_and_material(ring_mesh, tmp_path):
    path = tmp_path / "ring.msh"                  # .msh keeps no material
    write_mesh(ring_mesh, path)
    src = Source("ring.msh", path.read_bytes())
    mesh = read_mesh(src, units="mm", material=ring_mesh.material)
    np.testing.assert_allclose(mesh.nodes, 1e-3 * ring_mesh.nodes, rtol=1e-15)
    assert mesh.material == ring_mesh.material
    vtu = tmp_path / "ring.vtu"                   # .vtu keeps it, in SI units
    write_mesh(ring_mesh, vtu)
    with pytest.raises(MeshError, match=r"^ring\.vtu: holds a material in SI units"):
        read_mesh(Source("ring.vtu", vtu.read_bytes()), units="mm")
