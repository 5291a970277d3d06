"""Parts: a polygon with polygonal holes and a linear-elastic material (SPEC §1, §5).

A part file is JSON::

    {"name": "rubber", "units": "mm",
     "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
     "holes": [],
     "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
                  "elastic_limit_strain": 0.8, "plane": "stress", "model": "linear"},
     "mesh": {"max_area": 0.5, "min_angle": 30, "points": [[6, 0], [6, 20]]}}

``youngs_modulus`` is in Pa; every length (coordinates, thickness, points) is in
``units`` and ``max_area`` in ``units``². On reading, everything is converted to SI
and the rings are normalised: outer ring counter-clockwise, holes clockwise, closing
duplicate point and repeated consecutive points removed. ``material.model`` (optional)
names the material law: ``"linear"`` (default, SPEC §1) or ``"neo-hookean"`` (SPEC §8).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import shapely
from pydantic import BaseModel, ConfigDict, ValidationError, field_validator
from shapely.geometry import LinearRing, Polygon

from .choices import MATERIAL_MODELS, PLANES, choose
from .drawing import (drawing_source, is_drawing_file, material_file_beside,
                      material_path_beside, read_drawing)
from .errors import DeformClosureError, PartError
from .geometry import point_set_diameter, signed_area, touch_tolerance
from .jsonfile import InputFile, Source
from .limits import MAX_COORDINATE, MAX_TRIANGLES, check_mesh_points, check_ring_gaps, points_within
from .units import length_scale

__all__ = [
    "Material",
    "MeshOptions",
    "Part",
    "demo_part",
    "read_material",
    "part_from_drawing",
    "MAX_TRIANGLES",
]


# --------------------------------------------------------------------------- schema
class _MaterialModel(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)
    youngs_modulus: float
    poisson_ratio: float
    thickness: float = 1.0
    elastic_limit_strain: float
    plane: Literal["stress", "strain"] = "stress"
    critical_distance: float | None = None
    model: Any = "linear"           # checked by choices.choose, whose message lists the laws

    @field_validator("youngs_modulus", "poisson_ratio", "thickness", "elastic_limit_strain",
                     "critical_distance", mode="before")
    @classmethod
    def _int_to_float(cls, v: Any) -> Any:
        if isinstance(v, int) and not isinstance(v, bool):
            return float(v)
        return v


class _MeshModel(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)
    max_area: float | None = None
    min_angle: float = 30.0
    points: list[list[float]] = []

    @field_validator("max_area", "min_angle", mode="before")
    @classmethod
    def _int_to_float(cls, v: Any) -> Any:
        if isinstance(v, int) and not isinstance(v, bool):
            return float(v)
        return v

    @field_validator("points", mode="before")
    @classmethod
    def _points_float(cls, v: Any) -> Any:
        return _coerce_coords(v)


def _coerce_coords(v: Any) -> Any:
    """Accept ints where floats are expected inside coordinate lists (strict mode)."""
    if isinstance(v, list):
        return [
            [float(c) if isinstance(c, int) and not isinstance(c, bool) else c for c in p]
            if isinstance(p, list) else p
            for p in v
        ]
    return v


class _PartModel(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)
    name: str = "part"
    units: str
    outer: list[list[float]]
    holes: list[list[list[float]]] = []
    material: _MaterialModel
    mesh: _MeshModel = _MeshModel()
    provenance: dict | None = None      # written by `deformclosure import`; not read

    @field_validator("outer", mode="before")
    @classmethod
    def _outer_float(cls, v: Any) -> Any:
        return _coerce_coords(v)

    @field_validator("holes", mode="before")
    @classmethod
    def _holes_float(cls, v: Any) -> Any:
        if isinstance(v, list):
            return [_coerce_coords(h) for h in v]
        return v


_KEYS = {(): set(_PartModel.model_fields), ("material",): set(_MaterialModel.model_fields),
         ("mesh",): set(_MeshModel.model_fields)}


def _nearest_key(loc: tuple) -> str:
    """'did you mean …' for a misspelt key, else the list of allowed keys."""
    import difflib

    allowed = sorted(_KEYS.get(tuple(str(p) for p in loc[:-1]), set()))
    close = difflib.get_close_matches(str(loc[-1]), allowed, n=1, cutoff=0.6)
    if close:
        return f"did you mean {close[0]!r}?"
    return f"remove it (allowed here: {', '.join(allowed)})" if allowed else "remove it"


def _pydantic_message(err: ValidationError, within: tuple = (), shown: str | None = None) -> str:
    """One line naming the first offending field and what is wrong with it.

    ``within``: the location of the validated block inside a part file (for the key
    hints); ``shown``: how to name that block in the message (default its location)."""
    e = err.errors()[0]
    full = (*within, *e["loc"])
    names = [str(p) for p in e["loc"]]
    if within:
        names = [shown or ".".join(map(str, within)), *names]
    loc = ".".join(names) or "part"
    kind = e["type"]
    if kind == "extra_forbidden":
        return f"{loc}: unknown key; {_nearest_key(full)}"
    if kind == "missing":
        return f"{loc}: required field is missing; add it"
    if kind == "literal_error":
        return f"{loc}: {e['msg'].lower()}"
    inp = e.get("input")
    return f"{loc}: {e['msg'].lower()} (got {inp!r:.60})"


# --------------------------------------------------------------------------- values
@dataclass(frozen=True)
class Material:
    """Linear-elastic isotropic material of a planar part.

    Attributes
    ----------
    youngs_modulus : float
        Young's modulus ``E`` (Pa), > 0.
    poisson_ratio : float
        Poisson ratio ``nu``, -1 < nu < 0.5.
    thickness : float
        Out-of-plane thickness ``t`` (m), > 0.
    elastic_limit_strain : float
        Elastic-limit strain ``e_L`` (dimensionless), > 0, compared with the largest
        absolute in-plane principal strain of an element.
    plane : {"stress", "strain"}
        Plane stress (thin sheet, default) or plane strain (long prism).
    critical_distance : float or None
        Radius ``ℓ`` (m) of the disc over which strains are averaged before they are
        compared with ``e_L`` by the pad model (SPEC §6, theory of critical distances);
        ``None``: 2 % of the part's diameter.
    model : {"linear", "neo-hookean"}
        Material law: small-strain linear elasticity (SPEC §1, default) or the
        compressible neo-Hookean law with the same ``E``, ``nu`` (SPEC §8,
        :class:`deformclosure.elasticity.neohookean.NeoHookean`).

    Examples
    --------
    Soft rubber, 1 mm thick (every value in SI):

    >>> Material(2e6, 0.1, 1e-3, 0.8)
    Material(youngs_modulus=2000000.0, poisson_ratio=0.1, thickness=0.001, elastic_limit_strain=0.8, plane='stress', critical_distance=None, model='linear')
    >>> Material(2e6, 0.5, 1e-3, 0.8)
    Traceback (most recent call last):
    ...
    deformclosure.errors.PartError: material.poisson_ratio = 0.5: must satisfy -1 < poisson_ratio < 0.5 (0.5 is incompressible; use 0.49)
    """

    youngs_modulus: float
    poisson_ratio: float
    thickness: float
    elastic_limit_strain: float
    plane: str = "stress"
    critical_distance: float | None = None
    model: str = "linear"

    def __post_init__(self) -> None:
        _check_material(self.youngs_modulus, self.poisson_ratio, self.thickness,
                        self.elastic_limit_strain, self.plane, self.critical_distance,
                        prefix="material", model=self.model)

    @classmethod
    def from_dict(cls, data: Any, scale: float = 1.0, where: str = "material") -> "Material":
        """Validated material from the ``"material"`` block of a part file (SPEC §5).

        Parameters
        ----------
        data : dict
            ``youngs_modulus`` (Pa), ``poisson_ratio``, ``thickness`` (default 1),
            ``elastic_limit_strain``, optional ``plane``, ``critical_distance`` and
            ``model`` (``"linear"`` or ``"neo-hookean"``).
        scale : float
            Metres per unit of ``thickness`` and ``critical_distance``.
        where : str
            Name of the block in error messages.

        Raises
        ------
        PartError

        Examples
        --------
        >>> Material.from_dict({"youngs_modulus": 2e6, "poisson_ratio": 0.1,
        ...                     "thickness": 1, "elastic_limit_strain": 0.8}, 1e-3).thickness
        0.001
        """
        if not isinstance(data, dict):
            raise PartError(f"{where}: must be a JSON object with youngs_modulus, poisson_ratio, "
                            "thickness and elastic_limit_strain")
        try:
            mat = _MaterialModel.model_validate(data)
        except ValidationError as err:
            raise PartError(_pydantic_message(err, ("material",), where)) from None
        cd = mat.critical_distance
        _check_material(mat.youngs_modulus, mat.poisson_ratio, mat.thickness,
                        mat.elastic_limit_strain, mat.plane, cd, prefix=where, model=mat.model)
        lo, hi = LENGTH_RANGE
        if not lo <= mat.thickness * scale <= hi:
            raise PartError(f"{where}.thickness = {mat.thickness!r}: out of range in these units; "
                            f"give a thickness from {lo:g} m to {hi:g} m")
        if cd is not None and not cd * scale <= hi:
            raise PartError(f"{where}.critical_distance = {cd!r}: out of range in these units; "
                            f"give a length from 0 to {hi:g} m")
        return cls(mat.youngs_modulus, mat.poisson_ratio, mat.thickness * scale,
                   mat.elastic_limit_strain, mat.plane, None if cd is None else cd * scale,
                   mat.model)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict in SI units (thickness and critical distance in m).

        ``model`` is written only when it is not ``"linear"`` (the default), so files and
        reports of linear parts are unchanged.
        """
        d = {
            "youngs_modulus": self.youngs_modulus,
            "poisson_ratio": self.poisson_ratio,
            "thickness": self.thickness,
            "elastic_limit_strain": self.elastic_limit_strain,
            "plane": self.plane,
        }
        if self.critical_distance is not None:
            d["critical_distance"] = self.critical_distance
        if self.model != "linear":
            d["model"] = self.model
        return d


