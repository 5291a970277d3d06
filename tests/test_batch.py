"""Batch runs (SPEC §5 "Batch"): job lists, keys, resumable SQLite results, Dask.

The runner is checked against itself: a Dask cluster must give the same rows as the
local pool, and a run killed with SIGKILL and started again must give the same rows as
an uninterrupted run (timings aside), every job exactly once.
"""

from __future__ import annotations

import csv
import io
import json
import multiprocessing
import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

import deformclosure
from deformclosure import reports
from deformclosure.batch import (Job, format_results, job_key, load_jobs, read_results,
                                 result_summary, run_batch)
from deformclosure.cli.main import main
from deformclosure.errors import BatchError

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
CORRUPT = Path(__file__).resolve().parent / "bad_inputs" / "part_invalid_syntax.json"
TIMINGS = ("started", "finished", "seconds")


def _untimed(d):
    """``d`` without timing fields (the columns, and ``timings_s`` inside reports)."""
    if isinstance(d, dict):
        return {k: _untimed(v) for k, v in d.items() if k not in TIMINGS and k != "timings_s"}
    return d


def _rows(db) -> list[dict]:
    """Rows of a results file without the timing fields."""
    return [_untimed(r) for r in read_results(db)]


@pytest.fixture()
def parts(tmp_path) -> Path:
    """A catalogue: three example parts and a corrupt part file."""
    d = tmp_path / "parts"
    d.mkdir()
    for name in ("rectangle", "plate_with_hole", "l_shape"):
        shutil.copy(EXAMPLES / f"{name}.json", d / f"{name}.json")
    shutil.copy(CORRUPT, d / "corrupt.json")
    (d / "notes.txt").write_text("not a part")
    return d


def _write_list(path: Path, entries: list[dict]) -> Path:
    path.write_text(json.dumps(entries))
    return path


# ----------------------------------------------------------------------------- job lists


