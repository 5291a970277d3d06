"""The results file: an SQLite database marked as ours, one row per job.

Marked by ``PRAGMA application_id`` = :data:`APPLICATION_ID` and table ``meta`` with
``format`` = ``deformclosure-results/1``; created atomically (built beside the target and
linked onto it), so it exists complete or not at all. Any other file — text, or another
program's SQLite database — is refused unchanged. Table ``jobs`` (:data:`SCHEMA`)::

    key TEXT PRIMARY KEY  -- hex sha256, see deformclosure.batch.jobs
    part TEXT             -- the part or mesh file as named in the job list
    command TEXT          -- e.g. "plan"
    options TEXT          -- JSON list of the option strings, as given
    status TEXT           -- "ok" or "failed"
    result TEXT           -- JSON report of the command (SI units), NULL if failed
    error TEXT            -- one-line message if failed, else NULL
    started REAL          -- Unix time (s) the worker started the job
    finished REAL         -- Unix time (s) it finished
    seconds REAL          -- run time (s) in the worker
    version TEXT          -- deformclosure version that ran the job

Table ``job_lists`` holds the identity of every job list run into the file (sha256 of its
sorted job keys without the version): a different list is refused unless ``append``.
Only the batch process writes, one transaction per finished job (WAL, synchronous=FULL);
an ``ok`` row is never overwritten. Stored rows are read as untrusted
(:func:`decode_row`): a bad one is "unreadable", never a traceback.
"""

from __future__ import annotations

import json
import math
import os
import sqlite3
import stat
import tempfile
import time
from pathlib import Path
from typing import Any, Sequence

from ..errors import BatchError
from .jobs import MAX_FIELD, Job, _version, one_line as _one_line

__all__ = ["SCHEMA", "APPLICATION_ID", "COLUMNS", "inspect_results", "check_writable",
           "open_for_run", "open_read", "store_row", "decode_row", "db_error", "iso", "is_num",
           "statuses", "failures", "read_rows"]

#: ``PRAGMA application_id`` of a results file ("DCLR"): how we recognise our own files.
APPLICATION_ID = 0x44434C52
#: ``PRAGMA user_version`` of the current results-file layout.
_SCHEMA_VERSION = 1
_FORMAT = "deformclosure-results/1"
_SQLITE_MAGIC = b"SQLite format 3\x00"

#: The results table (one row per job).
SCHEMA = """CREATE TABLE IF NOT EXISTS jobs (
    key TEXT PRIMARY KEY,
    part TEXT NOT NULL,
    command TEXT NOT NULL,
    options TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('ok', 'failed')),
    result TEXT,
    error TEXT,
    started REAL,
    finished REAL,
    seconds REAL,
    version TEXT
)"""
_META_SCHEMA = "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT)"
_LISTS_SCHEMA = """CREATE TABLE IF NOT EXISTS job_lists (
    identity TEXT PRIMARY KEY,
    n_jobs INTEGER,
    source TEXT,
    added REAL
)"""
COLUMNS = ("key", "part", "command", "options", "status", "result", "error", "started",
            "finished", "seconds", "version")


# --------------------------------------------------------------------------- results file
#
# A results file is recognised before anything writes to it: the first 100 bytes must be
# an SQLite header with our application_id (or, for a file of an earlier version, no id
# and nothing but our ``jobs`` table). Anything else is refused without being opened for
# writing, so another program's database is never changed. Every open runs ``PRAGMA
# quick_check``; every SQLite error becomes one line naming the file.

_FIX_RUN = "delete it or give another -o"
_FIX_READ = "restore a copy, or run the batch again into a new file (-o)"


def db_error(shown: str, err: BaseException, fix: str = _FIX_RUN) -> BatchError:
    """One-line BatchError for an SQLite error on the results file ``shown``."""
    msg = _one_line(str(err))[:300]
    low = msg.lower()
    if (isinstance(err, sqlite3.DatabaseError) and not isinstance(err, sqlite3.OperationalError)
            and not isinstance(err, sqlite3.IntegrityError)) \
            or any(w in low for w in ("malformed", "not a database", "corrupt")):
        return BatchError(f"results file {shown} is corrupt: {msg}; {fix}")
    if any(w in low for w in ("readonly", "read-only", "permission", "unable to open")):
        return BatchError(f"results file {shown}: cannot write ({msg}); make the file and its "
                          "folder writable, or give another -o")
    if "full" in low:
        return BatchError(f"results file {shown}: cannot write ({msg}); free some disk space "
                          "and run the same command again (finished jobs are kept)")
    if "locked" in low or "busy" in low:
        return BatchError(f"results file {shown}: in use by another process ({msg}); wait for "
                          "it to finish, or give another -o")
    return BatchError(f"results file {shown}: SQLite error ({msg}); {fix}")


