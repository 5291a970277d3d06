"""Length units accepted in part, finger and mesh files (SPEC §1).

Everything inside the package is SI; files state the unit of their lengths and are
converted once, on reading.
"""

from __future__ import annotations

from .errors import DeformClosureError

__all__ = ["LENGTH_UNITS", "length_scale", "SI_UNITS"]

#: Metres per unit of each accepted length unit.
LENGTH_UNITS: dict[str, float] = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "in": 0.0254}

#: The ``units`` dictionary written into every JSON report (SPEC §5).
SI_UNITS: dict[str, str] = {
    "length": "m",
    "energy": "J",
    "stiffness": "N/m",
    "strain_per_length": "1/m",
    "force": "N",
}


def length_scale(unit: str, field: str = "units",
                 error: type[DeformClosureError] = DeformClosureError) -> float:
    """Metres per ``unit``.

    Parameters
    ----------
    unit : str
        One of ``"m"``, ``"cm"``, ``"mm"``, ``"in"``.
    field : str
        Name of the field the unit came from, used in the error message.
    error : DeformClosureError subclass
        Raised for an unknown unit (the reader's own: ``PartError``, ``MeshError``…).

    Raises
    ------
    DeformClosureError
        If ``unit`` is not a known unit (as ``error``), with one line naming ``field``
        and listing the units.

    Examples
    --------
    >>> length_scale("mm")
    0.001
    >>> length_scale("ft", "part.units")
    Traceback (most recent call last):
    ...
    deformclosure.errors.DeformClosureError: part.units: unknown length unit 'ft'; use one of 'm', 'cm', 'mm', 'in'
    """
    try:
        return LENGTH_UNITS[unit]
    except (KeyError, TypeError):
        valid = ", ".join(repr(u) for u in LENGTH_UNITS)
        raise error(f"{field}: unknown length unit {unit!r}; use one of {valid}") from None
