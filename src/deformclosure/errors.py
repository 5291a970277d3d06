"""Exception hierarchy: every user-facing error derives from :class:`DeformClosureError`.

The CLI catches :class:`DeformClosureError` and prints its message as one line with
exit code 2, so messages must name the offending field and say how to fix it.
"""

from __future__ import annotations

__all__ = [
    "DeformClosureError",
    "PartError",
    "MeshError",
    "StiffnessError",
    "GraspError",
    "FingerError",
    "BatchError",
]


class DeformClosureError(ValueError):
    """Base class of all errors raised for bad input or impossible requests."""


class PartError(DeformClosureError):
    """A part file or part description is invalid (geometry, material, mesh options)."""


class MeshError(DeformClosureError):
    """A mesh is invalid (degenerate/inverted triangles, non-manifold, disconnected...)."""


class StiffnessError(DeformClosureError):
    """A stiffness matrix is invalid (shape, symmetry, rigid modes) or cannot be read."""


class GraspError(DeformClosureError):
    """A grasp request is invalid (jaw nodes, separation, epsilon, jaw width...)."""


class FingerError(DeformClosureError):
    """A finger file or finger description is invalid."""


class BatchError(DeformClosureError):
    """A batch job list or results database is invalid."""
