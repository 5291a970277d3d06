"""Helpers shared by the CLI subcommands: loading inputs, writing reports."""

from __future__ import annotations

import json
import math
from contextvars import ContextVar
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DeformClosureError
from ..outputs import write_text_atomic
from ..mesh import Mesh, mesh_part, read_mesh
from ..mesh.io import is_mesh_file
from ..part import Part
from ..units import length_scale

__all__ = ["load_part_or_mesh", "write_json", "json_safe", "parse_xy", "pad_from_options",
           "pad_options", "check_grid", "lazy_progress", "with_verbosity", "VERBOSITY",
           "mesh_input_options"]


def load_part_or_mesh(path: str | Path, points: np.ndarray | None = None,
                      units: str | None = None, material: str | None = None,
                      need_material: bool = True) -> tuple[Part | None, Mesh]:
    """Read a part file (and mesh it, inserting ``points`` in m) or a mesh file.

    Parameters
    ----------
    path : path-like
    points : ndarray, shape (k, 2), optional
        Points (m) to insert as mesh nodes (part files only).
    units : str, optional
        ``--units``: the unit of a meshio file's coordinates (default m) and of a
        ``--material`` that states none (default: the part's units, else m).
    material : str, optional
        ``--material``: inline JSON or a JSON file (:func:`deformclosure.part.read_material`);
        it replaces the file's material.
    need_material : bool
        Refuse a mesh that ends up without a material, naming ``--material``.
    """
    from ..part import read_material

    path = Path(path)
    if not path.exists():
        raise DeformClosureError(f"{path}: file not found; give a part file (.json) or a mesh file")
    if units is not None:
        length_scale(units, "--units")
    if is_mesh_file(path):
        mat = None if material is None else read_material(material, units or "m")
        mesh = read_mesh(path, units=units or "m", material=mat)
        if need_material and mesh.material is None:
            raise DeformClosureError(
                f"{path}: the mesh file has no material; give --material FILE or --material "
                "'{\"youngs_modulus\": 2e6, \"poisson_ratio\": 0.1, \"thickness\": 1, "
                "\"elastic_limit_strain\": 0.8, \"units\": \"mm\"}'")
        return None, mesh
    part = read_part(path, units, material)
    return part, mesh_part(part, points=points)


def read_part(path: str | Path, units: str | None = None, material: str | None = None) -> Part:
    """Read a part file, give it the ``--material`` if one is given (lengths in ``units``,
    default the part's), and print its unit-sanity warnings."""
    import dataclasses

    from ..drawing import is_drawing_file, part_from_drawing
    from ..part import read_material

    if is_drawing_file(path):
        part = part_from_drawing(path, material=material, default_units=units)
    else:
        part = Part.from_file(path)
        if material is not None:
            part = dataclasses.replace(part, material=read_material(material, units or part.units))
    warn_part(part)
    return part


def mesh_input_options(units: bool = True):
    """Click options of every command that reads a part or mesh: ``--material`` and, when
    the command has none yet (``units=True``), ``--units``."""
    import click

    opts = [click.option(
        "--material", type=str, default=None, metavar="FILE|JSON",
        help="Material replacing the input's (needed for mesh files without one): a JSON "
             "file or inline JSON with youngs_modulus (Pa), poisson_ratio, thickness, "
             "elastic_limit_strain [, plane, critical_distance, units].")]
    if units:
        opts.append(click.option(
            "--units", type=str, default=None,
            help="Unit of the lengths given here and of a meshio file's coordinates "
                 "(m, cm, mm, in; default: the part file's units, m for mesh files)."))

    def decorate(fn):
        for opt in reversed(opts):
            fn = opt(fn)
        return fn

    return decorate


def warn_part(part: Part) -> None:
    """Print the part's unit-sanity warnings on standard error."""
    import click

    for w in part.sanity_warnings():
        click.echo(f"warning: {w}", err=True)


def json_safe(obj: Any) -> Any:
    """Convert numpy scalars/arrays to Python; non-finite floats to ``None``."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    return obj


#: The real standard output while a command writes its report there (``-o -``): every
#: human-readable line then goes to standard error, so stdout is pure JSON.
REPORT_STDOUT = None

#: Input files of the running command (set by ``main`` and the batch runner), recorded in
#: its report; a context variable, so concurrent jobs in threads keep their own.
INPUTS: ContextVar[tuple] = ContextVar("deformclosure_inputs", default=())


def provenance() -> dict:
    """Package version and the name and SHA-256 of every input file of the command."""
    import hashlib

    from .. import __version__

    files = []
    for p in INPUTS.get():
        try:
            digest = hashlib.sha256(Path(p).read_bytes()).hexdigest()
        except OSError:
            continue
        files.append({"name": Path(p).name, "sha256": digest})
    return {"package": "deformclosure", "version": __version__, "inputs": files}


def write_json(report: dict, path: str | Path | None) -> None:
    """Write ``report`` as JSON to ``path`` (nothing if ``None``; ``-`` is stdout)."""
    import sys

    if path is None:
        return
    report = {**report, "provenance": provenance()}
    text = json.dumps(json_safe(report), indent=2, allow_nan=False)
    if str(path) == "-":
        print(text, file=REPORT_STDOUT or sys.stdout, flush=True)
        return
    write_text_atomic(path, text + "\n", "report")


def parse_xy(text: str, field: str) -> tuple[float, float]:
    """Parse ``"X,Y"`` into a pair of floats."""
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise DeformClosureError(f"{field}: expected X,Y (two numbers separated by a comma), got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise DeformClosureError(f"{field}: coordinates must be finite, got {text!r}")
    return x, y


def pad_from_options(radius: float | None, width: float, scale: float, diameter: float):
    """The pad of ``--pad-radius``/``--pad-width`` (in units of ``scale`` m); the default
    radius is 5 % of the part's ``diameter`` (m)."""
    from ..pads import Pad

    if radius is not None and not (math.isfinite(radius) and radius > 0):
        raise DeformClosureError(f"--pad-radius = {radius!r}: must be a finite length > 0")
    if not (math.isfinite(width) and width >= 0):
        raise DeformClosureError(f"--pad-width = {width!r}: must be a finite length >= 0")
    rho = 0.05 * diameter if radius is None else radius * scale
    for name, v in (("--pad-radius", rho), ("--pad-width", width * scale)):
        if v > 100 * diameter:
            raise DeformClosureError(f"{name} = {v:.3g} m: more than 100 times the part's diameter "
                                     f"({diameter:.3g} m); check the value and --units")
    return Pad(width * scale, rho)


