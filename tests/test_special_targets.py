"""Outputs on special targets: devices and FIFOs are written in place, never replaced
(issue 23, item 1; :func:`deformclosure.outputs.output_target`).

Every device or FIFO here is private: FIFOs made with ``os.mkfifo`` and device nodes
made with ``os.mknod`` (where permitted) in ``tmp_path``. The system's ``/dev/null`` and
``/dev/full`` are reached only through symbolic links in ``tmp_path``, and the only
thing checked about them afterwards is that they are still character devices.
"""

from __future__ import annotations

import errno
import io
import os
import socket
import stat
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from deformclosure.cli.main import main
from deformclosure.errors import DeformClosureError
from deformclosure.outputs import (STREAM_OPEN_WAIT, atomic_path, output_target, write_json,
                                   write_text_atomic)

ROOT = Path(__file__).resolve().parents[1]
PART = ROOT / "examples" / "rectangle.json"
FINGERS = ROOT / "examples" / "fingers" / "rectangle.json"

#: Longest time an output may take to give up on a FIFO nobody reads (s).
BOUND = STREAM_OPEN_WAIT + 3.0

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="POSIX FIFOs")


@pytest.fixture(autouse=True)
def private_tmp(tmp_path, monkeypatch):
    """Temporary files of the writers in a folder of this test: none may be left."""
    tmp = tmp_path / "_tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    yield tmp
    assert list(tmp.iterdir()) == []


class Reader:
    """A thread reading a FIFO to its end (what a ``cat fifo`` would see)."""

    def __init__(self, path: Path, limit: int | None = None):
        self.path, self.limit, self.data = path, limit, None
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self) -> None:
        with open(self.path, "rb") as fh:           # blocks until a writer opens it
            self.data = fh.read(self.limit) if self.limit else fh.read()

    def result(self, timeout: float = 30.0) -> bytes | None:
        self.thread.join(timeout)
        if self.thread.is_alive():                  # the writer never came: release it
            fd = os.open(self.path, os.O_WRONLY | os.O_NONBLOCK)
            os.close(fd)
            self.thread.join(5.0)
        return self.data


def _fifo(tmp_path: Path, name: str) -> Path:
    p = tmp_path / name
    os.mkfifo(p)
    return p


def _mknod(tmp_path: Path, name: str, major: int, minor: int) -> Path:
    """A private character device node (1,3 is null, 1,7 is full on Linux)."""
    p = tmp_path / name
    try:
        os.mknod(p, stat.S_IFCHR | 0o666, os.makedev(major, minor))
    except (PermissionError, OSError) as err:
        pytest.skip(f"cannot make a device node here ({err})")
    return p


def _one_error_line(capsys) -> str:
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and err[0].startswith("error:"), err
    assert "Traceback" not in err[0]
    return err[0]


# --------------------------------------------------------------------------- the rule
def test_the_rule_classifies_each_kind_of_target(tmp_path):
    reg = tmp_path / "a.json"
    reg.write_text("{}")
    link = tmp_path / "link.json"
    link.symlink_to(reg)
    dangling = tmp_path / "dangling.json"
    dangling.symlink_to(tmp_path / "later.json")
    fifo = _fifo(tmp_path, "f.json")
    assert output_target(tmp_path / "new.json") == ("file", (tmp_path / "new.json").resolve())
    assert output_target(reg) == ("file", reg.resolve())
    assert output_target(link) == ("file", reg.resolve())          # the link is followed
    assert output_target(dangling) == ("file", (tmp_path / "later.json").resolve())
    assert output_target(fifo) == ("stream", fifo)
    with pytest.raises(DeformClosureError, match="is a folder"):
        output_target(tmp_path)


def test_a_socket_is_refused_with_one_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)                     # short name: AF_UNIX paths are short
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        s.bind("sock.json")
        with pytest.raises(DeformClosureError, match=r"sock\.json: a socket") as err:
            write_json("sock.json", {"a": 1})
        assert "\n" not in str(err.value)
        assert stat.S_ISSOCK(os.lstat("sock.json").st_mode)
    finally:
        s.close()


# --------------------------------------------------------------------------- FIFOs
def _figure():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(2, 2))
    ax.plot([0, 1, 2], [0, 1, 4])
    return fig


def _write_mesh(path):
    from deformclosure import Part, mesh_part
    from deformclosure.mesh import write_mesh

    write_mesh(mesh_part(Part.from_file(PART)), path)