def read_material(source: str | InputFile, units: str = "m", where: str = "--material"
                  ) -> Material:
    """The material given on a command line: a JSON file or inline JSON text.

    Parameters
    ----------
    source : str, path or Source
        Inline JSON (starting with ``{``), or the path (or :class:`~deformclosure.jsonfile.Source`)
        of a JSON file holding either a material object (the ``"material"`` block of a part
        file, optionally with its own ``"units"``) or a whole part or mesh file, whose
        material and units are taken.
    units : str
        Unit of ``thickness`` and ``critical_distance`` when the source states none.
    where : str
        Name of the option in error messages.

    Raises
    ------
    PartError

    Examples
    --------
    >>> read_material('{"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 2,'
    ...               ' "elastic_limit_strain": 0.8, "units": "mm"}').thickness
    0.002
    """
    from .jsonfile import parse_json, read_json

    if isinstance(source, str) and source.strip().startswith("{"):
        data = parse_json(source.strip(), where, PartError, "material")
    else:
        data = read_json(source if isinstance(source, Source) else Path(source), PartError,
                         "material file")
    if not isinstance(data, dict):
        raise PartError(f"{where}: expected a JSON object with youngs_modulus, poisson_ratio, "
                        "thickness and elastic_limit_strain")
    data = dict(data)
    unit = data.pop("units", units)
    if "material" in data:       # a part or mesh file: its material block, its units
        data = data["material"]
    return Material.from_dict(data, length_scale(unit, f"{where}.units", PartError), where)


