"""Outputs are written atomically and checked before the work (issue 11, item 5)."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from deformclosure.outputs import write_json
from deformclosure.cli.main import main
from deformclosure.errors import DeformClosureError
from deformclosure.outputs import atomic_path, write_text_atomic

ROOT = Path(__file__).resolve().parents[1]
PART = ROOT / "examples" / "rectangle.json"


def _one_error_line(capsys) -> str:
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and err[0].startswith("error:"), err
    return err[0]


def test_output_equal_to_the_input_is_refused(tmp_path, capsys):
    part = tmp_path / "p.json"
    part.write_bytes(PART.read_bytes())
    before = part.read_bytes()
    assert main(["mesh", str(part), "-o", str(part)]) == 2
    assert "input" in _one_error_line(capsys)
    assert part.read_bytes() == before


def test_missing_output_folder_is_refused_before_the_work(tmp_path, capsys):
    t0 = time.perf_counter()
    assert main(["plan", str(PART), "-o", str(tmp_path / "nodir" / "plan.json")]) == 2
    assert "does not exist" in _one_error_line(capsys)
    assert time.perf_counter() - t0 < 2.0       # no planning happened first


def test_plot_folder_under_a_file_is_one_line(tmp_path, capsys):
    blocker = tmp_path / "afile"
    blocker.write_text("x")
    assert main(["optimize", str(PART), "--at", "0,10", "12,10", "--plot", str(blocker / "out")]) == 2
    assert "is a file" in _one_error_line(capsys)


def test_full_disk_keeps_the_previous_file(tmp_path, monkeypatch):
    target = tmp_path / "report.json"
    write_json(target, {"quality": 1.0})
    before = target.read_bytes()
    real = Path.write_text

    def full(self, *a, **k):
        real(self, "{\"trunc", encoding="utf-8")       # a partial write, then the disk is full
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(DeformClosureError, match="No space left"):
        write_json(target, {"quality": 2.0})
    monkeypatch.undo()
    assert target.read_bytes() == before and json.loads(before)["quality"] == 1.0
    assert [p.name for p in tmp_path.iterdir()] == ["report.json"]   # no temporary left


def test_atomic_write_keeps_permissions_and_cleans_up_on_error(tmp_path):
    target = tmp_path / "a.txt"
    write_text_atomic(target, "one")
    target.chmod(0o640)
    write_text_atomic(target, "two")
    assert target.read_text() == "two" and (target.stat().st_mode & 0o777) == 0o640
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("three")
            raise RuntimeError("killed half way")
    assert target.read_text() == "two" and len(list(tmp_path.iterdir())) == 1


WRITER = """
import sys
from deformclosure.outputs import write_json
big = {"rows": [{"i": i, "x": [float(j) for j in range(40)]} for i in range(4000)]}
k = 0
while True:
    big["k"] = k
    write_json(sys.argv[1], big)
    k += 1
"""


def test_sigkill_during_writes_never_leaves_a_broken_report(tmp_path):
    """A process rewriting a ~1.7 MB report is killed at random moments: the report on
    disk always parses, as the previous or the new version."""
    target = tmp_path / "plan.json"
    write_json(target, {"k": -1})
    for delay in (0.35, 0.5, 0.8, 1.1):
        proc = subprocess.Popen([sys.executable, "-c", WRITER, str(target)])
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        data = json.loads(target.read_text())
        assert "k" in data
