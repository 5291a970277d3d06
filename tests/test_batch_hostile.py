"""Batch and results against hostile inputs (issue 11): every failure is one line.

Job lists with NUL bytes or huge fields, dead or fake Dask schedulers, results files that
are someone else's database, made for another job list, corrupt or read-only, stored rows
that are not what we wrote, Ctrl-C, files that change under a running batch, paths that
leave the job list's folder, and the CSV export's units, times and coordinates.

Most tests run jobs with the ``inline`` scheduler and a tiny stand-in for the report
function (a few milliseconds a job); only Ctrl-C needs real worker processes.
"""

from __future__ import annotations

import csv
import gc
import io
import json
import os
import shutil
import signal
import socket
import sqlite3
import subprocess
import sys
import tempfile
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from deformclosure import batch, reports
from deformclosure.batch import (Job, cluster, format_results, load_jobs, read_results,
                                 run_batch, store)
from deformclosure.cli.main import main
from deformclosure.errors import BatchError
from deformclosure.jsonfile import Source

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


# ----------------------------------------------------------------------------- helpers


@pytest.fixture()
def parts(tmp_path) -> Path:
    """A folder with two example parts."""
    d = tmp_path / "parts"
    d.mkdir()
    for name in ("rectangle", "l_shape"):
        shutil.copy(EXAMPLES / f"{name}.json", d / f"{name}.json")
    return d


@pytest.fixture()
def note(monkeypatch, tmp_path):
    """A stand-in for the report function, as the inline worker calls it: logs each run
    in ``runs.log`` (the part's name, the type of the part and of ``--fingers``) and
    returns a small report (padded with ``--max-area`` characters); returns the log's
    path."""
    log = tmp_path / "runs.log"

    def note_run(command, part, params=None, **kwargs):
        fingers = (params or {}).get("fingers")
        with open(log, "a") as fh:
            fh.write(f"{Path(part.name).name} {type(part).__name__} {type(fingers).__name__}\n")
        size = int((params or {}).get("max_area") or 0)
        return reports.Report(command, {"quality": 1.5e-4, "sigma_star": 0.008,
                                        "pad": "x" * size}, params=params)

    monkeypatch.setattr(reports, "run", note_run)
    return log


def _jobs(parts: Path, *names: str, options=()) -> list[Job]:
    return [Job.from_spec(parts / f"{n}.json", "mesh", list(options)) for n in names]


def _one_error_line(capsys) -> str:
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and err[0].startswith("error: "), err
    assert "Traceback" not in err[0]
    return err[0]


