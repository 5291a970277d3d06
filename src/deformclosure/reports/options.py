"""The options of every report command, in one table: the CLI builds its click options
from it and the batch runner parses a job's option strings with it.

An option's *role* says what it is to a batch job:

``param``
    a value of the computation; part of the job key.
``input``
    a file the command reads (``--fingers``); its bytes enter the job key.
``file_or_json``
    ``--material``: inline JSON (a value) or a file (an input).
``output``
    a file or folder the command writes (``-o``, ``--plot``, ``--export-fields``); not in
    the key.
``display``
    changes only what is printed or drawn (``--quiet``, ``--scale``); not in the key.

This module imports nothing heavy (no numpy, no click at import time): ``deformclosure
--help`` reads it.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from typing import Any, Sequence

from ..choices import MATERIAL_MODELS, METHODS, MODELS
from ..errors import DeformClosureError
from ..limits import MAX_SLICE_RESOLUTION

__all__ = ["Opt", "OPTIONS", "JOB_COMMANDS", "options_of", "parse_argv", "defaults",
           "key_params"]

#: Commands that can be batch jobs (they read one part or mesh file).
JOB_COMMANDS = ("check", "mesh", "optimize", "plan", "slice")

ROLES = ("param", "input", "file_or_json", "output", "display")


@dataclass(frozen=True)
class Opt:
    """One option of a command.

    Attributes
    ----------
    name : str
        Parameter name (``pad_radius``).
    flags : tuple of str
        Spellings on the command line (``("--pad-radius",)``, ``("-o", "--output")``).
    kind : str
        ``"float"``, ``"int"``, ``"str"``, ``"flag"`` (no value), ``"choice"``,
        ``"file"`` (a file path), ``"folder"`` (a folder path) or ``"plot"`` (``--plot``:
        a folder, or a file whose suffix — png, svg, pdf — sets the format of every
        figure; :func:`deformclosure.outputs.plot_target`, checked as it is parsed).
    default : object
        Value when absent (``None``: not given).
    help : str
        One-sentence help.
    role : str
        See the module docstring.
    nargs : int
        Values taken (``--at X,Y X,Y`` takes 2).
    multiple : bool
        Repeatable; the values collect in a tuple.
    choices : tuple of str
        For ``kind="choice"``.
    required : bool
    metavar : str, optional
    show_default : bool
    """

    name: str
    flags: tuple[str, ...]
    kind: str = "str"
    default: Any = None
    help: str = ""
    role: str = "param"
    nargs: int = 1
    multiple: bool = False
    choices: tuple[str, ...] = ()
    required: bool = False
    metavar: str | None = None
    show_default: bool = False

    def convert(self, text: str, shown: str) -> Any:
        """One value of this option from its text; a one-line error naming the option."""
        if self.kind in ("float", "int"):
            try:
                v = float(text) if self.kind == "float" else int(text)
            except ValueError:
                what = "a number" if self.kind == "float" else "a whole number"
                raise DeformClosureError(f"{shown}: {text!r} is not {what}") from None
            if self.kind == "float" and math.isnan(v):
                raise DeformClosureError(f"{shown}: {text!r} is not a number")
            return v
        if self.kind == "plot":
            from ..outputs import plot_target

            plot_target(text, shown)
            return text
        if self.kind == "choice" and text not in self.choices:
            raise DeformClosureError(f"{shown} = {text!r}: choose one of {', '.join(self.choices)}")
        return text


# ----------------------------------------------------------------------------- shared groups

_OUTPUT = Opt("output", ("-o", "--output"), "file", role="output",
              help="Write the JSON report here (SI units; '-' for stdout).")
_MATERIAL = Opt("material", ("--material",), "str", role="file_or_json", metavar="FILE|JSON",
                help="Material replacing the input's (needed for mesh files without one): a "
                     "JSON file or inline JSON with youngs_modulus (Pa), poisson_ratio, "
                     "thickness, elastic_limit_strain [, plane, critical_distance, units].")
_MAX_AREA = Opt("max_area", ("--max-area",), "float",
                help="Largest triangle area of the starting mesh, in the part's units² "
                     "(overrides the part's mesh.max_area; part files and drawings only).")
_ACCURACY = (
    Opt("rtol", ("--rtol",), "float",
        help="pads: relative accuracy of Q* and U_A to refine to (default 0.05; mesh and "
             "landscape, adaptively)."),
    Opt("max_seconds", ("--max-seconds",), "float",
        help="pads: time budget of the refinement in seconds (default 120); when it runs "
             "out the report says converged: false."),
    Opt("uniform", ("--uniform",), "flag", False,
        help="pads: with --rtol, refine the mesh everywhere instead of adaptively."),
)
_ELASTICITY = Opt("elasticity", ("--elasticity",), "choice", choices=MATERIAL_MODELS,
                  help="pads: material law — linear (small strain, SPEC §6) or neo-hookean "
                       "(finite strain with the exact pad contact, SPEC §8); default the "
                       "part's material.model (linear).")
_FRICTION = Opt("friction", ("--friction",), "float", 0.0, show_default=True,
                help="Coulomb friction coefficient μ between pads (fingers) and part (SPEC "
                     "§9); 0 = frictionless (SPEC §6 exactly). pads: Q with the release work "
                     "U_A^μ and the holding force; not yet supported by check.")
_UNITS = Opt("units", ("--units",), "str",
             help="Unit of the lengths given here and of a meshio file's coordinates (m, cm, "
                  "mm, in; default: the part file's units, m for mesh files).")
_DISPLAY = (
    Opt("quiet", ("--quiet", "-q"), "flag", False, role="display",
        help="Only the report, errors and warnings: no progress, no summary lines."),
    Opt("verbose", ("--verbose", "-v"), "flag", False, role="display",
        help="Also log each step (meshing, factorisation, solves) with its time on stderr."),
)
_FIELDS = ("--export-fields",)

_PLOT_FORMS = ("a folder (PNG figures) or a .png/.svg/.pdf file whose suffix sets the format "
               "of every figure (out/fig.svg writes out/fig_<figure>.svg)")


def _plot(what: str, single: bool = False) -> Opt:
    """``--plot``: a folder or a picture file (:func:`deformclosure.outputs.plot_target`)."""
    where = ("a .png/.svg/.pdf file (its suffix sets the format), or a folder (PNG)"
             if single else _PLOT_FORMS)
    return Opt("plot", ("--plot",), "plot", role="output", metavar="PATH",
               help=f"{what}: {where}.")


_ANIMATE = Opt("animate", ("--animate",), "flag", False, role="display",
               help="With --plot: also write the escape path as an animated GIF beside the "
                    "pictures (escape.gif in a folder, <stem>_escape.gif beside a file; "
                    "optimize: pads model). Needs Pillow.")
_SCALE = Opt("scale", ("--scale",), "float", 1.0, role="display", show_default=True,
             help="pads pictures (--plot): draw the displacements this many times their size "
                  "(1 = true scale; the pads move with the part).")


def _pads(angles: int, offsets: int) -> tuple[Opt, ...]:
    """The pad model's options shared by ``optimize`` and ``plan``."""
    return (
        Opt("pad_radius", ("--pad-radius",), "float",
            help="pads: radius of the pad ends (default 5 % of the part's diameter)."),
        Opt("pad_width", ("--pad-width",), "float", 0.0, show_default=True,
            help="pads: width of the flat face (0 = round fingertip)."),
        Opt("grid_angles", ("--grid-angles",), "int", angles, show_default=True,
            help="pads: axis angles in the release landscape (Δθ = 180°/N)."),
        Opt("grid_offsets", ("--grid-offsets",), "int", offsets, show_default=True,
            help="pads: axis offsets per part diameter in the release landscape."),
    )


