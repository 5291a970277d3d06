"""What every CLI command shares: click options built from the one option table
(:mod:`deformclosure.reports.options`), running a report command, printing its summary
and writing its outputs, the ``--quiet``/``--verbose`` switches and progress bars.

The commands themselves only parse arguments, print and write: the work is in
:mod:`deformclosure.reports`.
"""

from __future__ import annotations

from contextvars import ContextVar
from typing import Any

__all__ = ["table_options", "run_report", "lazy_progress", "with_verbosity", "VERBOSITY",
           "REPORT_STDOUT"]

#: The real standard output while a command writes its report there (``-o -``): every
#: human-readable line then goes to standard error, so stdout is pure JSON.
REPORT_STDOUT = None

#: 0 ``--quiet``, 1 normal, 2 ``--verbose``: of the running command.
VERBOSITY: ContextVar[int] = ContextVar("deformclosure_verbosity", default=1)


def _click_option(opt):
    """The click option of one :class:`~deformclosure.reports.options.Opt`."""
    import click

    kinds = {"float": float, "int": int, "str": str,
             "file": click.Path(dir_okay=False), "folder": click.Path(file_okay=False)}
    extra: dict[str, Any] = {}
    if opt.kind == "flag":
        extra["is_flag"] = True
    elif opt.kind == "choice":
        extra["type"] = click.Choice(list(opt.choices))
    elif opt.kind == "plot":      # checked as it is parsed: a bad suffix before any work
        extra["type"] = str
        extra["callback"] = lambda ctx, param, value: (
            value if value is None else opt.convert(value, opt.flags[-1]))
    else:
        extra["type"] = kinds[opt.kind]
    if opt.nargs != 1:
        extra["nargs"] = opt.nargs
    if opt.metavar:
        extra["metavar"] = opt.metavar
    return click.option(*opt.flags, opt.name, default=opt.default, help=opt.help,
                        multiple=opt.multiple, required=opt.required,
                        show_default=opt.show_default, **extra)


def table_options(command: str):
    """Decorate a click command with the options of ``command`` from the option table."""
    from ..reports.options import options_of

    def decorate(fn):
        for opt in reversed(options_of(command)):
            fn = _click_option(opt)(fn)
        return fn

    return decorate


def _check_outputs(command: str, part: str, params: dict) -> None:
    """Refuse, before any work, outputs that cannot be written or would replace an input."""
    from ..outputs import check_outputs
    from ..reports.options import options_of

    files, folders, inputs = [], [], [part]
    for opt in options_of(command):
        value = params.get(opt.name)
        if value is None:
            continue
        if opt.role == "input":
            inputs.append(value)
        elif opt.kind == "plot":             # its folder is created by the writer
            from pathlib import Path

            from ..outputs import plot_target

            target = plot_target(value, opt.flags[-1])
            if Path(value).exists() and not Path(value).is_dir():
                files.append(value)         # a file, a device, a FIFO: written in place
            else:
                folders.append(target[0])
        elif opt.role == "output":
            (folders if opt.kind == "folder" else files).append(value)
    if command == "optimize" and params.get("export_fields"):
        from ..fields import check_field_path, field_paths, pads_path

        check_field_path(params["export_fields"])
        states = field_paths(params["export_fields"], ["sigma_star", "sigma_L"])
        files += states + [pads_path(f) for f in states if f.suffix.lower() != ".pvd"]
    check_outputs(files, folders, inputs)


_PROGRESS = {"plan": ("plan", "step"), "check": ("release landscape", "placements")}


