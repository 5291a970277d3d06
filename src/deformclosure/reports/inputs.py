"""Reading a command's inputs: the part (or mesh, or drawing) file, the material and the
lengths given in the part's units, each read once as a :class:`~deformclosure.jsonfile.Source`
so the report's provenance names exactly the bytes that were used."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..errors import DeformClosureError, GraspError
from ..jsonfile import Source, as_source
from ..limits import MIN_PAD_RADIUS_FRACTION, check_body_size

__all__ = ["Inputs", "read_inputs", "read_part", "source_of", "material_of", "parse_xy",
           "pad_from_options", "check_grid", "unit_of"]

_NO_MATERIAL = ("the mesh file has no material; give --material FILE or --material "
                "'{\"youngs_modulus\": 2e6, \"poisson_ratio\": 0.1, \"thickness\": 1, "
                "\"elastic_limit_strain\": 0.8, \"units\": \"mm\"}'")


def source_of(file: Any, what: str = "input file") -> Source:
    """``file`` (a path or a Source) as a Source, read once; one-line errors
    (``<path>: cannot read the part file (No such file or directory)``)."""
    from ..errors import FingerError, PartError

    error = {"finger file": FingerError, "part file": PartError, "drawing": PartError,
             "material file": PartError}.get(what, DeformClosureError)
    src = as_source(file, error, what)
    if what in ("part file", "drawing") and not isinstance(file, Source):
        from ..drawing import is_drawing_file, material_file_beside

        side = material_file_beside(file) if is_drawing_file(src) else None
        if side is not None:               # the drawing's material travels with it
            src = Source(src.name, src.data, as_source(side, error, "material file"))
    return src


def material_of(material: Any) -> str | Source | None:
    """``--material`` as inline JSON text or the Source of its file (``None``: not given)."""
    if material is None or isinstance(material, Source):
        return material
    text = str(material)
    return text if text.lstrip().startswith("{") else source_of(text, "material file")


@dataclass
class Inputs:
    """A command's part (``None`` for a mesh file), mesh, unit and the Sources read."""

    part: Any
    mesh: Any
    unit: str
    sources: list = field(default_factory=list)
    warnings: list = field(default_factory=list)

    @property
    def scale(self) -> float:
        """Metres per unit of :attr:`unit`."""
        from ..units import length_scale

        return length_scale(self.unit, "--units")


def unit_of(units: str | None, part) -> str:
    """The unit of lengths given on the command line: ``--units``, else the part's, else m."""
    from ..units import length_scale

    unit = units if units is not None else ("m" if part is None else part.units)
    length_scale(unit, "--units")
    return unit


def read_part(src: Source, units: str | None = None, material=None):
    """The part of a part file or drawing, with ``--material`` (in ``units``, default the
    part's) replacing its own; returns ``(part, warnings)``."""
    from ..drawing import is_drawing_file
    from ..part import Part, part_from_drawing, read_material

    if is_drawing_file(src):
        part = part_from_drawing(src, material=material, default_units=units)
    else:
        part = Part.from_file(src)
        if material is not None:
            part = dataclasses.replace(part, material=read_material(material, units or part.units))
    return part, list(part.sanity_warnings())


def read_inputs(file: Any, units: str | None = None, material: Any = None, *,
                points=None, need_material: bool = True, mesh: bool = True,
                max_area: float | None = None) -> Inputs:
    """Read a part file (meshed with ``points`` (m) inserted as nodes), a drawing, or a
    mesh file; ``--units``, ``--material`` and ``--max-area`` (the part's units², the
    starting mesh of every command: the part's ``mesh.max_area`` replaced, so refinement
    and twin meshes start there too) as on the command line.

    ``points`` may be a callable ``points(part)`` returning the points, for commands whose
    points depend on the part (``check``). ``mesh=False`` reads the part without meshing.
    """
    from ..mesh import mesh_part, read_mesh
    from ..mesh.io import is_mesh_file
    from ..part import read_material
    from ..units import length_scale

    src = source_of(file, "part file")
    if units is not None:
        length_scale(units, "--units")
    mat = material_of(material)
    sources = [src, src.sidecar] + ([mat] if isinstance(mat, Source) else [])
    if is_mesh_file(src):
        if max_area is not None:
            raise DeformClosureError("--max-area: applies to part files and drawings only; a "
                                     "mesh file is used as it is")
        m = None if mat is None else read_material(mat, units or "m")
        msh = read_mesh(src, units=units or "m", material=m)
        if need_material and msh.material is None:
            raise DeformClosureError(f"{src.name}: {_NO_MATERIAL}")
        return Inputs(None, msh, units or "m", sources)
    part, warnings = read_part(src, units, mat)
    if max_area is not None:
        part = with_max_area(part, max_area, units)
    pts = points(part) if callable(points) else points
    msh = mesh_part(part, points=pts) if mesh else None
    return Inputs(part, msh, unit_of(units, part), sources, warnings)