def _snapshot(folder: Path) -> dict:
    """Every file of ``folder`` with its bytes."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@contextmanager
def _read_only(path: Path):
    """Make ``path`` unwritable even for root (``chattr +i``), else by its mode."""
    if os.geteuid() == 0:
        if shutil.which("chattr") is None:
            pytest.skip("running as root without chattr: cannot make a file read-only")
        r = subprocess.run(["chattr", "+i", str(path)], capture_output=True)
        if r.returncode != 0:
            pytest.skip(f"chattr +i not supported here: {r.stderr.decode().strip()}")
        try:
            yield
        finally:
            subprocess.run(["chattr", "-i", str(path)], check=True)
    else:
        mode = path.stat().st_mode
        path.chmod(mode & ~0o222)
        try:
            yield
        finally:
            path.chmod(mode)


# ----------------------------------------------------------------------------- 1. fields


def _csv(d: Path, text: str) -> Path:
    (d / "jobs.csv").write_text(text, encoding="utf-8")
    return d / "jobs.csv"


def _json(d: Path, text: str) -> Path:
    (d / "jobs.json").write_text(text, encoding="utf-8")
    return d / "jobs.json"


@pytest.mark.parametrize("make,match", [
    (lambda d: _csv(d, "part,command,options\nparts/rectangle.json,mesh,--min-angle\x0025\n"),
     r"jobs\.csv: line 2: 'options': contains a NUL character"),
    (lambda d: _csv(d, "part,command,options\nparts/rectangle.json,mesh," + "x" * 131_100 + "\n"),
     r"jobs\.csv: line 2: 'options': more than the 4096 characters"),
    (lambda d: _csv(d, "part,command,options\nparts/rectangle.json,mesh,\"--at\n" + "y" * 140_000 + "\"\n"),
     r"jobs\.csv: line 2: 'options': more than the 4096 characters"),
    (lambda d: _csv(d, "part,command,options\n" + "p" * 5000 + ".json,mesh,\n"),
     r"jobs\.csv: line 2: 'part': 5005 characters, more than the 4096"),
    (lambda d: _csv(d, "part,comm\x00and,options\n"),
     r"jobs\.csv: line 1: column 2: contains a NUL character"),
    (lambda d: _csv(d, "part,command,options\nparts/rectangle.json,optimize,--at 0,10 12,10\n"),
     r"jobs\.csv: line 2: 5 cells but the header has 3; quote"),
    (lambda d: _json(d, '[{"part": "parts/rectangle.json"}, {"part": "parts/rect\\u0000.json"}]'),
     r"jobs\.json: job \[1\]: part: contains a NUL character"),
    (lambda d: _json(d, '[{"part": "parts/rectangle.json", "options": ["--top", "1\x002"]}]'),
     r"jobs\.json: job \[0\]: options\[1\]: contains a NUL character"),
    (lambda d: _json(d, '[{"part": "parts/rectangle.json"},\x00 "x"]'),
     r"jobs\.json: line 1 column 35: a NUL byte"),
    (lambda d: _json(d, json.dumps([{"part": "parts/rectangle.json", "command": "c" * 200_000}])),
     r"jobs\.json: job \[0\]: command: 200000 characters, more than the 4096"),
])
def test_nul_and_huge_fields_name_file_row_and_field(parts, make, match, capsys):
    jobs = make(parts.parent)
    with pytest.raises(BatchError, match=match) as err:
        load_jobs(jobs)
    assert "\n" not in str(err.value) and len(str(err.value)) < 400
    db = parts.parent / "r.sqlite"
    assert main(["batch", str(jobs), "-o", str(db), "--quiet"]) == 2
    assert len(_one_error_line(capsys)) < 400
    assert not db.exists()


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("fuzz")
    shutil.copy(EXAMPLES / "rectangle.json", d / "rectangle.json")
    return d


_CELLS = st.sampled_from(["rectangle.json", "mesh", "plan", "--top 2", "--top", "\x00", "",
                          '"', ",", "\n", "../rectangle.json", "/etc/passwd", "-o x",
                          "--fingers", "x" * 5000, "\ud7ff", "'"]) | st.text(max_size=20)
_PARTS = st.sampled_from(["rectangle.json", "./rectangle.json", "p" * 5000, "q" * 300,
                          "rect\x00angle.json", "../rectangle.json", "/etc/passwd", "/dev/zero",
                          ".", "missing.json"])
_COMMANDS = st.sampled_from(["", "mesh", "plan", "check", "demo", "x" * 5000, "\x00"])
_OPTIONS = st.sampled_from(["", "--top 2", "--max-area 0.5", "--plot " + "d/" * 2100, "'",
                            "--fingers rectangle.json", "-o x", "--top \x00"])
_ROW = st.one_of(st.tuples(_PARTS, _COMMANDS, _OPTIONS).map(list),
                 st.lists(_CELLS, max_size=4))
_CSV_TEXT = st.lists(_ROW, max_size=4).map(
    lambda rows: "part,command,options\n" + "\n".join(",".join(r) for r in rows))
_JSON_LIST = st.lists(st.tuples(_PARTS, _COMMANDS, _OPTIONS).map(
    lambda t: {"part": t[0], "command": t[1] or None, "options": t[2].split(" ")}),
    min_size=1, max_size=3).map(json.dumps)
_JSON_VALUE = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | _CELLS,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(
        st.sampled_from(["part", "command", "options", "x"]), inner, max_size=4),
    max_leaves=12)


@settings(max_examples=200, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(data=st.one_of(
    st.tuples(st.sampled_from(["csv", "json"]),
              st.one_of(st.binary(max_size=200).map(lambda b: b.decode("latin-1")),
                        _JSON_VALUE.map(json.dumps),
                        st.lists(_JSON_VALUE, max_size=3).map(json.dumps))),
    st.tuples(st.just("csv"), _CSV_TEXT),
    st.tuples(st.just("json"), _JSON_LIST)))
def test_fuzz_job_list_reader_gives_jobs_or_a_batch_error(fuzz_dir, data):
    """Random bytes, CSV or JSON as a job list: a list of jobs or a BatchError."""
    kind, text = data
    f = fuzz_dir / f"jobs.{kind}"
    f.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        jobs = load_jobs(f)
    except BatchError as err:
        assert "\n" not in str(err)
    else:
        assert jobs and all(isinstance(j, Job) for j in jobs)


# ----------------------------------------------------------------------------- 2. scheduler


def _closed_port() -> int:
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


@contextmanager
def _server(reply: bytes | None):
    """A TCP server on localhost that never answers (``None``) or sends ``reply``."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen()
    conns = []

    def serve():
        while True:
            try:
                c, _ = srv.accept()
            except OSError:
                return
            conns.append(c)
            if reply is not None:
                try:
                    c.sendall(reply)
                except OSError:
                    pass

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    finally:
        srv.close()
        for c in conns:
            c.close()