def _not_ours(shown: str, what: str, fix: str = "give another -o") -> BatchError:
    return BatchError(f"{shown}: not a deformclosure results file ({what}); it was left "
                      f"unchanged — {fix}")


def inspect_results(p: Path, shown: str, fix: str = "give another -o") -> str:
    """``"missing"``, ``"empty"`` (0 bytes: an empty SQLite database, nothing to lose),
    ``"ours"`` or ``"legacy"`` (a results file of an earlier version), found without
    writing anything; BatchError for any other file."""
    try:
        st = p.stat()
    except FileNotFoundError:
        if p.is_symlink():
            raise BatchError(f"{shown}: a symbolic link to a missing file; give another -o") from None
        return "missing"
    except (OSError, ValueError) as err:
        raise BatchError(f"results file {shown}: cannot read ({getattr(err, 'strerror', None) or err})") from None
    if stat.S_ISDIR(st.st_mode):
        raise BatchError(f"{shown}: is a folder; give a file name for the results file")
    if not stat.S_ISREG(st.st_mode):
        raise BatchError(f"{shown}: not a regular file; give a file name for the results file")
    if st.st_size == 0:
        return "empty"
    try:
        with open(p, "rb") as fh:
            head = fh.read(100)
    except OSError as err:
        raise BatchError(f"results file {shown}: cannot read ({err.strerror or err})") from None
    if len(head) < 100 or not head.startswith(_SQLITE_MAGIC):
        raise _not_ours(shown, "not an SQLite database", fix)
    app_id = int.from_bytes(head[68:72], "big")
    layout = int.from_bytes(head[60:64], "big")
    if app_id == APPLICATION_ID:
        if layout > _SCHEMA_VERSION:
            raise BatchError(f"{shown}: written by a newer deformclosure (layout {layout}); "
                             "upgrade deformclosure to use it")
        return "ours"
    if app_id != 0:
        raise _not_ours(shown, f"an SQLite database of another program, application_id "
                               f"{app_id:#x}", fix)
    # No id: a results file of an earlier version has exactly our table `jobs`. Read the
    # main file alone first (immutable: no -wal/-shm file is touched); only if its schema
    # is empty and a -wal file exists may the tables be in the log, read the usual way.
    tables, cols = _legacy_schema(p, shown, immutable=True)
    if not tables and Path(f"{p}-wal").exists():
        tables, cols = _legacy_schema(p, shown, immutable=False)
    if tables != ["jobs"] or tuple(cols) != COLUMNS:
        listed = ", ".join(tables[:5]) + (", ..." if len(tables) > 5 else "")
        raise _not_ours(shown, f"an SQLite database with tables {listed or '(none)'}", fix)
    return "legacy"


def _legacy_schema(p: Path, shown: str, immutable: bool) -> tuple[list[str], list[str]]:
    """Tables of an SQLite file without our id, and the columns of ``jobs``; read only."""
    conn = None
    try:
        if immutable:
            conn = sqlite3.connect(p.resolve().as_uri() + "?immutable=1", uri=True)
        else:
            conn = _connect_ro(p)
        tables = sorted(r[0] for r in conn.execute(
            "SELECT name FROM sqlite_master WHERE type IN ('table', 'view') "
            "AND name NOT LIKE 'sqlite_%'"))
        cols = [r[1] for r in conn.execute("PRAGMA table_info(jobs)")] if tables == ["jobs"] else []
    except sqlite3.Error as err:
        raise db_error(shown, err) from None
    finally:
        if conn is not None:
            conn.close()
    return tables, cols


def _connect_ro(p: Path) -> sqlite3.Connection:
    """A read-only connection (opened through a ``file:`` URI: nothing is written)."""
    uri = p.resolve().as_uri() + "?mode=ro"
    try:
        conn = sqlite3.connect(uri, uri=True, timeout=60.0)
        conn.execute("SELECT 1 FROM sqlite_master LIMIT 1").fetchall()
        return conn
    except sqlite3.OperationalError:
        if Path(str(p) + "-wal").exists():
            raise
        # A read-only folder: no -shm can be made; without a -wal file nothing is pending.
        return sqlite3.connect(p.resolve().as_uri() + "?immutable=1", uri=True)