def with_max_area(part, max_area: Any, units: str | None):
    """``part`` with its ``mesh.max_area`` replaced by ``--max-area`` (in ``units``², default
    the part's units); a one-line error unless it is a finite area > 0."""
    import dataclasses

    from ..units import length_scale

    try:
        value = float(max_area)
    except (TypeError, ValueError):
        raise DeformClosureError(f"--max-area: expected an area, got {max_area!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise DeformClosureError(f"--max-area = {max_area!r}: must be a finite area > 0 "
                                 f"(in {units or part.units}²)")
    s = length_scale(units or part.units)
    opts = dataclasses.replace(part.mesh_options, max_area=value * s * s)
    return dataclasses.replace(part, mesh_options=opts)


def parse_xy(text: Any, field_name: str) -> tuple[float, float]:
    """``"X,Y"`` (or a pair of numbers) as two finite floats; one-line error naming the field.

    Examples
    --------
    >>> parse_xy("1.5,-2", "--at")
    (1.5, -2.0)
    """
    try:
        x, y = (float(v) for v in (text.split(",") if isinstance(text, str) else text))
    except (ValueError, TypeError):
        raise DeformClosureError(f"{field_name}: expected X,Y (two numbers separated by a comma), "
                                 f"got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise DeformClosureError(f"{field_name}: coordinates must be finite, got {text!r}")
    return x, y


def parse_numbers(text: Any, n: int, field_name: str, form: str) -> list[float]:
    """``n`` comma-separated finite numbers (or a sequence of them)."""
    try:
        vals = [float(v) for v in (text.split(",") if isinstance(text, str) else text)]
    except (ValueError, TypeError):
        vals = []
    if len(vals) != n:
        raise DeformClosureError(f"{field_name}: expected {form} ({n} numbers), got {text!r}")
    if not all(math.isfinite(v) for v in vals):
        raise DeformClosureError(f"{field_name}: values must be finite, got {text!r}")
    return vals


def pad_from_options(radius: float | None, width: float, scale: float, diameter: float):
    """The pad of ``--pad-radius``/``--pad-width`` (in units of ``scale`` m); the default
    radius is 5 % of the part's ``diameter`` (m)."""
    from ..pads import Pad

    if radius is not None and not (math.isfinite(radius) and radius > 0):
        raise DeformClosureError(f"--pad-radius = {radius!r}: must be a finite length > 0")
    if not (math.isfinite(width) and width >= 0):
        raise DeformClosureError(f"--pad-width = {width!r}: must be a finite length >= 0")
    rho = 0.05 * diameter if radius is None else radius * scale
    unit = _unit_name(scale)
    if radius is not None:
        check_body_size("--pad-radius", radius, diameter, MIN_PAD_RADIUS_FRACTION, scale=scale,
                        units=unit, hint="; check the value and --units")
    check_body_size("--pad-width", width, diameter, 0.0, scale=scale, units=unit,
                    hint="; 0 = a round fingertip")
    return Pad(width * scale, rho)


def _unit_name(scale: float) -> str:
    """The length unit of ``scale`` metres (one of LENGTH_UNITS, else ``× scale m``)."""
    from ..units import LENGTH_UNITS

    for name, f in LENGTH_UNITS.items():
        if math.isclose(f, scale, rel_tol=1e-12):
            return name
    return f"x {scale:g} m"


def check_grid(angles: int, offsets: int) -> None:
    """Refuse release-landscape grids outside 4..2000 angles/offsets."""
    for name, v in (("--grid-angles", angles), ("--grid-offsets", offsets)):
        if not (4 <= v <= 2000):
            raise DeformClosureError(f"{name} = {v}: give a whole number from 4 to 2000")


def check_eps(eps: float | None) -> None:
    """``--eps``: a finite energy > 0 (J) or not given."""
    if eps is not None and not (np.isfinite(eps) and eps > 0):
        raise GraspError(f"--eps = {eps!r}: must be a finite energy > 0 in joules")


def check_jaw_width(jaw_width: float) -> None:
    """``--jaw-width``: a finite length >= 0."""
    if not (np.isfinite(jaw_width) and jaw_width >= 0):
        raise GraspError(f"--jaw-width = {jaw_width!r}: must be a finite length >= 0 (0 = point jaws)")


def only_for(model: str, given: Sequence[tuple[str, bool]], fix: str) -> None:
    """Refuse the first option of ``given`` that was given but belongs to ``model``."""
    bad = [name for name, g in given if g]
    if bad:
        raise GraspError(f"{bad[0]}: belongs to the {model} model; {fix}")