def test_a_scheduler_that_cannot_be_used_fails_fast_before_the_results_file(
        parts, note, monkeypatch, capsys):
    pytest.importorskip("distributed")
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 1.0)
    jobs = _jobs(parts, "rectangle")
    db = parts.parent / "r.sqlite"
    cases = [(f"tcp://127.0.0.1:{_closed_port()}", r"no answer within 1 s|cannot connect"),
             ("foo://host:1", r"not a usable scheduler address .*unknown address scheme"),
             ("tcp://host", r"not a usable scheduler address .*missing port"),
             ("tcp://host:notaport", r"not a usable scheduler address")]
    with _server(None) as silent, _server(b"HTTP/1.0 400 Bad\r\n\r\n" * 20) as web:
        cases += [(silent, r"no answer within 1 s"), (web, r"not a Dask scheduler")]
        for address, match in cases:
            t0 = time.monotonic()
            with pytest.raises(BatchError, match=match) as err:
                run_batch(jobs, db, scheduler=address, progress=False)
            assert time.monotonic() - t0 < 8, address
            assert str(err.value).startswith(f"--scheduler {address}: ")
            assert not db.exists()
        capsys.readouterr()
        assert main(["batch", str(parts), "-o", str(db), "--quiet", "--command", "mesh",
                     "--scheduler", silent]) == 2
    gc.collect()   # a half-made Dask client would print its traceback when collected
    assert "no answer within" in _one_error_line(capsys)
    assert not db.exists() and not note.exists()


# ----------------------------------------------------------------------------- 3. foreign files


def _foreign_dbs(d: Path) -> list[Path]:
    out = []
    a = d / "people.sqlite"                      # someone's database, rollback journal
    with sqlite3.connect(a) as c:
        c.execute("CREATE TABLE people (name TEXT, age INTEGER)")
        c.execute("INSERT INTO people VALUES ('ada', 36)")
    out.append(a)
    b = d / "wal.sqlite"                         # in WAL mode, with a `jobs` table of its own
    c = sqlite3.connect(b)
    c.execute("PRAGMA journal_mode=WAL")
    with c:
        c.execute("CREATE TABLE jobs (id INTEGER, what TEXT)")
    c.close()
    out.append(b)
    e = d / "app.sqlite"                         # another application's id, our tables
    with sqlite3.connect(e) as c:
        c.execute("PRAGMA application_id = 1234")
        c.execute(batch.SCHEMA)
    out.append(e)
    t = d / "notes.sqlite"
    t.write_text("SQLite format 3 is what this text says, but it is text\n" * 5)
    out.append(t)
    return out


def test_a_file_that_is_not_ours_is_refused_and_left_unchanged(parts, note, capsys):
    d = parts.parent / "dbs"
    d.mkdir()
    for db in _foreign_dbs(d):
        before = _snapshot(d)
        with pytest.raises(BatchError, match=r"not a deformclosure results file .*left unchanged"):
            run_batch(_jobs(parts, "rectangle"), db, scheduler="inline", progress=False)
        with pytest.raises(BatchError, match=r"not a deformclosure results file"):
            read_results(db)
        assert main(["batch", str(parts), "-o", str(db), "--command", "mesh", "--quiet"]) == 2
        assert "not a deformclosure results file" in _one_error_line(capsys)
        assert main(["results", str(db)]) == 2
        _one_error_line(capsys)
        assert _snapshot(d) == before, db.name        # same files, same bytes
    assert not note.exists()