def _write_plot(path):
    from deformclosure.plotting.mesh import save_figure

    save_figure(_figure(), path)


def _write_fields(path):
    from deformclosure.fields import _write_mesh as write_fields_mesh

    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    write_fields_mesh(path, pts, [("triangle", np.array([[0, 1, 2]]))],
                      point_data={"u": np.arange(3.0)})


def _write_slice(path):
    from deformclosure.dspace.slices import SliceResult

    g = np.zeros((2, 3), bool)
    SliceResult(node=0, xs=np.arange(3.0), ys=np.arange(2.0), free=g, in_dt=g,
                obstacles=g[None], energy=np.ones((2, 3)), energy_kind="linear",
                q=np.zeros((3, 2))).save(path)


#: Every kind of writer, by the suffix it needs (its content is compared with the same
#: write to a regular file).
WRITERS = {
    "json": (".json", lambda p: write_json(p, {"k": [1.5, None, "x"]})),
    "text": (".csv", lambda p: write_text_atomic(p, "a,b\n1,2\n", "table")),
    "mesh vtu": (".vtu", _write_mesh),
    "mesh json": (".json", _write_mesh),
    "plot png": (".png", _write_plot),
    "fields vtk": (".vtk", _write_fields),
    "slice npz": (".npz", _write_slice),
}


@pytest.mark.parametrize("name", sorted(WRITERS))
def test_every_writer_writes_into_a_fifo_with_a_reader(tmp_path, name):
    suffix, write = WRITERS[name]
    regular = tmp_path / f"regular{suffix}"
    write(regular)
    fifo = _fifo(tmp_path, f"pipe{suffix}")
    reader = Reader(fifo)
    write(fifo)
    assert reader.result() == regular.read_bytes()
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)                   # not replaced
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["_tmp", regular.name, fifo.name])


def test_a_slice_to_a_fifo_without_a_suffix_keeps_its_name(tmp_path):
    """A regular ``out`` becomes ``out.npz`` (what numpy would write); a FIFO stays."""
    fifo = _fifo(tmp_path, "pipe")
    reader = Reader(fifo)
    _write_slice(fifo)
    data = reader.result()
    assert data[:2] == b"PK"                                       # a zip: the .npz
    assert set(np.load(io.BytesIO(data))) >= {"energy", "free", "xs"}
    assert not (tmp_path / "pipe.npz").exists()


@pytest.mark.parametrize("name", ["json", "mesh vtu", "plot png", "fields vtk"])
def test_a_fifo_without_a_reader_is_one_line_in_bounded_time(tmp_path, name):
    suffix, write = WRITERS[name]
    fifo = _fifo(tmp_path, f"pipe{suffix}")
    t0 = time.monotonic()
    with pytest.raises(DeformClosureError, match=r"pipe.*: a FIFO that no process opened "
                                                 r"for reading within") as err:
        write(fifo)
    assert time.monotonic() - t0 < BOUND + 5.0        # a mesh or a plot is made first
    assert "\n" not in str(err.value) and str(err.value).count("FIFO") == 1   # not wrapped twice
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_a_reader_that_leaves_early_is_one_line(tmp_path):
    fifo = _fifo(tmp_path, "pipe.txt")
    reader = Reader(fifo, limit=10)                   # reads 10 bytes, then closes
    with pytest.raises(DeformClosureError, match=r"pipe\.txt: cannot write text \(") as err:
        write_text_atomic(fifo, "x" * (4 << 20), "text")            # more than a pipe holds
    assert reader.result() == b"x" * 10
    assert "\n" not in str(err.value)


def test_cli_report_into_a_fifo(tmp_path, capsys):
    fifo = _fifo(tmp_path, "mesh.json")
    reader = Reader(fifo)
    assert main(["mesh", str(PART), "-o", str(fifo), "-q"]) == 0
    regular = tmp_path / "regular.json"
    assert main(["mesh", str(PART), "-o", str(regular), "-q"]) == 0
    assert reader.result() == regular.read_bytes()
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_cli_fifo_without_a_reader_exits_2_without_hanging(tmp_path, capsys):
    fifo = _fifo(tmp_path, "mesh.json")
    t0 = time.monotonic()
    assert main(["mesh", str(PART), "-o", str(fifo), "-q"]) == 2
    assert time.monotonic() - t0 < BOUND + 5.0
    line = _one_error_line(capsys)
    assert str(fifo) in line and "FIFO" in line
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_import_output_into_a_fifo(tmp_path, capsys):
    drawing = ROOT / "examples" / "drawings"
    dxf = sorted(drawing.glob("*.dxf"))
    if not dxf:
        pytest.skip("no example drawing")
    fifo = _fifo(tmp_path, "part.json")
    reader = Reader(fifo)
    assert main(["import", str(dxf[0]), "-o", str(fifo), "-q"]) == 0
    regular = tmp_path / "regular.json"
    assert main(["import", str(dxf[0]), "-o", str(regular), "-q"]) == 0
    assert reader.result() == regular.read_bytes()


