"""Command-line interface ``deformclosure`` (SPEC §5).

Every subcommand is a thin call into the library and writes a JSON report with ``-o``.
User errors print one line ``error: ...`` on stderr and exit with code 2.
"""

from __future__ import annotations

import sys

import click

from ..errors import DeformClosureError

__all__ = ["cli", "main", "run"]

EPILOG = """\b
Examples:
  deformclosure demo
  deformclosure mesh examples/rectangle.json -o mesh.json --plot mesh.png
  deformclosure import examples/drawings/gasket.dxf --material examples/rectangle.json -o part.json
  deformclosure optimize examples/rectangle.json --at 0,10 12,10 -o report.json --plot out/
  deformclosure check examples/l_shape.json --fingers examples/fingers/l_shape.json
  deformclosure plan examples/rectangle.json --top 10 -o plan.json --plot plan/
  deformclosure batch examples/ -o results.sqlite
"""


@click.group(epilog=EPILOG, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="deformclosure", prog_name="deformclosure")
def cli() -> None:
    """How well do rigid jaws or fingers hold a deformable planar part?

    D-space, deform closure and optimal two-jaw grasps (Gopalakrishnan & Goldberg,
    IJRR 2005). Lengths in JSON reports are in metres, energies in joules.
    """


def _register() -> None:
    from . import batch, check, demo, import_cmd, mesh_cmd, optimize, plan, results, slice

    from .common import with_verbosity

    for name, module in (("demo", demo), ("import", import_cmd), ("mesh", mesh_cmd),
                         ("check", check), ("slice", slice), ("optimize", optimize),
                         ("plan", plan), ("batch", batch), ("results", results)):
        # `results` prints its table on stdout as its product: --quiet keeps it.
        cli.add_command(with_verbosity(module.command, keep_stdout=name == "results"), name)


_register()


def _report_to_stdout(argv: list[str]) -> bool:
    """Whether the command line asks for the JSON report on stdout (``-o -``)."""
    return any((a in ("-o", "--output") and i + 1 < len(argv) and argv[i + 1] == "-")
               or a in ("-o-", "--output=-") for i, a in enumerate(argv))


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the exit code (0 ok, 2 bad input).

    With ``-o -`` the report is the only thing on standard output; all human-readable text
    goes to standard error.
    """
    from . import common

    args = list(sys.argv[1:] if argv is None else argv)
    real_stdout = sys.stdout
    if _report_to_stdout(args):
        common.REPORT_STDOUT, sys.stdout = real_stdout, sys.stderr
    try:
        return _main(args)
    finally:
        sys.stdout, common.REPORT_STDOUT = real_stdout, None


def _main(argv: list[str]) -> int:
    try:
        rv = cli.main(args=argv, prog_name="deformclosure", standalone_mode=False)
    except DeformClosureError as err:
        click.echo(f"error: {err}", err=True)
        return 2
    except click.exceptions.Abort:
        click.echo("aborted", err=True)
        return 130
    except click.UsageError as err:
        if type(err).__name__ == "NoArgsIsHelpError" and err.ctx is not None:
            click.echo(err.ctx.get_help())  # bare `deformclosure`: show the help
            return 0
        # one line, like every other input error
        where = err.ctx.command_path if err.ctx is not None else "deformclosure"
        click.echo(f"error: {err.format_message()} (see '{where} --help')", err=True)
        return 2
    except click.ClickException as err:
        click.echo(f"error: {err.format_message()}", err=True)
        return err.exit_code
    except click.exceptions.Exit as err:
        return err.exit_code
    except KeyboardInterrupt:
        click.echo("interrupted", err=True)
        return 130
    return rv if isinstance(rv, int) else 0


def run() -> None:  # pragma: no cover - console-script entry point
    """Console-script entry point."""
    sys.exit(main())