def test_a_results_file_of_the_earlier_layout_is_resumed(parts, note):
    db = parts.parent / "old.sqlite"
    jobs = _jobs(parts, "rectangle", "l_shape")
    c = sqlite3.connect(db)                       # as the earlier version made it
    c.execute("PRAGMA journal_mode=WAL")
    with c:
        c.execute(batch.SCHEMA)
        c.execute("INSERT INTO jobs VALUES (?, 'old.json', 'note', '[]', 'ok', '{}', NULL, "
                  "1.0, 2.0, 1.0, '0.0.1')", (jobs[0].key,))
    c.close()
    s = run_batch(jobs, db, scheduler="inline", progress=False)
    assert (s.n_run, s.n_skipped, s.n_ok) == (1, 1, 2)
    with sqlite3.connect(db) as c:
        assert c.execute("PRAGMA application_id").fetchone()[0] == batch.APPLICATION_ID
    assert {r["key"]: r["part"] for r in read_results(db)}[jobs[0].key] == "old.json"


# ----------------------------------------------------------------------------- 4. job lists


def test_a_results_file_refuses_another_job_list_unless_append(parts, note, capsys):
    db = parts.parent / "r.sqlite"
    a, b = _jobs(parts, "rectangle"), _jobs(parts, "l_shape")
    run_batch(a, db, scheduler="inline", progress=False)
    rows = read_results(db)
    with pytest.raises(BatchError, match=r"made for another job list \(1 job in it, 0 of them "
                                         r"in this batch\); pass --append"):
        run_batch(b, db, scheduler="inline", progress=False)
    assert read_results(db) == rows and note.read_text().count("\n") == 1
    # The same list again (with --retry-failed, or in another order) resumes.
    assert run_batch(a + a, db, scheduler="inline", retry_failed=True, progress=False).n_run == 0
    s = run_batch(b, db, scheduler="inline", progress=False, append=True)
    assert (s.n_run, s.n_ok) == (1, 1)
    # Both lists are now known to the file.
    assert run_batch(a, db, scheduler="inline", progress=False).n_run == 0
    assert run_batch(b, db, scheduler="inline", progress=False).n_run == 0
    # From the command line: the same refusal, and --append in --help.
    (parts / "ring.json").write_bytes((EXAMPLES / "ring.json").read_bytes())
    capsys.readouterr()
    assert main(["batch", str(parts), "-o", str(db), "--command", "mesh", "--quiet"]) == 2
    assert "--append" in _one_error_line(capsys)
    assert main(["batch", "--help"]) == 0
    assert "--append" in capsys.readouterr().out


# ----------------------------------------------------------------------------- 5. corruption


def _garble(db: Path, offsets) -> None:
    data = bytearray(db.read_bytes())
    for start, n in offsets:
        data[start:start + n] = bytes((0xA5 + i) % 256 for i in range(n))
    db.write_bytes(bytes(data))


@pytest.mark.parametrize("where", ["pages", "root"])
def test_a_corrupt_results_file_is_one_line(parts, note, where, capsys):
    db = parts.parent / "r.sqlite"
    jobs = _jobs(parts, "rectangle", "l_shape", options=["--max-area", "20000"])
    run_batch(jobs, db, scheduler="inline", progress=False)
    size = db.stat().st_size
    assert size > 8 * 4096 and not Path(f"{db}-wal").exists()
    if where == "pages":     # every page's b-tree header, not the first page
        _garble(db, [(i, 12) for i in range(4096, size, 4096)])
    else:                    # the schema's root page, after the 100-byte file header
        _garble(db, [(100, 400)])
    with pytest.raises(BatchError, match=rf"results file {db} is corrupt: .*; delete it or "
                                         r"give another -o"):
        run_batch(jobs, db, scheduler="inline", progress=False, retry_failed=True)
    with pytest.raises(BatchError, match=r"is corrupt"):
        read_results(db)
    capsys.readouterr()
    assert main(["batch", str(parts), "-o", str(db), "--command", "mesh", "--quiet"]) == 2
    assert "is corrupt" in _one_error_line(capsys)
    assert main(["results", str(db), "--format", "csv"]) == 2
    assert "is corrupt" in _one_error_line(capsys)
    assert note.read_text().count("\n") == 2      # only the first run's jobs ever ran


# ----------------------------------------------------------------------------- 6. read-only