# --------------------------------------------------------------------------- devices
def test_dev_null_through_a_link_is_written_not_replaced(tmp_path, capsys):
    link = tmp_path / "null.json"
    link.symlink_to("/dev/null")
    write_json(link, {"a": 1})
    assert main(["mesh", str(PART), "-o", str(link), "-q"]) == 0
    plot = tmp_path / "null.png"
    plot.symlink_to("/dev/null")
    _write_plot(plot)
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    assert link.is_symlink() and plot.is_symlink()


def test_dev_full_through_a_link_is_one_line_exit_2(tmp_path, capsys):
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    link = tmp_path / "full.json"
    link.symlink_to("/dev/full")
    assert main(["mesh", str(PART), "-o", str(link), "-q"]) == 2
    line = _one_error_line(capsys)
    assert str(link) in line and os.strerror(errno.ENOSPC) in line
    assert stat.S_ISCHR(os.stat("/dev/full").st_mode)


def test_private_device_nodes_are_written_in_place(tmp_path, capsys):
    null = _mknod(tmp_path, "null.vtu", 1, 3)
    full = _mknod(tmp_path, "full.vtu", 1, 7)
    _write_mesh(null)
    with pytest.raises(DeformClosureError, match=rf"full\.vtu: cannot write mesh file "
                                                 rf"\({os.strerror(errno.ENOSPC)}\)"):
        _write_mesh(full)
    assert main(["optimize", str(PART), "--at", "0,10", "12,10", "-o", str(full), "-q"]) == 2
    assert "full.vtu" in _one_error_line(capsys)
    for p in (null, full):
        assert stat.S_ISCHR(os.lstat(p).st_mode)


# --------------------------------------------------------------------------- links
def test_a_link_to_a_regular_file_is_followed_and_kept(tmp_path):
    real = tmp_path / "real.json"
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(real.name)                      # relative, as ln -s makes them
    write_json(link, {"new": True})
    assert link.is_symlink() and os.readlink(link) == real.name
    assert real.read_text().strip().replace(" ", "").replace("\n", "") == '{"new":true}'
    dangling = tmp_path / "dangling.json"
    dangling.symlink_to(tmp_path / "made.json")
    write_json(dangling, [1])
    assert dangling.is_symlink() and (tmp_path / "made.json").is_file()


def test_a_link_loop_is_one_line(tmp_path):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    a.symlink_to(b)
    b.symlink_to(a)
    with pytest.raises(DeformClosureError, match=r"a\.json: cannot write there") as err:
        write_json(a, {})
    assert "\n" not in str(err.value)


def test_a_failed_write_to_a_device_leaves_no_temporary_file(tmp_path):
    fifo = _fifo(tmp_path, "x.json")
    with pytest.raises(RuntimeError):
        with atomic_path(fifo) as tmp:
            tmp.write_text("partial")
            raise RuntimeError("writer failed")
    # private_tmp checks that the temporary folder is empty


# --------------------------------------------------------------------------- databases
@pytest.mark.parametrize("kind", ["fifo", "null link", "null node"])
def test_a_batch_database_on_a_special_file_is_refused(tmp_path, capsys, kind):
    parts = tmp_path / "parts"
    parts.mkdir()
    (parts / "p.json").write_bytes(PART.read_bytes())
    if kind == "fifo":
        target = _fifo(tmp_path, "results.db")
    elif kind == "null link":
        target = tmp_path / "results.db"
        target.symlink_to("/dev/null")
    else:
        target = _mknod(tmp_path, "results.db", 1, 3)
    t0 = time.monotonic()
    assert main(["batch", str(parts), "-o", str(target), "--scheduler", "inline", "-q"]) == 2
    assert time.monotonic() - t0 < BOUND
    line = _one_error_line(capsys)
    assert "results.db" in line and "regular file" in line
    assert stat.S_ISFIFO(os.stat(target).st_mode) or stat.S_ISCHR(os.stat(target).st_mode)
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