def _check_structure(conn: sqlite3.Connection, shown: str, fix: str) -> None:
    """``PRAGMA quick_check`` and the ``jobs`` columns; BatchError, connection left open."""
    rows = conn.execute("PRAGMA quick_check").fetchall()
    if [tuple(r) for r in rows] != [("ok",)]:
        detail = _one_line(" ".join(str(r[0]) for r in rows[:3]))[:300]
        raise BatchError(f"results file {shown} is corrupt: {detail}; {fix}")
    cols = [r[1] for r in conn.execute("PRAGMA table_info(jobs)")]
    if tuple(cols) != COLUMNS:
        raise _not_ours(shown, f"no table jobs with columns {', '.join(COLUMNS)}", fix)


def open_read(p: Path, shown: str) -> sqlite3.Connection:
    """A checked read-only connection to an existing results file."""
    state = inspect_results(p, shown, fix=_FIX_READ)
    if state == "missing":
        raise BatchError(f"{shown}: results file not found; run deformclosure batch ... -o {shown} first")
    if state == "empty":
        raise BatchError(f"{shown}: an empty file, not a deformclosure results file (yet); run "
                         f"deformclosure batch ... -o {shown} first")
    folder = p.parent if str(p.parent) else Path(".")
    try:
        if os.access(p, os.W_OK) and os.access(folder, os.W_OK | os.X_OK):
            # Ours, and writable: the usual connection, so that closing it removes the
            # -wal/-shm files as the batch does; query_only: reading changes no row.
            conn = sqlite3.connect(str(p), timeout=60.0)
            conn.execute("PRAGMA query_only = ON")
        else:
            conn = _connect_ro(p)
    except sqlite3.Error as err:
        raise db_error(shown, err, _FIX_READ) from None
    try:
        _check_structure(conn, shown, _FIX_READ)
    except sqlite3.Error as err:
        conn.close()
        raise db_error(shown, err, _FIX_READ) from None
    except BaseException:
        conn.close()
        raise
    return conn


def read_rows(p: Path, shown: str, status: str | None = None) -> list:
    """The stored rows (raw cells, text as bytes) of a checked results file; ``status``:
    only rows with it."""
    conn = open_read(p, shown)
    try:
        conn.text_factory = bytes          # decoded per cell: bad UTF-8 marks one row only
        sql = f"SELECT {', '.join(COLUMNS)} FROM jobs"
        return conn.execute(sql + (" WHERE status = ?" if status else ""),
                            (status,) if status else ()).fetchall()
    except sqlite3.Error as err:
        raise db_error(shown, err, _FIX_READ) from None
    finally:
        conn.close()


def check_writable(p: Path, shown: str, exists: bool) -> None:
    """Write access to the file and its folder (SQLite writes its -wal/-shm files beside
    it), checked before any job runs."""
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.is_dir():
        raise BatchError(f"{shown}: folder {folder} does not exist; create it first")
    if exists and not os.access(p, os.W_OK):
        raise BatchError(f"results file {shown}: not writable; make it writable (chmod u+w) "
                         "or give another -o")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise BatchError(f"results file {shown}: its folder {folder} is not writable (SQLite "
                         "keeps its journal beside the file); make it writable or give another -o")


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # pragma: no cover - Windows
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


def _create_results(p: Path, shown: str, replace_empty: bool = False) -> None:
    """Make an empty results file atomically: built beside ``p``, then linked onto it
    (if another run made ``p`` meanwhile, theirs is kept). With ``replace_empty``, ``p``
    is an empty (0-byte) file, replaced if it still is."""
    folder = p.parent if str(p.parent) else Path(".")
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".creating", dir=folder)
    except OSError as err:
        raise BatchError(f"results file {shown}: cannot create it in {folder} "
                         f"({err.strerror or err}); make the folder writable or give another -o") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        conn = sqlite3.connect(str(tmp), isolation_level=None)
        try:
            conn.execute("BEGIN")
            conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
            conn.execute(f"PRAGMA user_version = {_SCHEMA_VERSION}")
            conn.execute(SCHEMA)
            conn.execute(_META_SCHEMA)
            conn.execute(_LISTS_SCHEMA)
            conn.executemany("INSERT INTO meta (key, value) VALUES (?, ?)",
                             [("format", _FORMAT), ("created_by", f"deformclosure {_version()}"),
                              ("created", iso(time.time()))])
            conn.execute("COMMIT")
            # WAL: a commit is one append to the log, and a killed writer leaves the file
            # consistent; the mode is stored in the file.
            conn.execute("PRAGMA journal_mode=WAL")
        finally:
            conn.close()
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        if replace_empty:
            if p.is_file() and p.stat().st_size == 0:
                os.replace(tmp, p)
        else:
            try:
                os.link(tmp, p)
            except FileExistsError:
                pass                               # made meanwhile by another run
            except OSError:                        # no hard links here
                if not p.exists():
                    os.replace(tmp, p)
        _fsync_dir(folder)
    except sqlite3.Error as err:
        raise BatchError(f"results file {shown}: cannot create it ({_one_line(str(err))}); "
                         "give another -o") from None
    except OSError as err:
        raise BatchError(f"results file {shown}: cannot create it ({err.strerror or err}); "
                         "give another -o") from None
    finally:
        for q in (tmp, Path(f"{tmp}-wal"), Path(f"{tmp}-shm"), Path(f"{tmp}-journal")):
            try:
                q.unlink()
            except OSError:
                pass