@pytest.mark.parametrize("what", ["file", "folder", "new file in folder"])
def test_a_read_only_results_file_or_folder_fails_before_any_job(parts, note, what, capsys):
    folder = parts.parent / "out"
    folder.mkdir()
    db = folder / "r.sqlite"
    if what != "new file in folder":
        run_batch(_jobs(parts, "rectangle"), db, scheduler="inline", progress=False)
    before = _snapshot(folder)
    n_runs = note.read_text().count("\n") if note.exists() else 0
    jobs = _jobs(parts, "rectangle", "l_shape")
    with _read_only(db if what == "file" else folder):
        with pytest.raises(BatchError, match=r"results file .*(not writable|cannot write)"):
            run_batch(jobs, db, scheduler="inline", progress=False, append=True)
        assert main(["batch", str(parts), "-o", str(db), "--command", "mesh", "--quiet",
                     "--append"]) == 2
        _one_error_line(capsys)
    assert (note.read_text().count("\n") if note.exists() else 0) == n_runs   # no job ran
    assert _snapshot(folder) == before


def test_the_write_check_itself_catches_what_access_does_not_see(parts, note, monkeypatch):
    db = parts.parent / "r.sqlite"
    run_batch(_jobs(parts, "rectangle"), db, scheduler="inline", progress=False)
    real_connect = sqlite3.connect

    def read_only_connect(path, *args, **kwargs):   # a file SQLite may only read
        if str(path) == str(db):
            return real_connect(Path(db).resolve().as_uri() + "?mode=ro", uri=True)
        return real_connect(path, *args, **kwargs)

    monkeypatch.setattr(store.sqlite3, "connect", read_only_connect)
    with pytest.raises(BatchError, match=r"results file .*: cannot write \(attempt to write a "
                                         r"readonly database\)"):
        run_batch(_jobs(parts, "rectangle", "l_shape"), db, scheduler="inline",
                  progress=False, append=True)
    assert note.read_text().count("\n") == 1


# ----------------------------------------------------------------------------- 7. stored rows


def test_results_reads_stored_rows_defensively(parts, note, capsys):
    db = parts.parent / "r.sqlite"
    run_batch(_jobs(parts, "rectangle"), db, scheduler="inline", progress=False)
    deep = "[" * 5000 + "]" * 5000
    bad = [("k1", "a.json", "not json", "ok", "{}", 1.0),
           ("k2", "b.json", "[]", "ok", '{"quality": NaN}', 1.0),
           ("k3", "c.json", "[]", "ok", deep, 1.0),
           ("k4", "d.json", "[]", "ok", "{}", "soon"),
           ("k5", "e.json", "[]", "ok", "{}", 1e999),
           ("k6", "f.json", '[1, {"a": 2}]', "ok", "[1, 2]", 1.0),
           ("k7", "g.json", "[]", "ok", '{"quality": 1, "quality": 2}', 1.0),
           ("k8", b"\xff\xfe.json", "[]", "ok", "{}", 1.0),
           # wrong types inside a readable report: shown as "-", not unreadable
           ("k9", "h.json", "[]", "ok", json.dumps({"pairs": [{"a": "x", "sigma_star": "y"}],
                                                   "axes": [{"angle": "z", "point": ["a", 1]}],
                                                   "verdict": 3}), 1.0)]
    with sqlite3.connect(db) as c:
        c.executemany("INSERT INTO jobs (key, part, command, options, status, result, seconds) "
                      "VALUES (?, ?, 'note', ?, ?, ?, ?)", bad)
    rows = {r["key"]: r for r in read_results(db)}
    assert {k for k, r in rows.items() if r["status"] == "unreadable"} == {
        f"k{i}" for i in range(1, 9)}
    assert "NaN or Infinity" in rows["k2"]["error"]
    assert "nested more than" in rows["k3"]["error"]
    assert "seconds is not a finite number" in rows["k4"]["error"]
    assert "appears twice" in rows["k7"]["error"]
    assert "part is not UTF-8" in rows["k8"]["error"]
    assert rows["k9"]["status"] == "ok"
    capsys.readouterr()
    for fmt in ("table", "csv", "json"):
        assert main(["results", str(db), "--format", fmt]) == 0
        out, err = capsys.readouterr()
        assert "Traceback" not in out + err
        warnings = [ln for ln in err.splitlines() if ln.strip()]
        assert len(warnings) == 8 and all(ln.startswith("warning: ") and "unreadable" in ln
                                          for ln in warnings)
        if fmt == "table":
            assert out.count("unreadable row: ") == 8
            assert out.strip().endswith("10 jobs: 2 ok, 0 failed, 8 unreadable")
        elif fmt == "json":
            assert len(json.loads(out)) == 10
        else:
            assert sum(r["status"] == "unreadable" for r in csv.DictReader(io.StringIO(out))) == 8


