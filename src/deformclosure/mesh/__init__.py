"""Meshes of parts: generation, validation, boundary loops, file I/O."""

from .core import Mesh, boundary_loops, triangle_areas
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
