"""``deformclosure results results.sqlite [--format csv|json]``: list or export a batch."""

from __future__ import annotations

import click

__all__ = ["command"]

EPILOG = """\b
Examples:
  deformclosure results results.sqlite
  deformclosure results results.sqlite --status failed
  deformclosure results results.sqlite --format csv -o results.csv
  deformclosure results results.sqlite --format json -o results.json

\b
The table and CSV show the key figures of each report (SI units: m, J); the JSON
export holds every row with its full report.
"""


@click.command(epilog=EPILOG)
@click.argument("db", type=click.Path(dir_okay=False))
@click.option("--format", "fmt", type=click.Choice(["table", "csv", "json"]), default="table",
              show_default=True, help="Output format.")
@click.option("--status", type=click.Choice(["ok", "failed"]), default=None,
              help="Only jobs with this status.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
              help="Write to this file instead of stdout.")
def command(db, fmt, status, output) -> int:
    """List a batch's results, or export them as CSV or JSON."""
    from ..errors import BatchError
    from ..outputs import atomic_path, check_outputs
    from ..planning.batch import format_results, read_results

    check_outputs([output], [], [db])
    text = format_results(read_results(db, status=status), fmt)
    if output is None or output == "-":
        click.echo(text.rstrip("\n"))
        return 0
    try:
        with atomic_path(output) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(text if text.endswith("\n") else text + "\n")
    except OSError as err:
        raise BatchError(f"{output}: cannot write ({err.strerror})") from None
    return 0