# ----------------------------------------------------------------------------- 8, 9. Ctrl-C


def _group_alive(pgid: int) -> bool:
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            return True
    return False


def _default_sigint() -> None:
    """In the child: Ctrl-C's default action, as from a terminal. A child inherits an
    ignored SIGINT, and a test process can have one (a worker initialiser run in-process
    ignores it): the batch then never saw the interrupt (exit 0, or a 60 s hang)."""
    signal.signal(signal.SIGINT, signal.default_int_handler)


def _slow_jobs(d: Path, n: int) -> Path:
    """``n`` (at most 99) distinct paper-model jobs of about 2 s each: together longer than
    the test waits for a first result (90 s), so the interrupt always lands mid-batch."""
    shutil.copy(EXAMPLES / "rectangle.json", d / "rectangle.json")
    entries = [{"part": "rectangle.json", "command": "optimize",
                "options": ["--model", "paper", "--at", f"0,{3 + (i % 11) * 1.5:g}",
                            f"12,{3 + (i % 11) * 1.5 + (i // 11) * 0.2:g}", "--max-area", "0.02"]}
               for i in range(n)]
    (d / "jobs.json").write_text(json.dumps(entries))
    return d / "jobs.json"


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc")
@pytest.mark.slow
def test_ctrl_c_is_one_line_exit_130_and_leaves_no_temporary_folder(tmp_path):
    """Ctrl-C of a batch on worker processes: one line, exit 130, the workers gone, and
    no folder of ours in the temporary folder (workers get bytes, not copies)."""
    n_jobs = 96       # ~100 s of work on 2 workers: never done before the interrupt
    jobs = _slow_jobs(tmp_path, n_jobs)
    db = tmp_path / "r.sqlite"
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = {**os.environ, "TMPDIR": str(tmp)}
    proc = subprocess.Popen([sys.executable, "-m", "deformclosure", "batch", str(jobs), "-o",
                             str(db), "--workers", "2", "--quiet"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, preexec_fn=_default_sigint)
    try:
        deadline, n_done = time.monotonic() + 90, 0
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                with sqlite3.connect(db.resolve().as_uri() + "?mode=ro", uri=True) as conn:
                    n_done = conn.execute("SELECT COUNT(*) FROM jobs").fetchone()[0]
            except sqlite3.Error:
                n_done = 0
            if n_done >= 1:
                break
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGINT)          # Ctrl-C: the whole foreground group
        out, err = proc.communicate(timeout=60)
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and _group_alive(proc.pid):
            time.sleep(0.1)
        assert not _group_alive(proc.pid), "worker processes outlived Ctrl-C"
    finally:
        if _group_alive(proc.pid):
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("interrupted; ") and "finished" in lines[0] \
        and "run the same command to resume" in lines[0]
    n_kept = len(read_results(db))
    assert 1 <= n_kept < n_jobs and f"interrupted; {n_kept} job" in lines[0]
    assert not list(tmp.glob("deformclosure-*"))


def test_ctrl_c_inline_is_reported_with_what_is_kept(parts, monkeypatch, tmp_path, capsys):
    calls = []

    def stop(command, part, params=None, **kwargs):
        calls.append(part.name)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return reports.Report(command, {}, params=params)

    monkeypatch.setattr(reports, "run", stop)
    db = tmp_path / "r.sqlite"
    assert main(["batch", str(parts), "-o", str(db), "--command", "mesh", "--quiet",
                 "--scheduler", "inline"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"interrupted; 1 job finished is kept in {db}; run the same command to resume"]
    assert len(read_results(db)) == 1


def test_workers_get_the_bytes_of_the_key_named_as_the_user_named_them(parts, note,
                                                                       monkeypatch, tmp_path):
    """A worker receives the part and every input file as a Source (name and bytes): no
    temporary copies, the user's names in messages; a file that changes after the jobs
    were loaded fails its job, it is not run on other bytes than its key's."""
    base = tmp_path / "systmp"
    base.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(base))
    fingers = parts / "fingers.json"
    shutil.copy(EXAMPLES / "fingers" / "rectangle.json", fingers)
    jobs = [Job.from_spec(parts / "rectangle.json", "check", ["--fingers", "fingers.json"],
                          base_dir=parts),
            *_jobs(parts, "l_shape")]
    (_, path, digest), = jobs[0].inputs
    assert path == str(fingers) and len(digest) == 64
    payload = batch.worker.payload(jobs[0], "9.9")
    assert payload["part"] == Source(jobs[0].part, (parts / "rectangle.json").read_bytes())
    assert payload["params"]["fingers"] == Source(str(fingers), fingers.read_bytes())
    (parts / "l_shape.json").write_text((parts / "l_shape.json").read_text() + " ")
    s = run_batch(jobs, tmp_path / "r.sqlite", scheduler="inline", progress=False)
    assert note.read_text().splitlines() == ["rectangle.json Source Source"]
    assert s.failures[0]["error"] == (f"{jobs[1].part}: the file changed after the batch "
                                      "started; run the batch again")
    assert not list(base.iterdir())
    # The worker checks the version it runs against the batch's.
    out = batch.run_job(payload)
    assert out["status"] == "failed" and "install the same version on every worker" in out["error"]