def run_report(command: str, part: str, params: dict) -> int:
    """Run ``command`` through :func:`deformclosure.reports.run`, print its summary
    (stdout) and warnings (stderr), write its outputs; the JSON to stdout for ``-o -``."""
    import click

    from ..outputs import json_text
    from ..reports import run

    _check_outputs(command, part, params)
    from ..log import compile_notice

    desc, unit = _PROGRESS.get(command, (command, "step"))
    progress, close, say = lazy_progress(bool(params.get("quiet")), desc, unit)
    quiet = bool(params.get("quiet")) or VERBOSITY.get() == 0
    try:
        with compile_notice(say):
            rep = run(command, part, params, progress=progress,
                      notify=None if quiet else (lambda s: click.echo(s, err=True)))
    finally:
        close()
    for w in rep.warnings:
        click.echo(f"warning: {w}", err=True)
    for line in rep.lines:
        click.echo(line)
    shown = len(rep.warnings)
    if params.get("output") == "-":
        import sys

        print(json_text(rep.data), file=REPORT_STDOUT or sys.stdout, flush=True)
    for path in rep.save():
        click.echo(f"wrote {path}")
    for w in rep.warnings[shown:]:
        click.echo(f"warning: {w}", err=True)
    return 0


def lazy_progress(quiet: bool, desc: str, unit: str):
    """A ``progress(done, total)`` callback whose bar appears at the first call (so input
    errors print no bar), a ``close()`` for it, and ``say(text)``: a line on standard
    error that does not break the bar (nothing when quiet).

    The bar is :func:`deformclosure.log.progress_bar`'s: tqdm on a terminal, plain lines
    without carriage returns when standard error is a file or a pipe.
    """
    import sys

    state: dict[str, Any] = {"bar": None}
    quiet = quiet or VERBOSITY.get() == 0

    def progress(done: int, total: int | None) -> None:
        if quiet:
            return
        if state["bar"] is None:
            from ..log import progress_bar

            state["bar"] = progress_bar(total, desc, unit, file=sys.stderr, leave=False)
        state["bar"].update(done - state["bar"].n)

    def close() -> None:
        if state["bar"] is not None:
            state["bar"].close()

    def say(text: str) -> None:
        if quiet:
            return
        if state["bar"] is not None:
            state["bar"].write(text, file=sys.stderr)
        else:
            print(text, file=sys.stderr, flush=True)

    return progress, close, say


def with_verbosity(command, keep_stdout: bool = False):
    """Give ``command`` the ``--quiet`` and ``--verbose`` options every command has.

    ``--quiet``: no progress bars and no human-readable lines on standard output (the
    report of ``-o -``, errors and warnings still appear). ``--verbose``: also log each
    main step of the library with its time on standard error. A command that already
    declares ``--quiet`` receives the flag itself as well. ``keep_stdout``: standard output
    is the command's product (``results``), kept under ``--quiet``.
    """
    import functools

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
            from ..errors import DeformClosureError

            raise DeformClosureError("--quiet/--verbose: give at most one of them")
        with _verbosity(quiet, verbose, keep_stdout):
            return callback(*args, **kwargs)

    command.callback = run
    return command


class _verbosity:
    """Set :data:`VERBOSITY`; under ``--verbose`` log steps on stderr; under ``--quiet``
    send standard output to the null device (the report of ``-o -`` keeps the real one)."""

    def __init__(self, quiet: bool, verbose: bool, keep_stdout: bool):
        self.quiet, self.verbose, self.keep = quiet, verbose, keep_stdout

    def __enter__(self):
        import os
        import sys

        global REPORT_STDOUT
        self.token = VERBOSITY.set(0 if self.quiet else 2 if self.verbose else 1)
        self.handler = None
        if self.verbose:
            from ..log import show_steps

            self.handler = show_steps(sys.stderr)
        self.saved = (sys.stdout, REPORT_STDOUT)
        self.silenced = self.quiet and not self.keep
        if self.silenced:
            REPORT_STDOUT = REPORT_STDOUT or sys.stdout
            sys.stdout = open(os.devnull, "w", encoding="utf-8")
        return self

    def __exit__(self, *exc) -> None:
        import sys

        global REPORT_STDOUT
        if self.silenced:
            sys.stdout.close()
            sys.stdout, REPORT_STDOUT = self.saved
        if self.handler is not None:
            from ..log import logger

            logger.removeHandler(self.handler)
        VERBOSITY.reset(self.token)