#: Hard ranges of the material values (SI). Energies are proportional to E × thickness:
#: outside these they underflow to subnormals or overflow (thickness 1e308 made the
#: stiffness matrix "singular", E = 1e308 gave infinite energies). The soft ranges of
#: :meth:`Part.sanity_warnings` (1 kPa..1 TPa) only warn.
MODULUS_RANGE = (1e-3, 1e15)
LENGTH_RANGE = (1e-9, 1e6)
STRAIN_RANGE = (1e-12, 100.0)


def _check_material(E: float, nu: float, t: float, eL: float, plane: str,
                    critical_distance: float | None, prefix: str, model: str = "linear") -> None:
    """Refuse material values outside their physical ranges, naming ``prefix.field``."""
    cd = critical_distance
    checks = [
        ("youngs_modulus", E, math.isfinite(E) and E > 0,
         "must be a finite number > 0 in Pa (e.g. 2e6 for soft rubber)"),
        ("youngs_modulus", E, MODULUS_RANGE[0] <= E <= MODULUS_RANGE[1],
         f"must be from {MODULUS_RANGE[0]:g} to {MODULUS_RANGE[1]:g} Pa (e.g. 2e6 for soft "
         "rubber); beyond, the energies underflow or overflow"),
        ("poisson_ratio", nu, math.isfinite(nu) and -1.0 < nu < 0.5,
         "must satisfy -1 < poisson_ratio < 0.5 (0.5 is incompressible; use 0.49)"),
        ("thickness", t, math.isfinite(t) and t > 0, "must be a finite number > 0"),
        ("elastic_limit_strain", eL, math.isfinite(eL) and eL > 0,
         "must be a finite strain > 0 (e.g. 0.8)"),
        ("elastic_limit_strain", eL, STRAIN_RANGE[0] <= eL <= STRAIN_RANGE[1],
         f"must be a strain from {STRAIN_RANGE[0]:g} to {STRAIN_RANGE[1]:g} (e.g. 0.8)"),
        ("critical_distance", cd, cd is None or (math.isfinite(cd) and cd >= 0),
         "must be a finite length >= 0 in the part's units (or omit it for 2 % of the "
         "part's diameter)"),
    ]
    for name, value, ok, fix in checks:
        if not ok:
            raise PartError(f"{prefix}.{name} = {value!r}: {fix}")
    choose(plane, PLANES, f"{prefix}.plane", PartError)
    choose(model, MATERIAL_MODELS, f"{prefix}.model", PartError)


