"""``deformclosure results results.sqlite [--format csv|json]``: list or export a batch."""

from __future__ import annotations

import click

__all__ = ["command"]

EPILOG = """\b
Examples (after "deformclosure batch examples/drawings/ -o drawings.sqlite --command mesh"):
  deformclosure results drawings.sqlite
  deformclosure results drawings.sqlite --status failed
  deformclosure results drawings.sqlite --format csv -o drawings.csv
  deformclosure results drawings.sqlite --format json -o drawings.json

\b
The table and CSV show the key figures of each report in SI units; CSV columns carry
their unit (sigma_star_m, quality_J, seconds_s, jaw_a_x_m, ...), times are ISO 8601
UTC (started_utc, finished_utc). The JSON export holds every row with its full report.
A stored row that cannot be read (not JSON, NaN, too deep, not UTF-8) is listed with
status "unreadable" and a warning on stderr.
"""

#: Most warnings printed for unreadable rows.
MAX_WARNINGS = 20


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
    from ..batch import format_results, read_results

    check_outputs([output], [], [db])
    rows = read_results(db, status=status)
    bad = [r for r in rows if r["status"] == "unreadable"]
    for r in bad[:MAX_WARNINGS]:
        who = f"row {r['key'][:16] or '(no key)'}" + (f" ({r['part'][:80]})" if r["part"] else "")
        click.echo(f"warning: {db}: {who} is unreadable: {r['error']}", err=True)
    if len(bad) > MAX_WARNINGS:
        click.echo(f"warning: {db}: ... and {len(bad) - MAX_WARNINGS} more unreadable rows",
                   err=True)
    text = format_results(rows, fmt)
    if output is None or output == "-":
        from . import common

        # with -o - the CLI routes human text to stderr; the table is the product
        click.echo(text.rstrip("\n"), file=common.REPORT_STDOUT if output == "-" else None)
        return 0
    try:
        with atomic_path(output, "results") as tmp, \
                open(tmp, "w", encoding="utf-8", newline="") as fh:
            fh.write(text if text.endswith("\n") else text + "\n")
    except OSError as err:
        raise BatchError(f"{output}: cannot write ({err.strerror})") from None
    return 0