def check_grid(angles: int, offsets: int) -> None:
    """Refuse release-landscape grids outside 4..2000 angles/offsets."""
    for name, v in (("--grid-angles", angles), ("--grid-offsets", offsets)):
        if not (4 <= v <= 2000):
            raise DeformClosureError(f"{name} = {v}: give a whole number from 4 to 2000")


def lazy_progress(quiet: bool, desc: str, unit: str):
    """A ``progress(done, total)`` callback whose tqdm bar appears at the first call (so
    input errors print no bar), and a ``close()`` for it."""
    from tqdm import tqdm

    state = {"bar": None}
    quiet = quiet or VERBOSITY.get() == 0

    def progress(done: int, total: int) -> None:
        if quiet:
            return
        if state["bar"] is None:
            state["bar"] = tqdm(total=total, desc=desc, unit=unit, leave=False)
        state["bar"].update(done - state["bar"].n)

    def close() -> None:
        if state["bar"] is not None:
            state["bar"].close()

    return progress, close


def pad_options(angles: int, offsets: int):
    """Click options of the pad model shared by ``optimize`` and ``plan``: the pad's size
    and the release landscape's grid (defaults ``angles``, ``offsets``)."""
    import click

    opts = [
        click.option("--pad-radius", type=float, default=None,
                     help="pads: radius of the pad ends (default 5 % of the part's diameter)."),
        click.option("--pad-width", type=float, default=0.0, show_default=True,
                     help="pads: width of the flat face (0 = round fingertip)."),
        click.option("--grid-angles", type=int, default=angles, show_default=True,
                     help="pads: axis angles in the release landscape (Δθ = 180°/N)."),
        click.option("--grid-offsets", type=int, default=offsets, show_default=True,
                     help="pads: axis offsets per part diameter in the release landscape."),
    ]

    def decorate(fn):
        for opt in reversed(opts):
            fn = opt(fn)
        return fn

    return decorate


#: 0 ``--quiet``, 1 normal, 2 ``--verbose``: of the running command (a context variable,
#: so batch jobs running in threads keep their own).
VERBOSITY: ContextVar[int] = ContextVar("deformclosure_verbosity", default=1)


def with_verbosity(command, keep_stdout: bool = False):
    """Give ``command`` the ``--quiet`` and ``--verbose`` options every command has.

    ``--quiet``: no progress bars and no human-readable lines on standard output (the
    report of ``-o -``, errors and warnings still appear). ``--verbose``: also log each
    main step of the library with its time on standard error. A command that already
    declares ``--quiet`` receives the flag itself as well. ``keep_stdout``: standard output
    is the command's product (``results``), kept under ``--quiet``.
    """
    import functools
    import sys

    import click

    own = {p.name: p for p in command.params}
    for name, short in (("quiet", "-q"), ("verbose", "-v")):
        taken = {o for p in command.params for o in getattr(p, "opts", ())}
        if name in own and short not in taken:
            own[name].opts.append(short)
    if "quiet" not in own:
        command.params.append(click.Option(
            ["--quiet", "-q"], is_flag=True,
            help="Only the report, errors and warnings: no progress, no summary lines."))
    if "verbose" not in own:
        command.params.append(click.Option(
            ["--verbose", "-v"], is_flag=True,
            help="Also log each step (meshing, factorisation, solves) with its time on stderr."))
    callback = command.callback

    @functools.wraps(callback)
    def run(*args, **kwargs):
        quiet = kwargs["quiet"] if "quiet" in own else kwargs.pop("quiet")
        verbose = kwargs["verbose"] if "verbose" in own else kwargs.pop("verbose")
        if quiet and verbose:
            raise DeformClosureError("--quiet/--verbose: give at most one of them")
        token = VERBOSITY.set(0 if quiet else 2 if verbose else 1)
        handler = None
        if verbose:
            from ..log import show_steps

            handler = show_steps(sys.stderr)
        global REPORT_STDOUT
        silenced = quiet and not keep_stdout and _may_swap_stdout()
        saved = (sys.stdout, REPORT_STDOUT)
        if silenced:
            import os

            REPORT_STDOUT = REPORT_STDOUT or sys.stdout
            sys.stdout = open(os.devnull, "w", encoding="utf-8")
        try:
            return callback(*args, **kwargs)
        finally:
            if silenced:
                sys.stdout.close()
                sys.stdout, REPORT_STDOUT = saved
            if handler is not None:
                from ..log import logger

                logger.removeHandler(handler)
            VERBOSITY.reset(token)

    command.callback = run
    return command


def _may_swap_stdout() -> bool:
    """Whether ``sys.stdout`` may be replaced: only in the main thread, never while the batch
    runner routes each thread's output to its own buffer (it keeps a job's lines anyway)."""
    import sys
    import threading

    return (threading.current_thread() is threading.main_thread()
            and type(sys.stdout).__name__ != "_ThreadRouter")