def open_for_run(p: Path, shown: str, ident: str, keys: set, source: str,
                 append: bool) -> sqlite3.Connection:
    """Create or open the results file for a run: recognised as ours, intact, writable,
    made for this job list (or ``append``). Nothing runs before this succeeds."""
    state = inspect_results(p, shown)
    check_writable(p, shown, exists=state != "missing")
    if state in ("missing", "empty"):
        _create_results(p, shown, replace_empty=state == "empty")
        state = inspect_results(p, shown)
        if state in ("missing", "empty"):
            raise BatchError(f"results file {shown}: cannot create it; give another -o")
    try:
        conn = sqlite3.connect(str(p), timeout=60.0)
    except sqlite3.Error as err:
        raise db_error(shown, err) from None
    try:
        _check_structure(conn, shown, _FIX_RUN)
        conn.isolation_level = None          # explicit transaction below
        if conn.execute("PRAGMA journal_mode").fetchone()[0].lower() != "wal":
            conn.execute("PRAGMA journal_mode=WAL")
        # FULL: a committed row also survives a power cut.
        conn.execute("PRAGMA synchronous=FULL")
        # One write transaction now: a read-only file or folder, a full disk or a file
        # in use fails here, before any job runs.
        conn.execute("BEGIN IMMEDIATE")
        try:
            _prepare(conn, shown, state, ident, keys, source, append)
            conn.execute("COMMIT")
        except BaseException:
            try:
                conn.execute("ROLLBACK")
            except sqlite3.Error:
                pass
            raise
        conn.isolation_level = ""            # back to the default: `with conn` per job
    except sqlite3.Error as err:
        conn.close()
        raise db_error(shown, err) from None
    except BaseException:
        conn.close()
        raise
    return conn


def _prepare(conn: sqlite3.Connection, shown: str, state: str, ident: str, keys: set,
             source: str, append: bool) -> None:
    """Inside the run's first transaction: mark a file of the earlier layout as ours,
    and register this job list (refused if the file holds another one, unless append)."""
    if state == "legacy":            # a results file of an earlier version: mark it
        conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
        conn.execute(f"PRAGMA user_version = {_SCHEMA_VERSION}")
    conn.execute(_META_SCHEMA)
    conn.execute(_LISTS_SCHEMA)
    conn.execute("INSERT OR IGNORE INTO meta (key, value) VALUES ('format', ?)", (_FORMAT,))
    known = {r[0] for r in conn.execute("SELECT identity FROM job_lists")}
    if ident not in known:
        n_rows = conn.execute("SELECT COUNT(*) FROM jobs").fetchone()[0]
        if known and n_rows and not append:
            same = sum(1 for (k,) in conn.execute("SELECT key FROM jobs") if k in keys)
            raise BatchError(
                f"results file {shown}: made for another job list ({n_rows} "
                f"job{'s' * (n_rows != 1)} in it, "
                f"{same} of them in this batch); pass --append (append=True) to add this "
                "batch's jobs to it, or give another -o")
        conn.execute("INSERT INTO job_lists (identity, n_jobs, source, added) "
                     "VALUES (?, ?, ?, ?)", (ident, len(keys), source[:MAX_FIELD], time.time()))
    conn.execute("INSERT OR REPLACE INTO meta (key, value) VALUES ('last_run', ?)",
                 (iso(time.time()),))


def statuses(conn: sqlite3.Connection, shown: str, keys) -> dict[str, str]:
    """Stored status of each of ``keys`` that has a row."""
    try:
        return {k: s for k, s in conn.execute("SELECT key, status FROM jobs") if k in keys}
    except sqlite3.Error as err:
        raise db_error(shown, err) from None