@dataclass(frozen=True)
class MeshOptions:
    """Mesher settings of a part, SI.

    Attributes
    ----------
    max_area : float or None
        Largest triangle area (m²); ``None`` chooses area/400.
    min_angle : float
        Smallest triangle angle (degrees), 0 < min_angle ≤ 34.
    points : ndarray, shape (k, 2)
        Extra points (m) inserted as mesh nodes, e.g. intended contact locations.

    Examples
    --------
    >>> MeshOptions(max_area=1e-6).min_angle, MeshOptions().points.shape
    (30.0, (0, 2))
    """

    max_area: float | None = None
    min_angle: float = 30.0
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))


@dataclass(frozen=True)
class Part:
    """A planar deformable part: polygon with holes plus material, in SI units.

    Attributes
    ----------
    name : str
    units : str
        The unit the part was described in (used for printing only).
    outer : ndarray, shape (n, 2)
        Outer ring (m), counter-clockwise, not closed.
    holes : tuple of ndarray
        Hole rings (m), clockwise, not closed.
    material : Material
    mesh_options : MeshOptions

    Examples
    --------
    Build one with :meth:`from_dict` or :meth:`from_file`; the built-in example:

    >>> part = demo_part()
    >>> part.units, part.outer.shape, round(part.area * 1e6, 9)     # mm², from SI
    ('mm', (4, 2), 240.0)
    """

    name: str
    units: str
    outer: np.ndarray
    holes: tuple[np.ndarray, ...]
    material: Material
    mesh_options: MeshOptions = field(default_factory=MeshOptions)

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_dict(cls, data: Any) -> "Part":
        """Build a validated part from the JSON structure of SPEC §5.

        Parameters
        ----------
        data : dict
            ``name``, ``units`` (of every length), ``outer`` and ``holes`` rings,
            ``material`` (``youngs_modulus`` in Pa) and optional ``mesh`` options.

        Returns
        -------
        Part
            In SI units (m, Pa), outer ring counter-clockwise, holes clockwise.

        Raises
        ------
        PartError
            With a one-line message naming the offending field and the fix.

        Examples
        --------
        A 12 × 20 mm rubber block:

        >>> part = Part.from_dict({"units": "mm", "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
        ...     "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1,
        ...                  "elastic_limit_strain": 0.8}})
        >>> round(part.area * 1e6, 9), round(part.diameter * 1e3, 6)   # mm², mm
        (240.0, 23.323808)
        """
        if not isinstance(data, dict):
            raise PartError("part file: top level must be a JSON object {...}")
        try:
            model = _PartModel.model_validate(data)
        except ValidationError as err:
            raise PartError(_pydantic_message(err)) from None
        scale = length_scale(model.units, "units", PartError)
        outer = _clean_ring(model.outer, "outer") * scale
        holes = tuple(_clean_ring(h, f"holes[{i}]") * scale for i, h in enumerate(model.holes))
        material = Material.from_dict(data["material"], scale)
        outer, holes = _validate_geometry(outer, holes)
        diameter = point_set_diameter(outer)
        check_ring_gaps(outer, holes, diameter, units=model.units, scale=scale)
        opts = _validate_mesh_options(model.mesh, scale, outer, holes, diameter)
        return cls(model.name, model.units, outer, holes, material, opts)

    @classmethod
    def from_file(cls, path: InputFile) -> "Part":
        """Read and validate a part file (JSON, SPEC §5), or a DXF/SVG drawing whose
        material is in ``<name>.material.json`` beside it (:mod:`deformclosure.drawing`).

        Parameters
        ----------
        path : str, Path or Source
            The file, or a :class:`~deformclosure.jsonfile.Source` holding its bytes
            (its name selects the format and names the file in errors).

        Raises
        ------
        PartError
        """
        from .jsonfile import read_json

        if is_drawing_file(path):
            return part_from_drawing(path)
        return cls.from_dict(read_json(path, PartError, "part file"))

    # ------------------------------------------------------------------ geometry
    @property
    def polygon(self) -> Polygon:
        """The part as a shapely polygon (m)."""
        return Polygon(self.outer, [h for h in self.holes])

    @property
    def area(self) -> float:
        """Area (m²)."""
        return float(self.polygon.area)

    @property
    def diameter(self) -> float:
        """Largest distance between two outer-ring vertices (m).

        The one definition of :func:`deformclosure.geometry.point_set_diameter`, as for
        meshes and contact graphs.
        """
        return point_set_diameter(self.outer)

    def sanity_warnings(self) -> list[str]:
        """Hints that the file's ``units`` or modulus are probably not what was meant.

        A deformable part a gripper holds is between 0.1 mm and 10 m across, and the
        Young's modulus of soft solids is between 1 kPa and 1 TPa; outside, the numbers are
        most likely in the wrong unit (a 12 × 20 m rubber part, E = 2 Pa).
        """
        out = []
        d = self.diameter
        if d > 10.0 or d < 1e-4:
            out.append(f"the part is {d:.3g} m across; check 'units' ({self.units!r}): every "
                       "length in the file is in that unit")
        E = self.material.youngs_modulus
        if E < 1e3 or E > 1e12:
            out.append(f"material.youngs_modulus = {E:.3g} Pa; it is in pascals (soft rubber is "
                       "about 1e6)")
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict in SI units (``units = "m"``)."""
        opts = self.mesh_options
        return {
            "name": self.name,
            "units": "m",
            "outer": self.outer.tolist(),
            "holes": [h.tolist() for h in self.holes],
            "material": self.material.to_dict(),
            "mesh": {
                "max_area": opts.max_area,
                "min_angle": opts.min_angle,
                "points": np.asarray(opts.points).tolist(),
            },
        }


# --------------------------------------------------------------------------- checks
def check_coordinates(xy: np.ndarray, fld: str, error: type[DeformClosureError]) -> np.ndarray:
    """``xy`` (rows of coordinates) if all are finite and at most :data:`MAX_COORDINATE`
    in magnitude; else ``error`` naming the first bad row ``fld[i]``."""
    if not np.all(np.isfinite(xy)):
        bad = int(np.argwhere(~np.isfinite(xy))[0, 0])
        raise error(f"{fld}[{bad}]: coordinate is not finite (NaN or inf); give numbers")
    if np.any(np.abs(xy) > MAX_COORDINATE):
        bad = int(np.argwhere(np.abs(xy) > MAX_COORDINATE)[0, 0])
        raise error(f"{fld}[{bad}]: coordinate is larger than {MAX_COORDINATE:g} in magnitude; "
                    "check the units")
    return xy


def _clean_ring(coords: list[list[float]], fld: str) -> np.ndarray:
    if any(len(p) != 2 for p in coords):
        raise PartError(f"{fld}: every point must be a pair [x, y]")
    ring = check_coordinates(np.asarray(coords, dtype=float).reshape(-1, 2), fld, PartError)
    if len(ring) > 1 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]
    keep = np.any(ring != np.roll(ring, 1, axis=0), axis=1) if len(ring) > 1 else np.ones(len(ring), bool)
    ring = ring[keep]
    if len(ring) < 3:
        raise PartError(f"{fld}: a ring needs at least 3 distinct points (got {len(ring)})")
    return ring


def _validate_geometry(outer: np.ndarray, holes: tuple[np.ndarray, ...]
                       ) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    scale = float(np.ptp(outer, axis=0).max())
    rings = [("outer", outer)] + [(f"holes[{i}]", h) for i, h in enumerate(holes)]
    for fld, ring in rings:
        lr = LinearRing(ring)
        if not lr.is_simple:
            raise PartError(f"{fld}: ring is self-intersecting; reorder its points so edges do not cross")
        if abs(signed_area(ring)) <= 1e-12 * scale**2:
            raise PartError(f"{fld}: ring has zero area; give at least 3 non-collinear points")
    if signed_area(outer) < 0:
        outer = outer[::-1].copy()
    holes = tuple(h[::-1].copy() if signed_area(h) > 0 else h for h in holes)
    outer_poly = Polygon(outer)
    hole_polys = [Polygon(h) for h in holes]
    for i, hp in enumerate(hole_polys):
        if not outer_poly.contains(hp) or hp.exterior.intersects(outer_poly.exterior):
            raise PartError(f"holes[{i}]: hole is not strictly inside the outer ring; move it inside")
    if hole_polys:
        tree = shapely.STRtree(hole_polys)
        pairs = tree.query(hole_polys, predicate="intersects")
        pairs = pairs[:, pairs[0] < pairs[1]]
        if pairs.shape[1]:
            i, j = int(pairs[0, 0]), int(pairs[1, 0])
            raise PartError(f"holes[{i}] and holes[{j}] overlap or touch; holes must be pairwise disjoint")
    return outer, holes


def _validate_mesh_options(m: _MeshModel, scale: float, outer: np.ndarray,
                           holes: tuple[np.ndarray, ...], diameter: float) -> MeshOptions:
    poly = Polygon(outer, list(holes))
    if not (math.isfinite(m.min_angle) and 0.0 < m.min_angle <= 34.0):
        raise PartError(f"mesh.min_angle = {m.min_angle!r}: use 0 < min_angle <= 34 degrees "
                        "(the quality mesher cannot guarantee more)")
    max_area = None
    if m.max_area is not None:
        if not (math.isfinite(m.max_area) and m.max_area > 0):
            raise PartError(f"mesh.max_area = {m.max_area!r}: must be a finite area > 0 in units²")
        max_area = m.max_area * scale**2
        n_est = poly.area / max_area if max_area > 0 else math.inf
        if n_est > MAX_TRIANGLES:
            raise PartError(f"mesh.max_area = {m.max_area!r}: would need at least {n_est:.3g} "
                            f"triangles (limit {MAX_TRIANGLES:,}); increase max_area")
    if any(len(p) != 2 for p in m.points):
        raise PartError("mesh.points: every point must be a pair [x, y]")
    check_mesh_points(len(m.points))
    pts = check_coordinates(np.asarray(m.points, dtype=float).reshape(-1, 2), "mesh.points",
                            PartError) * scale
    if len(pts):
        inside = points_within(poly, pts, touch_tolerance(diameter))  # indexed
        if not inside.all():
            bad = int(np.flatnonzero(~inside)[0])
            raise PartError(f"mesh.points[{bad}]: point lies outside the part; move it onto or inside the part")
    return MeshOptions(max_area=max_area, min_angle=float(m.min_angle), points=pts)


# --------------------------------------------------------------------------- demo
def demo_part(max_area_mm2: float = 1.0) -> Part:
    """The built-in rubber part of the paper's example (12 × 20 mm, SPEC / issue 2).

    A 12 mm wide, 20 mm tall block of soft rubber, E = 2 MPa, nu = 0.1,
    e_L = 0.8, thickness 1 mm, plane stress.  Nodes are forced at the mid-points of
    the two long sides, where the demo places its jaws (12 mm apart at rest); the
    demo also reports the quality at the paper's example separation of 10 mm.

    Parameters
    ----------
    max_area_mm2 : float
        Largest triangle area (mm²).

    Examples
    --------
    >>> part = demo_part()
    >>> part.name, round(part.diameter * 1e3, 6), part.mesh_options.points.tolist()
    ('rubber-12x20', 23.323808, [[0.0, 0.01], [0.012, 0.01]])
    """
    return Part.from_dict({
        "name": "rubber-12x20",
        "units": "mm",
        "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
        "holes": [],
        "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
                     "elastic_limit_strain": 0.8, "plane": "stress"},
        "mesh": {"max_area": max_area_mm2, "min_angle": 30, "points": [[0, 10], [12, 10]]},
    })


def notched_part(max_area_mm2: float = 0.4) -> Part:
    """The built-in part a frictionless gripper can hold: a notched rubber bar.

    A 30 × 12 mm bar of the demo's rubber (E = 2 MPa, nu = 0.1, e_L = 0.8, thickness
    1 mm, plane stress) with a V-notch 3 mm deep and 6 mm wide (45° flanks) in the middle
    of each long side; round pads seated in the notches hold it (SPEC §6).

    Parameters
    ----------
    max_area_mm2 : float
        Largest triangle area (mm²).

    Examples
    --------
    >>> part = notched_part()
    >>> part.name, len(part.outer), round(part.area * 1e6, 9)     # mm²: 360 − 2 × 9
    ('notched-bar-30x12', 10, 342.0)
    """
    return Part.from_dict({
        "name": "notched-bar-30x12",
        "units": "mm",
        "outer": [[0, 0], [12, 0], [15, 3], [18, 0], [30, 0], [30, 12], [18, 12], [15, 9],
                  [12, 12], [0, 12]],
        "holes": [],
        "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
                     "elastic_limit_strain": 0.8, "plane": "stress"},
        "mesh": {"max_area": max_area_mm2, "min_angle": 30},
    })


def part_from_drawing(path: InputFile, material=None, units: str | None = None,
                      layer: str | None = None, tolerance: float | None = None,
                      mesh: dict | None = None, name: str | None = None,
                      default_units: str | None = None, material_file: InputFile | None = None):
    """A :class:`Part` from a drawing (its geometry read by :mod:`deformclosure.drawing`).

    Parameters
    ----------
    path : path-like or Source
        ``.dxf`` or ``.svg`` file, or its name and bytes
        (:class:`~deformclosure.jsonfile.Source`).
    material : Material, str, path-like or Source, optional
        A material, or the text of ``--material`` (inline JSON or a JSON file; lengths in
        the drawing's units unless it states its own). Default: from ``material_file``.
    units, layer, tolerance, default_units
        See :func:`read_drawing`.
    mesh : dict, optional
        Part-file mesh options (``max_area`` in units², ``min_angle``, ``points``); default
        from ``material_file``, if it has a ``mesh`` block.
    name : str, optional
        Default: the file's stem.
    material_file : path-like or Source, optional
        The drawing's material file: a material object, optionally with ``units`` and a
        ``mesh`` block. Default: :func:`material_file_beside` the drawing (a path only).

    Raises
    ------
    PartError

    Examples
    --------
    >>> from deformclosure.jsonfile import Source
    >>> from deformclosure.part import part_from_drawing
    >>> svg = (b'<svg xmlns="http://www.w3.org/2000/svg" width="20mm" height="10mm" '
    ...        b'viewBox="0 0 20 10"><rect width="20" height="10"/>'
    ...        b'<circle cx="10" cy="5" r="2"/></svg>')
    >>> part = part_from_drawing(Source("plate.svg", svg), material='{"youngs_modulus": 2e6, '
    ...     '"poisson_ratio": 0.1, "thickness": 1, "elastic_limit_strain": 0.8}')
    >>> part.units, len(part.holes), round(part.area * 1e6)      # mm²
    ('mm', 1, 188)
    """
    src = drawing_source(path)
    drawing = read_drawing(src, units, layer, tolerance, default_units)
    if isinstance(material, (str, os.PathLike, Source)):
        material = read_material(material, drawing.units)
    elif material is not None and not isinstance(material, Material):
        raise PartError(f"material = {material!r}: give a Material, inline JSON or a "
                        "material file")
    if material is None or mesh is None:
        side = material_file if material_file is not None else material_file_beside(path)
        if side is not None:
            material, mesh = _drawing_material_file(side, drawing.units, material, mesh)
        elif material is None:
            hint = "" if isinstance(path, Source) else \
                f" or put it in {material_path_beside(Path(path)).name} beside the drawing"
            raise PartError(f"{src.name}: a drawing has no material; give --material "
                            f"FILE|JSON{hint}")
    scale = length_scale(drawing.units)
    mat = material.to_dict()
    mat["thickness"] = material.thickness / scale
    if material.critical_distance is not None:
        mat["critical_distance"] = material.critical_distance / scale
    data = {"name": name or Path(src.name).stem, "units": drawing.units,
            "outer": drawing.outer.tolist(), "holes": [h.tolist() for h in drawing.holes],
            "material": mat}
    if mesh is not None:
        data["mesh"] = mesh
    part = Part.from_dict(data)
    import dataclasses

    return dataclasses.replace(part, material=material)


def _drawing_material_file(side: InputFile, units: str, material, mesh):
    """``(material, mesh)``, each kept if given, else from the material file ``side``
    (lengths in the drawing's ``units`` unless it states its own)."""
    import json

    from .jsonfile import read_json

    data = read_json(side if isinstance(side, Source) else Path(side), PartError, "material file")
    if isinstance(data, dict) and mesh is None and isinstance(data.get("mesh"), dict):
        mesh = data["mesh"]
    if material is None:
        blob = {k: v for k, v in data.items() if k != "mesh"} if isinstance(data, dict) else data
        material = read_material(json.dumps(blob), units, str(side))
    return material, mesh
