"""Meshes of parts: the validated container (:mod:`.core`), the geometry and topology of a
triangle list (:mod:`.topology`), generation (:mod:`.generate`) and file I/O (:mod:`.io`)."""

from .core import Mesh
from .topology import boundary_loops, triangle_areas
from .generate import insert_points_in_ring, mesh_part
from .io import mesh_from_dict, mesh_to_dict, read_mesh, write_mesh

__all__ = [
    "Mesh",
    "boundary_loops",
    "triangle_areas",
    "mesh_part",
    "insert_points_in_ring",
    "read_mesh",
    "write_mesh",
    "mesh_to_dict",
    "mesh_from_dict",
]