OPTIONS: dict[str, tuple[Opt, ...]] = {
    "mesh": (
        Opt("output", ("-o", "--output"), "file", role="output",
            help="Mesh file to write: .json (SPEC mesh JSON, metres) or any meshio format."),
        Opt("max_area", ("--max-area",), "float",
            help="Override the part's mesh.max_area (in the part's units²)."),
        Opt("min_angle", ("--min-angle",), "float",
            help="Override the part's mesh.min_angle (degrees, <= 34)."),
        _plot("Write a picture of the mesh", single=True),
        _MATERIAL, _UNITS,
        *_DISPLAY,
    ),
    "optimize": (
        Opt("model", ("--model",), "choice", choices=MODELS,
            help="pads (default): rigid pads on a grasp axis, converged (SPEC §6); paper: "
                 "point jaws at mesh nodes (SPEC §4). --jaws implies paper."),
        Opt("jaws", ("--jaws",), "int", nargs=2, metavar="A B", help="Jaw node ids (paper model)."),
        Opt("at", ("--at",), "str", nargs=2, metavar="X,Y X,Y",
            help="pads: the closing axis through these points; paper: jaw positions "
                 "(inserted as mesh nodes for part files)."),
        Opt("axis", ("--axis",), "str", metavar="X,Y,DEG",
            help="pads: the closing axis through (X, Y) at DEG degrees."),
        *_pads(48, 50),
        Opt("refine", ("--refine",), "int",
            help="pads: solve N uniform levels (h halving, the landscape refined at the "
                 "saddle) instead of refining to --rtol; 1 = one mesh, no error estimate."),
        *_ACCURACY,
        _ELASTICITY,
        _FRICTION,
        Opt("method", ("--method",), "choice", "exact", choices=METHODS, show_default=True,
            help="paper model: exact: ours; paper: every crossing; approx: ε-grid."),
        Opt("eps", ("--eps",), "float",
            help="paper model, --method approx: ε in joules (default 1e-3 · ½ k01 (σ0 − σ_L)², "
                 "or larger if needed for at most 20 000 grid steps)."),
        Opt("expanding", ("--expanding",), "flag", False,
            help="Jaws push outward from inside a hole (pads: the hole holding the --at "
                 "mid-point or the --axis point)."),
        Opt("jaw_width", ("--jaw-width",), "float", 0.0, show_default=True,
            help="paper model: jaw contact width (0 = point jaws)."),
        _MATERIAL, _UNITS, _MAX_AREA,
        Opt("output", ("-o", "--output"), "file", role="output", help="JSON report (SI units)."),
        _plot("The pictures (pads: deformed part at sigma* with strain and contact pressure, "
              "Q and force against sigma, escape path, convergence)"),
        _SCALE,
        _ANIMATE,
        Opt("export_graph", ("--export-graph",), "file", role="output",
            help="paper model: write the contact graph (JSON)."),
        Opt("export_fields", _FIELDS, "file", role="output",
            help="Write the fields at σ* to FILE.vtu (and at σ_L to FILE_sigma_L.vtu; pads: "
                 "FILE_pads.vtu) for ParaView: rest mesh + displacement (Warp By Vector), "
                 "strain and stress tensors, contact force and pressure; FILE.pvd: the "
                 "squeeze from first touch to σ_L as an animation."),
        *_DISPLAY,
    ),
    "check": (
        Opt("fingers", ("--fingers",), "file", role="input", required=True,
            help="Finger file (JSON, see below)."),
        _OUTPUT,
        _plot("Draw the part, fingers, contact forces, escaping motion and escape path",
              single=True),
        _ANIMATE,
        Opt("grid_steps", ("--grid-steps",), "int", 48, show_default=True,
            help="Release landscape: translation steps per part diameter (at most half the "
                 "smallest disc radius per step)."),
        Opt("saddle_levels", ("--saddle-levels",), "int", 2, show_default=True,
            help="Release landscape: halvings of the lattice near the saddle (error estimate)."),
        Opt("export_fields", _FIELDS, "file", role="output",
            help="Write the fields at the equilibrium to FILE.vtu (or a one-frame FILE.pvd) "
                 "for ParaView: rest mesh + displacement (Warp By Vector), strain and stress "
                 "tensors, contact force and pressure."),
        Opt("rtol", ("--rtol",), "float",
            help="Refine the mesh (h halved per level) until the error estimates of U_A and "
                 "of the quality (mesh levels plus lattice) are within this fraction "
                 "(default 0.05; a mesh file is solved once)."),
        Opt("refine", ("--refine",), "int",
            help="Solve N uniform mesh levels instead of refining to --rtol; 1 = one mesh, "
                 "no error estimate."),
        _ACCURACY[1],
        Opt("elasticity", ("--elasticity",), "choice", choices=MATERIAL_MODELS,
            help="Material law: linear (SPEC §7); neo-hookean is not supported by check yet "
                 "(it is by optimize and plan)."),
        _FRICTION,
        _MATERIAL, _UNITS, _MAX_AREA,
        *_DISPLAY,
    ),
    "slice": (
        Opt("node", ("--node",), "int", help="Id of the moving node."),
        Opt("at", ("--at",), "str", metavar="X,Y", help="Move the node at X,Y instead of --node."),
        Opt("fingers", ("--fingers",), "file", role="input", required=True,
            help="Finger file (JSON; see `deformclosure check --help`)."),
        Opt("extent", ("--extent",), "str", metavar="XMIN,XMAX,YMIN,YMAX",
            help="Region swept by the node (default: twice its longest edge around it)."),
        Opt("resolution", ("--resolution",), "int", 200, show_default=True,
            help=f"Pixels per axis (2..{MAX_SLICE_RESOLUTION:,})."),
        Opt("energy", ("--energy",), "choice", "linear", choices=("linear", "corotational"),
            show_default=True, help="Strain energy: linear or corotational."),
        Opt("units", ("--units",), "choice", choices=("m", "cm", "mm", "in"),
            help="Units of --at and --extent, and of a meshio file's coordinates."),
        Opt("output", ("-o", "--output"), "file", role="output", help="Write .npz or .json."),
        _plot("Draw the slice", single=True),
        Opt("export_fields", _FIELDS, "file", role="output",
            help="Write the slice as an image for ParaView (.vtu): energy, D_free, D_T and "
                 "each D-obstacle over the positions of the moving node."),
        _MATERIAL, _MAX_AREA,
        *_DISPLAY,
    ),
    "plan": (
        Opt("model", ("--model",), "choice", "pads", choices=MODELS, show_default=True,
            help="pads: grasp axes for rigid pads (SPEC §6); paper: node pairs (SPEC §4)."),
        *_pads(36, 40),
        Opt("top", ("--top",), "int", 10, show_default=True,
            help="Refine the best N pairs (paper) with the exact method; rows shown (pads)."),
        Opt("verify", ("--verify",), "int", 5, show_default=True,
            help="pads: verify the best N screened candidates with optimize's code path on "
                 "the plan's mesh and one with h doubled (error estimate); only a verified "
                 "row can be 'held'."),
        *_ACCURACY[:2],
        _ELASTICITY,
        _FRICTION,
        Opt("eps", ("--eps",), "float",
            help="paper: every pair's quality within eps of its optimum, in joules."),
        Opt("allow_pulling", ("--allow-pulling",), "flag", False,
            help="paper: let pairs whose jaws would have to pull into the top list."),
        Opt("expanding", ("--expanding",), "flag", False,
            help="Jaws push outward (e.g. from inside a hole)."),
        Opt("jaw_width", ("--jaw-width",), "float", 0.0, show_default=True,
            help="Jaw contact width in --units (0 = point jaws)."),
        Opt("min_sep", ("--min-sep",), "float", help="Smallest rest distance of a pair, in --units."),
        Opt("max_sep", ("--max-sep",), "float", help="Largest rest distance of a pair, in --units."),
        Opt("region", ("--region",), "str", multiple=True, metavar="X0,Y0,X1,Y1",
            help="Allowed box for both jaws (repeatable; union), in --units."),
        Opt("units", ("--units",), "str", help="Unit of lengths given here (m, cm, mm, in)."),
        _MATERIAL, _MAX_AREA,
        Opt("output", ("-o", "--output"), "file", role="output", help="JSON report (SI units)."),
        _plot("The pictures (pads: quality map over (angle, offset), top grasps deformed at "
              "sigma*, convergence of the verified ones)"),
        _SCALE,
        *_DISPLAY,
    ),
    "import": (
        Opt("output", ("-o", "--output"), "file", role="output", required=True,
            help="Part file to write (JSON, SI: metres); '-' for stdout."),
        Opt("units", ("--units",), "str",
            help="Unit of the drawing's coordinates, overriding its header (m, cm, mm, in)."),
        Opt("layer", ("--layer",), "str",
            help="DXF: read only this layer; SVG: only the element (group) with this id."),
        Opt("tolerance", ("--tolerance",), "float",
            help="Largest chord-to-curve distance, in the drawing's units (default 0.1 % of "
                 "its bounding-box diagonal)."),
        Opt("material", ("--material",), "str", role="file_or_json", metavar="FILE|JSON",
            help="Material: a JSON file or inline JSON (youngs_modulus Pa, poisson_ratio, "
                 "thickness, elastic_limit_strain [, plane, critical_distance, units])."),
        _plot("Draw the imported outline", single=True),
        *_DISPLAY,
    ),
}


