"""One library function per command: validated inputs in, a :class:`Report` out.

The CLI, the batch runner and Python users all go through :func:`run`::

    >>> from deformclosure import reports
    >>> rep = reports.run("mesh", "examples/rectangle.json")        # doctest: +SKIP
    >>> rep.data["n_nodes"], rep.lines[0]                             # doctest: +SKIP

A command's parameters are those of its CLI options (:mod:`.options`, the one table of
them), by their Python names (``pad_radius``), lengths in the part's units like on the
command line; the report (:attr:`Report.data`) is SI. :meth:`Report.save` writes the
outputs the parameters name (``output``, ``plot``, ``export_fields``, ``export_graph``).

Layering: this package sits above the models and below :mod:`deformclosure.batch` and
:mod:`deformclosure.cli`; it imports neither.
"""

from __future__ import annotations

from .base import Report
from .options import JOB_COMMANDS, OPTIONS, defaults, key_params, options_of, parse_argv

__all__ = ["run", "Report", "COMMANDS", "JOB_COMMANDS", "OPTIONS", "parse_argv", "defaults",
           "key_params", "options_of"]

#: Command name -> module of :mod:`deformclosure.reports` holding its ``run``.
COMMANDS = {"mesh": "mesh", "optimize": "optimize", "check": "check", "slice": "slice",
            "plan": "plan", "import": "drawing"}


def run(command: str, part, params: dict | None = None, *, progress=None, notify=None) -> Report:
    """Run one command on one part, mesh or drawing file and return its report.

    Parameters
    ----------
    command : str
        ``"mesh"``, ``"optimize"``, ``"check"``, ``"slice"``, ``"plan"`` or ``"import"``.
    part : str, path or :class:`deformclosure.jsonfile.Source`
        The input file (a Source: its bytes, as a batch worker has them).
    params : dict, optional
        The command's parameters by name (see :func:`defaults`); missing ones take their
        defaults. File parameters (``fingers``, a ``material`` file) may be paths or
        Sources.
    progress : callable(done, total), optional
        Called as long work advances (the CLI draws a bar).
    notify : callable(str), optional
        Receives progress notes meant for people (the CLI prints them on stderr).

    Returns
    -------
    Report

    Raises
    ------
    DeformClosureError
        Any bad input, with a one-line message naming the field and the fix.
    """
    import importlib

    from ..errors import DeformClosureError

    if command not in COMMANDS:
        raise DeformClosureError(f"command {command!r}: choose one of {', '.join(COMMANDS)}")
    full = defaults(command)
    unknown = sorted(set(params or {}) - set(full))
    if unknown:
        raise DeformClosureError(f"{command}: no parameter {unknown[0]!r}; the parameters are "
                                 f"{', '.join(full)}")
    full.update(params or {})
    from .options import options_of

    for opt in options_of(command):          # the CLI, batch and library callers alike
        if opt.required and full.get(opt.name) is None:
            raise DeformClosureError(f"{opt.flags[-1]}: required for {command}; see "
                                     f"'deformclosure {command} --help'")
        if opt.kind == "plot" and full.get(opt.name) is not None:   # before any work
            opt.convert(str(full[opt.name]), opt.flags[-1])
    module = importlib.import_module(f".{COMMANDS[command]}", __name__)
    return module.run(part, full, progress=progress, notify=notify)
