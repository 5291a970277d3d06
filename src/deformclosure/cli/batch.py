"""``deformclosure batch JOBS -o results.sqlite``: many jobs, resumable results (SPEC §5)."""

from __future__ import annotations

import click

__all__ = ["command"]

EPILOG = """\b
Examples (from the repository root):
  deformclosure batch examples/drawings/ -o drawings.sqlite --command mesh
  deformclosure batch examples/ -o results.sqlite --options "--top 5" --workers 2
  deformclosure results drawings.sqlite --format csv -o drawings.csv

\b
JOBS is a folder (one job per part or mesh file, running --command with --options)
or a job list: JSON [{"part": "a.json", "command": "optimize", "options": ["--at",
"0,10", "12,10"]}, ...] or CSV with the header part,command,options (options one
shell-quoted string); paths relative to the list file, and inside its folder
(--allow-outside lifts this for a list you trust). A field holds at most 4096
characters and no NUL. A drawing's material file <name>.material.json travels with the
drawing <name>.dxf (or .svg) and is no job of its own. Your own lists and clusters:
"deformclosure batch jobs.json -o results.sqlite", "... --scheduler tcp://HOST:8786".
\b
Each finished job is committed at once; run the same command again to resume: jobs
already in the results file are skipped (--retry-failed runs failed ones again).
Ctrl-C stops the workers and keeps every finished job. A results file remembers its
job list: another list is refused unless --append. A file that is not a deformclosure
results file is refused and left unchanged.
\b
Dask: the scheduler and its workers must be trusted (jobs and results travel pickled;
tcp:// is neither encrypted nor authenticated); use tls:// with the Dask TLS settings
(docs/batch.md).
Exit code: 0 if every job is ok, 1 if some failed, 2 for bad batch input, 130 if
interrupted.
"""


@click.command(epilog=EPILOG)
@click.argument("jobs", type=click.Path())
@click.option("-o", "--output", "db", required=True, type=click.Path(dir_okay=False),
              help="SQLite results file (created, or resumed if it exists).")
@click.option("--command", "job_command", default="plan", show_default=True,
              help="Command run on each file of a folder (and on list entries naming none).")
@click.option("--options", "job_options", default="", metavar="'OPTS'",
              help="Options of that command, one shell-quoted string (--options '--top 5').")
@click.option("--scheduler", default="processes", show_default=True,
              help="processes (local pool), inline (this process; debugging) or a Dask "
                   "scheduler address tcp://HOST:PORT (tls://HOST:PORT with the Dask TLS "
                   "configuration); trusted schedulers only.")
@click.option("--workers", type=int, default=None,
              help="Local worker processes (default: CPUs); with Dask, the most jobs in flight.")
@click.option("--retry-failed", is_flag=True, help="Run failed jobs again.")
@click.option("--append", is_flag=True,
              help="Add this batch to a results file made for another job list "
                   "(refused otherwise, so two catalogues never mix by mistake).")
@click.option("--allow-outside", is_flag=True,
              help="Let a job list name files outside its own folder (../ or absolute "
                   "paths, symbolic links leaving it); only for lists you trust.")
@click.option("--quiet", is_flag=True, help="No progress bar and no summary.")
def command(jobs, db, job_command, job_options, scheduler, workers, retry_failed, append,
            allow_outside, quiet) -> int:
    """Run a command on many part files, resumably.

    One row per job in an SQLite results file, committed as each job finishes.
    """
    from ..batch import BatchInterrupted, load_jobs, run_batch

    job_list = load_jobs(jobs, command=job_command, options=job_options,
                         allow_outside=allow_outside)
    try:
        s = run_batch(job_list, db, scheduler=scheduler, workers=workers,
                      retry_failed=retry_failed, progress=not quiet, append=append)
    except BatchInterrupted as err:
        click.echo(str(err), err=True)
        return 130
    except KeyboardInterrupt:
        click.echo(f"interrupted; the jobs finished are kept in {db}; run the same command "
                   "to resume", err=True)
        return 130
    if not quiet:
        extra = f" ({s.n_duplicates} duplicate entries)" if s.n_duplicates else ""
        click.echo(f"{s.n_jobs} jobs{extra}: {s.n_run} run, {s.n_skipped} already done; "
                   f"{s.n_ok} ok, {s.n_failed} failed -> {db} ({s.seconds:.1f} s)")
        for f in s.failures[:20]:
            click.echo(f"failed: {f['part']} ({f['command']}): {f['error']}")
        if len(s.failures) > 20:
            click.echo(f"... and {len(s.failures) - 20} more: deformclosure results {db}")
    return s.exit_code
