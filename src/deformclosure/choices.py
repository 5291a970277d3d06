"""The one home of the package's named choices (models, methods, modes, plane) and of the
one check that refuses any other value with a message listing the choices.

The CLI builds its ``click.Choice`` lists from these tuples, the library checks its
arguments with :func:`choose`, so a choice is spelled in one place.
"""

from __future__ import annotations

from typing import Sequence

from .errors import DeformClosureError

__all__ = ["MODELS", "METHODS", "MODES", "PLANES", "MATERIAL_MODELS", "choose"]

#: Two-jaw models: ``pads`` (physical pads on a grasp axis, SPEC §6) and ``paper`` (point
#: jaws at mesh nodes, SPEC §4).
MODELS = ("pads", "paper")
#: Paper-model σ* methods (SPEC §4): ours (exact), the ε-grid (approx), every crossing (paper).
METHODS = ("exact", "approx", "paper")
#: Jaw closing modes (SPEC §4): jaws move towards each other, or apart from inside a hole.
MODES = ("contracting", "expanding")
#: Plane elasticity assumptions.
PLANES = ("stress", "strain")
#: Material laws (SPEC §8): small-strain linear elasticity (§1) or compressible neo-Hookean.
MATERIAL_MODELS = ("linear", "neo-hookean")


def choose(value: object, choices: Sequence[str], field: str,
           error: type[DeformClosureError] = DeformClosureError) -> str:
    """Return ``value`` if it is one of ``choices``, else raise ``error`` naming ``field``.

    Examples
    --------
    >>> choose("exact", METHODS, "method")
    'exact'
    >>> choose("fast", METHODS, "method")
    Traceback (most recent call last):
    ...
    deformclosure.errors.DeformClosureError: method = 'fast': choose one of exact, approx, paper
    """
    if not isinstance(value, str) or value not in choices:
        raise error(f"{field} = {value!r}: choose one of {', '.join(choices)}")
    return value