def test_without_dask_a_scheduler_address_is_one_line_saying_what_to_install(parts, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)       # as if not installed
    with pytest.raises(BatchError, match=r'^--scheduler tcp://h:8786: Dask is not installed; '
                                         r'pip install "deformclosure\[cluster\]"'):
        run_batch(_jobs(parts, "rectangle"), parts.parent / "r.sqlite",
                  scheduler="tcp://h:8786", progress=False)
    assert not (parts.parent / "r.sqlite").exists()


# ----------------------------------------------------------------------------- 10. paths


def test_a_job_list_may_not_reach_outside_its_folder(parts, tmp_path, capsys):
    lists = tmp_path / "lists"
    lists.mkdir()
    shutil.copy(EXAMPLES / "rectangle.json", lists / "inside.json")
    fingers = EXAMPLES / "fingers" / "rectangle.json"
    if not fingers.exists():
        fingers = next((EXAMPLES / "fingers").glob("*.json"))
    shutil.copy(fingers, tmp_path / "fingers.json")
    (lists / "link.json").symlink_to(parts / "rectangle.json")
    cases = [({"part": "../parts/rectangle.json"}, r"job \[0\]: part '../parts/rectangle.json': "
                                                   r"outside the job list's folder"),
             ({"part": "/etc/passwd"}, r"part '/etc/passwd': outside the job list's folder"),
             ({"part": str(parts / "rectangle.json")}, r"outside the job list's folder"),
             ({"part": "link.json"}, r"part 'link.json': outside the job list's folder"),
             ({"part": "inside.json", "command": "check", "options": ["--fingers", "../fingers.json"]},
              r"--fingers '../fingers.json': outside the job list's folder"),
             ({"part": "inside.json", "command": "mesh", "options": ["--plot", "../../out"]},
              r"--plot '../../out': outside the job list's folder")]
    for entry, match in cases:
        jobs = lists / "jobs.json"
        jobs.write_text(json.dumps([entry]))
        with pytest.raises(BatchError, match=match + r".*--allow-outside"):
            load_jobs(jobs)
        assert main(["batch", str(jobs), "-o", str(tmp_path / "r.sqlite"), "--quiet"]) == 2
        _one_error_line(capsys)
        assert not (tmp_path / "r.sqlite").exists()
        assert len(load_jobs(jobs, allow_outside=True)) == 1       # when the user says so
    # Inside is fine, and options given on the command line are the user's own.
    jobs.write_text(json.dumps([{"part": "inside.json", "command": "check"}]))
    (job,) = load_jobs(jobs, options=["--fingers", str(tmp_path / "fingers.json")])
    assert job.options == ("--fingers", str(tmp_path / "fingers.json"))
    assert main(["batch", "--help"]) == 0
    assert "--allow-outside" in capsys.readouterr().out


# ----------------------------------------------------------------------------- 11. trust


def test_the_dask_trust_model_is_documented(capsys):
    doc = (Path(__file__).resolve().parent.parent / "docs" / "batch.md").read_text()
    for phrase in ("pickle", "trusted", "tls://", "distributed.Security",
                   "DASK_DISTRIBUTED__COMM__TLS__CA_FILE"):
        assert phrase in doc, phrase
    assert main(["batch", "--help"]) == 0
    out = capsys.readouterr().out
    assert "trusted" in out and "tls://" in out


# ----------------------------------------------------------------------------- 12. CSV