def failures(conn: sqlite3.Connection, shown: str, keys) -> list[dict]:
    """``{"part", "command", "options", "error"}`` of the failed rows of ``keys``, in
    the order of ``keys``."""
    try:
        raw = conn.execute(f"SELECT {', '.join(COLUMNS)} FROM jobs "
                           "WHERE status = 'failed'").fetchall()
    except sqlite3.Error as err:
        raise db_error(shown, err) from None
    rows = {r["key"]: r for r in map(decode_row, raw)}
    return [{"part": rows[k]["part"], "command": rows[k]["command"],
             "options": rows[k]["options"], "error": rows[k]["error"]}
            for k in keys if k in rows]


_UPSERT = f"""INSERT INTO jobs ({', '.join(COLUMNS)}) VALUES ({', '.join('?' * len(COLUMNS))})
ON CONFLICT(key) DO UPDATE SET {', '.join(f'{c} = excluded.{c}' for c in COLUMNS[1:])}
WHERE jobs.status != 'ok'"""


def store_row(conn: sqlite3.Connection, shown: str, job: Job, out: dict, version: str) -> None:
    """Commit one finished job in its own transaction (never overwrites an ok row)."""
    row = (job.key, job.part, job.command, json.dumps(list(job.options)), out["status"],
           out["result"], out["error"], out["started"], out["finished"], out["seconds"], version)
    try:
        with conn:
            conn.execute(_UPSERT, row)
    except sqlite3.Error as err:
        raise db_error(shown, err) from None


def iso(t: Any) -> str | None:
    """ISO 8601 UTC (``2025-01-31T12:00:00.000Z``) of a Unix time, None if not one."""
    import datetime as dt

    if not is_num(t):
        return None
    try:
        return dt.datetime.fromtimestamp(t, dt.timezone.utc).isoformat(
            timespec="milliseconds").replace("+00:00", "Z")
    except (OverflowError, OSError, ValueError):
        return None


def is_num(v: Any) -> bool:
    """A finite real number (not a bool)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _all_finite(value: Any) -> bool:
    stack = [value]
    while stack:
        v = stack.pop()
        if isinstance(v, float) and not math.isfinite(v):
            return False
        if isinstance(v, dict):
            stack.extend(v.values())
        elif isinstance(v, list):
            stack.extend(v)
    return True


def _stored_json(text: str, column: str) -> tuple[Any, str | None]:
    """Parse a stored JSON text by the strict reader's rules: (value, None) or (None, why)."""
    from ..jsonfile import parse_json

    try:
        value = parse_json(text, column, BatchError, "stored value")
    except BatchError as err:
        return None, _one_line(str(err))[:200]
    if not _all_finite(value):
        return None, f"{column}: NaN or Infinity in the stored JSON"
    return value, None


def decode_row(raw: Sequence[Any]) -> dict:
    """A stored row as a dict, checked; a bad row gets ``status = "unreadable"``."""
    d: dict[str, Any] = {}
    problems: list[str] = []
    for col, v in zip(COLUMNS, raw):
        if isinstance(v, (bytes, bytearray)):
            try:
                v = bytes(v).decode("utf-8")
            except UnicodeDecodeError:
                problems.append(f"{col} is not UTF-8 text")
                v = None
        d[col] = v
    for col in ("key", "part", "command", "status", "error", "version"):
        if d[col] is not None and not isinstance(d[col], str):
            problems.append(f"{col} is not text")
            d[col] = None
        elif isinstance(d[col], str) and "\x00" in d[col]:
            problems.append(f"{col} holds a NUL character")
            d[col] = d[col].replace("\x00", "\\0")
    for col in ("key", "part", "command"):
        d[col] = d[col] if d[col] is not None else ""
    if d["status"] not in ("ok", "failed"):
        problems.append(f"status {str(d['status'])[:20]!r} is neither 'ok' nor 'failed'")
    options = d["options"]
    d["options"] = []
    if isinstance(options, str):
        value, why = _stored_json(options, "options")
        if why:
            problems.append(why)
        elif not isinstance(value, list) or not all(isinstance(o, str) for o in value):
            problems.append("options: not a list of strings")
        else:
            d["options"] = value
    else:
        problems.append("options is not text")
    result = d["result"]
    d["result"] = None
    if isinstance(result, str):
        value, why = _stored_json(result, "result")
        if why:
            problems.append(why)
        elif not isinstance(value, dict):
            problems.append("result: not a JSON object")
        else:
            d["result"] = value
    elif result is not None:
        problems.append("result is not text")
    for col in ("started", "finished", "seconds"):
        if d[col] is not None and not is_num(d[col]):
            problems.append(f"{col} is not a finite number")
            d[col] = None
    if problems:
        d["status"] = "unreadable"
        d["result"] = None
        d["error"] = "; ".join(problems)
    return d