def test_folder_json_and_csv_lists_give_the_same_jobs(parts):
    folder = load_jobs(parts, command="mesh", options="--min-angle 25")
    assert [Path(j.part).name for j in folder] == ["corrupt.json", "l_shape.json",
                                                   "plate_with_hole.json", "rectangle.json"]
    assert all(j.command == "mesh" and j.options == ("--min-angle", "25") for j in folder)
    entries = [{"part": f"parts/{Path(j.part).name}", "command": "mesh",
                "options": ["--min-angle", "25"]} for j in folder]
    listed = load_jobs(_write_list(parts.parent / "jobs.json", entries))
    with open(parts.parent / "jobs.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["part", "command", "options"])
        for e in entries:
            w.writerow([e["part"], e["command"], "--min-angle 25"])
    csv_jobs = load_jobs(parts.parent / "jobs.csv")
    assert [j.key for j in folder] == [j.key for j in listed] == [j.key for j in csv_jobs]
    # An entry that names no command or options takes the defaults of load_jobs.
    (j,) = load_jobs(_write_list(parts.parent / "short.json", ["parts/rectangle.json"]),
                     command="optimize", options=["--at", "0,10", "12,10"])
    assert (j.command, j.options) == ("optimize", ("--at", "0,10", "12,10"))
    assert j.part == str(parts.parent / "parts" / "rectangle.json")


def test_key_follows_inputs_parsed_options_and_version(parts, tmp_path):
    rect = parts / "rectangle.json"
    base = Job.from_spec(rect, "optimize", ["--at", "0,10", "12,10"])
    same = [Job.from_spec(rect, "optimize", ["--method", "exact", "--at", "0,10", "12,10"]),
            Job.from_spec(rect, "optimize", "--at 0,10 12,10 --method=exact"),
            Job.from_spec(rect, "optimize", ["--at", "0,10", "12,10", "--plot", "out"]),
            # display options every command takes change nothing
            Job.from_spec(rect, "optimize", ["-q", "--at", "0,10", "12,10", "--verbose"]),
            Job.from_spec(rect, "optimize", ["--at", "0,10", "12,10", "--quiet"])]
    assert {j.key for j in same} == {base.key}
    copy = tmp_path / "renamed.json"
    shutil.copy(rect, copy)
    assert Job.from_spec(copy, "optimize", ["--at", "0,10", "12,10"]).key == base.key
    different = [Job.from_spec(rect, "optimize", ["--at", "0,8", "12,8"]),
                 Job.from_spec(rect, "optimize", ["--at", "0,10", "12,10", "--method", "paper"]),
                 Job.from_spec(rect, "mesh")]
    copy.write_text(rect.read_text().replace("0.1", "0.2"))
    different.append(Job.from_spec(copy, "optimize", ["--at", "0,10", "12,10"]))
    assert len({j.key for j in different} | {base.key}) == 5
    params = {"at": ["0,10", "12,10"]}
    assert job_key(base.digest, "optimize", params, "1.0") != job_key(base.digest, "optimize",
                                                                      params, "1.1")
    assert len(base.key) == 64


@pytest.mark.parametrize("make,match", [
    (lambda d: d / "missing", r"not found"),
    (lambda d: d / "empty", r"no part or mesh files"),
    (lambda d: d / "jobs.txt", r"must be \.json or \.csv"),
    (lambda d: _write_list(d / "j.json", {"part": "x"}), r"is a list"),
    (lambda d: (d / "j.json").write_text("[{") and d / "j.json", r"not valid JSON \(line 1"),
    (lambda d: _write_list(d / "j.json", [{"part": "parts/rectangle.json", "command": "fly"}]),
     r"job \[0\]: command 'fly': not a job command; choose one of .*optimize"),
    (lambda d: _write_list(d / "j.json", [{"part": "parts/rectangle.json", "command": "batch"}]),
     r"not a job command"),
    (lambda d: _write_list(d / "j.json", [{"part": "parts/nope.json"}]),
     r"job \[0\]: part 'parts/nope.json': file not found"),
    (lambda d: _write_list(d / "j.json", [{"part": "parts/rectangle.json", "command": "optimize",
                                          "options": ["--method", "magic"]}]),
     r"optimize --method magic: .*magic"),
    (lambda d: _write_list(d / "j.json", [{"part": "parts/rectangle.json", "command": "mesh",
                                          "options": ["-o", "x.json"]}]),
     r"-o is set by the batch runner"),
    (lambda d: _write_list(d / "j.json", [{"part": "parts/rectangle.json", "colour": "red"}]),
     r"unknown key 'colour'"),
    (lambda d: (d / "j.csv").write_text("file,cmd\na,b\n") and d / "j.csv",
     r"header part,command,options"),
    (lambda d: (d / "j.csv").write_text("part,command,options\nparts/rectangle.json,mesh,'--x\n")
     and d / "j.csv", r"line 2: options .*quotation"),
])
def test_bad_batch_input_is_one_error_line_and_exit_2(parts, make, match, capsys):
    (parts.parent / "empty").mkdir()
    (parts.parent / "jobs.txt").write_text("")
    jobs = make(parts.parent)
    with pytest.raises(BatchError, match=match):
        load_jobs(jobs)
    db = parts.parent / "r.sqlite"
    assert main(["batch", str(jobs), "-o", str(db), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ")
    assert not db.exists()


def test_bad_results_file_and_scheduler(parts, tmp_path, capsys):
    jobs = [Job.from_spec(parts / "rectangle.json", "mesh")]
    not_db = tmp_path / "not.sqlite"
    not_db.write_text("hello, I am text " * 100)
    with pytest.raises(BatchError, match="not a deformclosure results file"):
        run_batch(jobs, not_db, progress=False)
    with pytest.raises(BatchError, match="results file not found"):
        read_results(tmp_path / "none.sqlite")
    with pytest.raises(BatchError, match="choose 'processes', 'inline' or a Dask"):
        run_batch(jobs, tmp_path / "r.sqlite", scheduler="threads", progress=False)
    with pytest.raises(BatchError, match="must be a whole number >= 1"):
        run_batch(jobs, tmp_path / "r2.sqlite", workers=0, progress=False)
    with pytest.raises(BatchError, match="does not exist"):
        run_batch(jobs, tmp_path / "no" / "r.sqlite", progress=False)
    assert main(["results", str(tmp_path / "none.sqlite")]) == 2
    assert capsys.readouterr().err.startswith("error: ")


# ----------------------------------------------------------------------------- running


def test_failed_jobs_are_recorded_and_the_batch_goes_on(parts, capsys):
    db = parts.parent / "r.sqlite"
    code = main(["batch", str(parts), "-o", str(db), "--command", "mesh", "--workers", "2"])
    assert code == 1  # some failed
    out = capsys.readouterr().out
    assert "4 jobs: 4 run, 0 already done; 3 ok, 1 failed" in out
    rows = {Path(r["part"]).name: r for r in read_results(db)}
    assert set(rows) == {"corrupt.json", "l_shape.json", "plate_with_hole.json", "rectangle.json"}
    bad = rows.pop("corrupt.json")
    assert bad["status"] == "failed" and bad["result"] is None
    # The user's file is named in the message, not the worker's private copy.
    assert bad["error"].startswith(f"{parts / 'corrupt.json'}: not valid JSON")
    assert "\n" not in bad["error"] and "deformclosure-job-" not in bad["error"]
    for r in rows.values():
        assert r["status"] == "ok" and r["error"] is None
        assert r["version"] == deformclosure.__version__
        assert r["result"]["format"] == "deformclosure-mesh/1"
        assert r["seconds"] > 0 and r["finished"] >= r["started"]
    # The report equals the one the command writes by itself.
    ref = parts.parent / "mesh.json"
    assert main(["mesh", str(parts / "rectangle.json"), "-o", str(ref)]) == 0
    assert rows["rectangle.json"]["result"] == json.loads(ref.read_text())


def test_any_exception_is_recorded_with_its_type(parts, monkeypatch):
    def boom(command, part, params=None, **kwargs):
        if "plate" in part.name:
            raise ZeroDivisionError("no grip\non this part")
        return reports.Report(command, {"quality": 1.5, "sigma_star": None}, params=params)

    monkeypatch.setattr(reports, "run", boom)     # the inline worker runs in this process
    db = parts.parent / "r.sqlite"
    jobs = [Job.from_spec(parts / n, "mesh") for n in ("plate_with_hole.json", "rectangle.json")]
    s = run_batch(jobs, db, scheduler="inline", progress=False)
    assert (s.n_ok, s.n_failed, s.exit_code) == (1, 1, 1)
    assert s.failures[0]["error"] == "ZeroDivisionError: no grip on this part"
    rows = read_results(db)
    assert [r["status"] for r in rows] == ["failed", "ok"]
    assert rows[1]["result"] == {"quality": 1.5, "sigma_star": None}


def test_rerun_skips_finished_jobs_and_retry_failed_reruns_failed(parts):
    db = parts.parent / "r.sqlite"
    jobs = load_jobs(parts, command="mesh")
    first = run_batch(jobs, db, workers=2, progress=False)
    assert (first.n_run, first.n_ok, first.n_failed) == (4, 3, 1)
    before = read_results(db)
    again = run_batch(jobs + jobs[:2], db, workers=2, progress=False)
    assert (again.n_run, again.n_skipped, again.n_duplicates, again.exit_code) == (0, 4, 2, 1)
    assert read_results(db) == before  # nothing ran: timings are those of the first run
    retry = run_batch(jobs, db, workers=2, retry_failed=True, progress=False)
    assert (retry.n_run, retry.n_skipped, retry.n_failed) == (1, 3, 1)
    after = {r["part"]: r for r in read_results(db)}
    for r in before:
        same = r["status"] == "ok"
        assert (after[r["part"]]["finished"] == r["finished"]) == same
    assert _rows(db) == [_untimed(r) for r in before]


def test_a_job_that_kills_its_worker_fails_alone(parts, monkeypatch):
    """A worker process that dies takes the jobs in flight down; each runs again alone and
    only the culprit is recorded as failed. The culprit: a report function that ends its
    process on crash.json, patched here and inherited by workers forked from this process
    (``mp_context``)."""
    shutil.copy(parts / "rectangle.json", parts / "crash.json")
    (parts / "crash.json").write_text((parts / "crash.json").read_text() + " ")
    real = reports.run

    def crash_or_run(command, part, params=None, **kwargs):
        if Path(part.name).name == "crash.json":
            os._exit(3)
        return real(command, part, params, **kwargs)

    monkeypatch.setattr(reports, "run", crash_or_run)
    db = parts.parent / "r.sqlite"
    s = run_batch(load_jobs(parts, command="mesh"), db, workers=2, progress=False,
                  mp_context=multiprocessing.get_context("fork"))
    assert (s.n_run, s.n_ok, s.n_failed) == (5, 3, 2)
    rows = {Path(r["part"]).name: r for r in read_results(db)}
    assert {k: r["status"] for k, r in rows.items()} == {
        "corrupt.json": "failed", "crash.json": "failed", "l_shape.json": "ok",
        "plate_with_hole.json": "ok", "rectangle.json": "ok"}
    assert "worker process died" in rows["crash.json"]["error"]
    assert "not valid JSON" in rows["corrupt.json"]["error"]


# ----------------------------------------------------------------------------- dask, SIGKILL


def _optimize_jobs(tmp_path: Path, n: int) -> Path:
    """A job list of ``n`` distinct optimize jobs (~0.2 s each), a mesh job, a failing job."""
    for name in ("rectangle", "plate_with_hole"):
        shutil.copy(EXAMPLES / f"{name}.json", tmp_path / f"{name}.json")
    shutil.copy(CORRUPT, tmp_path / "corrupt.json")
    entries = []
    for i in range(n):
        y = 3 + (i // 2) * 1.5
        entries.append({"part": "rectangle.json", "command": "optimize",
                        "options": ["--model", "paper", "--at", f"0,{y:g}", f"12,{y:g}",
                                    *(["--method", "exact"], ["--method", "approx", "--eps", "1e-5"])[i % 2]]})
    entries += [{"part": "plate_with_hole.json", "command": "mesh"},
                {"part": "corrupt.json", "command": "optimize",
                 "options": ["--model", "paper", "--at", "0,1", "1,0"]}]
    return _write_list(tmp_path / "jobs.json", entries)


@pytest.mark.slow
def test_dask_local_cluster_gives_the_same_rows_as_the_local_pool(tmp_path):
    distributed = pytest.importorskip("distributed")
    jobs = load_jobs(_optimize_jobs(tmp_path, 4))
    pool = run_batch(jobs, tmp_path / "pool.sqlite", workers=2, progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        dask = run_batch(jobs, tmp_path / "dask.sqlite", scheduler=cluster.scheduler_address,
                         progress=False)
    assert (pool.n_ok, pool.n_failed) == (dask.n_ok, dask.n_failed) == (5, 1)
    assert _rows(tmp_path / "dask.sqlite") == _rows(tmp_path / "pool.sqlite")
    rows = read_results(tmp_path / "pool.sqlite")
    assert {r["command"] for r in rows if r["status"] == "ok"} == {"optimize", "mesh"}
    opt = [r for r in rows if r["command"] == "optimize" and r["status"] == "ok"]
    assert all(r["result"]["units"]["length"] == "m" and r["result"]["quality"] > 0 for r in opt)
    assert len(opt) == 4


def _group_alive(pgid: int) -> bool:
    """Whether a process of group ``pgid`` still runs (zombies waiting for a reaper don't)."""
    proc = Path("/proc")
    if not proc.is_dir():  # pragma: no cover - not Linux
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return False
        return True
    for stat in proc.glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:  # gone meanwhile
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            return True
    return False


@pytest.mark.slow
def test_sigkill_mid_batch_then_resume_equals_an_uninterrupted_run(tmp_path):
    jobs_file = _optimize_jobs(tmp_path, 8)
    n_jobs = len(load_jobs(jobs_file))
    ref = run_batch(jobs_file, tmp_path / "ref.sqlite", workers=2, progress=False)
    assert ref.n_jobs == n_jobs == 10
    db = tmp_path / "killed.sqlite"
    cmd = [sys.executable, "-m", "deformclosure", "batch", str(jobs_file), "-o", str(db),
           "--workers", "2", "--quiet"]
    with open(tmp_path / "log.txt", "w") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=log, start_new_session=True)
    group = proc.pid  # the batch leads its own process group: pool workers, fork server
    try:
        deadline, n_done = time.monotonic() + 60, 0
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                with sqlite3.connect(db) as conn:
                    n_done = conn.execute("SELECT COUNT(*) FROM jobs").fetchone()[0]
            except sqlite3.OperationalError:  # not created yet
                n_done = 0
            if n_done >= 1:
                break
            time.sleep(0.02)
        os.kill(proc.pid, signal.SIGKILL)  # as `kill -9 PID` does: the batch only
        proc.wait(10)
        # Its workers see it die and exit too: the whole group is gone in a few seconds.
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and _group_alive(group):
            time.sleep(0.1)
        assert not _group_alive(group), "worker processes outlived the killed batch"
    finally:
        if _group_alive(group):
            os.killpg(group, signal.SIGKILL)
    assert proc.returncode == -signal.SIGKILL, (tmp_path / "log.txt").read_text()
    survived = {r["key"]: r["finished"] for r in read_results(db)}
    assert 1 <= len(survived) < n_jobs  # killed mid-way
    rerun = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert rerun.returncode == 1, rerun.stderr  # the corrupt part failed, the rest is ok
    with sqlite3.connect(db) as conn:
        (count, distinct), = conn.execute("SELECT COUNT(*), COUNT(DISTINCT key) FROM jobs")
    assert count == distinct == n_jobs  # none lost, none duplicated
    assert _rows(db) == _rows(tmp_path / "ref.sqlite")
    # Jobs finished before the kill were not run again.
    assert {r["key"]: r["finished"] for r in read_results(db) if r["key"] in survived} == survived


# ----------------------------------------------------------------------------- results


def test_results_command_lists_and_exports(parts, capsys):
    db = parts.parent / "r.sqlite"
    run_batch(load_jobs(parts, command="mesh"), db, workers=2, progress=False)
    capsys.readouterr()
    assert main(["results", str(db)]) == 0
    table = capsys.readouterr().out
    assert "216 nodes, 382 triangles" in table and "error: " in table
    assert table.strip().endswith("4 jobs: 3 ok, 1 failed")
    assert main(["results", str(db), "--format", "csv", "--status", "ok"]) == 0
    got = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert [Path(r["part"]).name for r in got] == ["l_shape.json", "plate_with_hole.json",
                                                   "rectangle.json"]
    assert got[2]["n_nodes"] == "216" and got[2]["status"] == "ok" and "result" not in got[2]
    out = parts.parent / "all.json"
    assert main(["results", str(db), "--format", "json", "-o", str(out)]) == 0
    assert json.loads(out.read_text()) == read_results(db)


def test_result_summary_of_each_report_kind():
    assert result_summary(None) == {}
    assert result_summary({"sigma_star": 0.008, "quality": 1e-4, "U_A": None, "jaws": [1, 2]}) \
        == {"sigma_star": 0.008, "quality": 1e-4, "U_A": None}
    plan = {"pairs": [{"a": 3, "b": 9, "sigma_star": 0.01, "quality": 2e-4},
                      {"a": 1, "b": 2, "sigma_star": None, "quality": 0.0}]}
    assert result_summary(plan) == {"n_pairs": 2, "top_a": 3, "top_b": 9,
                                    "top_sigma_star": 0.01, "top_quality": 2e-4}
    row = {"part": "p.json", "command": "plan", "options": [], "status": "ok", "seconds": 1.0,
           "result": plan, "error": None}
    assert "best 3-9 sigma*=0.01 m Q=0.0002 J (2 pairs)" in format_results([row])
    assert format_results([]) == "no jobs"
    with pytest.raises(BatchError, match="choose 'table', 'csv' or 'json'"):
        format_results([row], "xml")


def test_pad_plan_summaries_take_only_verified_rows():
    """A screened row is a candidate (SPEC §6 "Plan"): batch summaries show the best
    *verified* axis and its verdict, and nothing when no row was verified."""
    from deformclosure.batch.results import result_summary

    screened = {"angle": 0.1, "point": [0.0, 0.0], "sigma_star": 0.01, "quality": 9e-4,
                "verified": False, "verdict": "candidate"}
    verified = {"angle": 1.5, "point": [0.01, 0.0], "sigma_star": 0.008, "quality": 2e-4,
                "verified": True, "verdict": "held"}
    s = result_summary({"model": "pads", "axes": [screened, verified]})
    assert s["top_quality"] == 2e-4 and s["top_verdict"] == "held" and s["top_angle"] == 1.5
    s = result_summary({"model": "pads", "axes": [screened]})
    assert "top_quality" not in s and s["n_axes"] == 1