def _row(key, command, result, status="ok"):
    return {"key": key, "part": f"{key}.json", "command": command, "options": ["--x", "a b"],
            "status": status, "result": result, "error": None, "started": 1_700_000_000.25,
            "finished": 1_700_000_001.5, "seconds": 1.25, "version": "0.1.0"}


def test_results_csv_has_units_iso_times_and_coordinates(parts, note, capsys):
    rows = [
        _row("a", "optimize", {"model": "paper", "sigma_star": 0.0079, "quality": 1.0e-4,
                               "U_A": None, "U_A_infinite": True, "U_L": 1.0e-4, "sigma_L": 0.0078,
                               "jaws": [5, 2], "jaw_positions": [[0.0, 0.01], [0.012, 0.01]]}),
        _row("b", "optimize", {"model": "pads", "verdict": "held", "sigma_star": 0.008,
                               "quality": 5.4e-4, "axis": {"point": [0.0, 0.01], "angle": 0.0},
                               "contacts": [[0.0, 0.01], [0.012, 0.01]]}),
        _row("c", "plan", {"model": "pads", "axes": [{"angle": 1.48, "point": [0.0095, 0.0097],
                                                      "contacts": [[0.0085, 0.0], [0.0105, 0.02]],
                                                      "sigma_star": 0.015, "quality": 9.7e-4,
                                                      "verified": True, "verdict": "held"}]}),
        _row("d", "plan", {"model": "paper", "pairs": [{"a": 30, "b": 204, "sigma_star": 0.008,
                                                        "quality": 2.1e-4}]}),
        _row("e", "check", {"deform_closure": True, "order": 2, "energy": 3e-6}),
        _row("f", "mesh", {"nodes": [[0, 0]] * 3, "triangles": [[0, 1, 2]]}),
        _row("g", "plan", None, status="failed")]
    got = {r["key"]: r for r in csv.DictReader(io.StringIO(format_results(rows, "csv")))}
    head = list(next(csv.reader(io.StringIO(format_results(rows, "csv")))))
    assert head[:10] == ["key", "part", "command", "options", "status", "error", "started_utc",
                         "finished_utc", "seconds_s", "version"]
    for name in ("sigma_star_m", "quality_J", "U_A_J", "U_L_J", "sigma_L_m", "energy_J",
                 "top_sigma_star_m", "top_quality_J", "top_angle_rad", "jaw_a_x_m",
                 "axis_angle_rad", "top_point_x_m", "top_jaw_b_y_m", "n_nodes"):
        assert name in head, name
    assert not {"sigma_star", "quality", "seconds", "started", "top_point"} & set(head)
    a, b, c, d = got["a"], got["b"], got["c"], got["d"]
    assert a["started_utc"] == "2023-11-14T22:13:20.250Z" and a["seconds_s"] == "1.25"
    assert a["options"] == "--x 'a b'"
    assert (a["jaw_a"], a["jaw_b"], a["jaw_b_x_m"], a["jaw_b_y_m"]) == ("5", "2", "0.012", "0.01")
    assert (a["U_A_J"], a["U_A_infinite"]) == ("", "True")
    assert (b["jaw_a_x_m"], b["axis_y_m"], b["axis_angle_rad"], b["verdict"]) == (
        "0.0", "0.01", "0.0", "held")
    assert (c["top_point_x_m"], c["top_jaw_b_y_m"], c["top_angle_rad"], c["n_axes"]) == (
        "0.0095", "0.02", "1.48", "1")
    assert (d["top_a"], d["top_b"], d["top_sigma_star_m"], d["top_jaw_a_x_m"]) == (
        "30", "204", "0.008", "")
    assert got["e"]["energy_J"] == "3e-06" and got["f"]["n_triangles"] == "1"
    assert got["g"]["status"] == "failed" and got["g"]["quality_J"] == ""
    # Through the command, on a real results file.
    db = parts.parent / "r.sqlite"
    run_batch(_jobs(parts, "rectangle"), db, scheduler="inline", progress=False)
    capsys.readouterr()
    assert main(["results", str(db), "--format", "csv"]) == 0
    (r,) = csv.DictReader(io.StringIO(capsys.readouterr().out))
    assert r["sigma_star_m"] == "0.008" and r["quality_J"] == "0.00015"
    assert r["started_utc"].endswith("Z") and float(r["seconds_s"]) >= 0
