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
    """Base class of all errors raised for bad input or impossible requests.

    Every message names the offending field and says how to fix it, on one line.

    Examples
    --------
    >>> from deformclosure.choices import METHODS, choose
    >>> try:
    ...     choose("fast", METHODS, "method")
    ... except DeformClosureError as err:
    ...     print(err)
    method = 'fast': choose one of exact, approx, paper
    """


class PartError(DeformClosureError):
    """A part file or part description is invalid (geometry, material, mesh options).

    Examples
    --------
    >>> from deformclosure import read_material
    >>> read_material('{"youngs_modulus": -1, "poisson_ratio": 0.1, "thickness": 1,'
    ...               ' "elastic_limit_strain": 0.8}')      # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    deformclosure.errors.PartError: --material.youngs_modulus = -1.0: must be a finite number > 0 in Pa ...
    """


class MeshError(DeformClosureError):
    """A mesh is invalid (degenerate/inverted triangles, non-manifold, disconnected...).

    Examples
    --------
    >>> import numpy as np
    >>> from deformclosure import Mesh
    >>> Mesh.from_arrays(np.zeros((3, 2)), np.array([[0, 1, 2]]))
    Traceback (most recent call last):
    ...
    deformclosure.errors.MeshError: triangles[0]: zero area (degenerate triangle); remesh
    """


class StiffnessError(DeformClosureError):
    """A stiffness matrix is invalid (shape, symmetry, rigid modes) or cannot be read.

    Examples
    --------
    >>> from deformclosure import read_stiffness
    >>> read_stiffness("missing.mtx", None)                   # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    deformclosure.errors.StiffnessError: ...
    """


class GraspError(DeformClosureError):
    """A grasp request is invalid (jaw nodes, separation, epsilon, jaw width...).

    Examples
    --------
    >>> from deformclosure.choices import MODES, choose
    >>> choose("squeezing", MODES, "mode", GraspError)
    Traceback (most recent call last):
    ...
    deformclosure.errors.GraspError: mode = 'squeezing': choose one of contracting, expanding
    """


class FingerError(DeformClosureError):
    """A finger file or finger description is invalid.

    Examples
    --------
    >>> from deformclosure.dspace import fingers_from_dict
    >>> fingers_from_dict({"fingers": [{"type": "point", "at": [0, 0]}]})
    Traceback (most recent call last):
    ...
    deformclosure.errors.FingerError: fingers: units: missing; give "units" as one of "m", "mm", "cm", "in"
    """


class BatchError(DeformClosureError):
    """A batch job list or results database is invalid.

    Examples
    --------
    >>> from deformclosure.batch import load_jobs
    >>> load_jobs("no-such-folder")                           # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    deformclosure.errors.BatchError: ...
    """