def options_of(command: str) -> tuple[Opt, ...]:
    """The options of ``command``; one-line error listing the commands otherwise."""
    if command not in OPTIONS:
        raise DeformClosureError(f"command {command!r}: choose one of {', '.join(sorted(OPTIONS))}")
    return OPTIONS[command]


def defaults(command: str) -> dict[str, Any]:
    """Every parameter of ``command`` at its default."""
    return {o.name: (() if o.multiple else o.default) for o in options_of(command)}


def _split(argv: Sequence[str], spellings: dict[str, Opt]) -> list[str]:
    """``--name=value`` of a known option as two tokens (so paths sit in their own)."""
    out: list[str] = []
    for tok in argv:
        name, eq, value = tok.partition("=")
        out += [name, value] if eq and name in spellings else [tok]
    return out


def parse_argv(command: str, argv: Sequence[str]) -> dict[str, Any]:
    """Parse a job's option strings as the CLI would, without click.

    Parameters
    ----------
    command : str
        One of :data:`OPTIONS`.
    argv : sequence of str
        The options (no part file): ``["--top", "5", "--model=paper"]``.

    Returns
    -------
    dict
        Every parameter of the command, defaults included; ``nargs > 1`` and repeatable
        options as tuples.

    Raises
    ------
    DeformClosureError
        An unknown option (with the nearest spelling), a missing or bad value, a value
        outside the choices, a missing required option, a stray argument.

    Examples
    --------
    >>> p = parse_argv("plan", ["--top", "5", "--model=paper", "--region", "0,0,1,1"])
    >>> p["top"], p["model"], p["region"], p["eps"]
    (5, 'paper', ('0,0,1,1',), None)
    >>> parse_argv("plan", ["--tops", "5"])
    Traceback (most recent call last):
    ...
    deformclosure.errors.DeformClosureError: plan: no option --tops (did you mean --top?)
    """
    table = options_of(command)
    spellings = {f: o for o in table for f in o.flags}
    params = defaults(command)
    tokens, i, seen = _split(argv, spellings), 0, set()
    while i < len(tokens):
        tok = tokens[i]
        opt = spellings.get(tok)
        if opt is None:
            near = difflib.get_close_matches(tok, list(spellings), n=1)
            hint = f" (did you mean {near[0]}?)" if near else ""
            what = "no option" if tok.startswith("-") else "unexpected argument"
            raise DeformClosureError(f"{command}: {what} {tok}{hint}")
        if opt.kind == "flag":
            params[opt.name], i = True, i + 1
            continue
        values = tokens[i + 1:i + 1 + opt.nargs]
        if len(values) < opt.nargs:
            raise DeformClosureError(f"{command}: {tok} needs {opt.nargs} value(s)")
        vals = tuple(opt.convert(v, tok) for v in values)
        value = vals[0] if opt.nargs == 1 else vals
        params[opt.name] = params[opt.name] + (value,) if opt.multiple else value
        seen.add(opt.name)
        i += 1 + opt.nargs
    for o in table:
        if o.required and o.name not in seen:
            raise DeformClosureError(f"{command}: missing option {o.flags[-1]}")
    return params


def key_params(command: str, params: dict[str, Any]) -> dict[str, Any]:
    """The parameters that identify a job: outputs and display options left out."""
    skip = {o.name for o in options_of(command) if o.role in ("output", "display")}
    return {k: v for k, v in params.items() if k not in skip}
