"""Every ``--help`` example runs as written from the repository root (issue 24, item 6):
each parses with click and names files that exist; the cheap ones run here, the rest
in the slow suite, in a scratch folder holding a copy of ``examples/``."""

from __future__ import annotations

import re
import shlex
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from deformclosure.cli.main import cli, main

ROOT = Path(__file__).resolve().parents[1]

#: Too long for any suite (a plan of every example part; the demo has its own tests).
NOT_RUN = ("deformclosure batch examples/ ", "deformclosure demo")
#: Seconds each, or more: run in the slow suite only.
SLOW = ("deformclosure plan examples/notched_bar.json", "deformclosure plan examples/c_shape.json",
        "deformclosure plan examples/rectangle.json",
        "deformclosure optimize examples/notched_bar.json",
        "deformclosure optimize examples/rectangle.json --at",
        "deformclosure optimize examples/rectangle.json --axis",
        "deformclosure check ", "deformclosure optimize examples/ring.json",
        "deformclosure import examples/drawings/gasket.dxf -o gasket.json --layer")


def _examples() -> list[tuple[str, str]]:
    """``(command, line)`` of every example line of every help text, in help order."""
    out = []
    for name in ["", *sorted(cli.commands)]:
        text = CliRunner().invoke(cli, [name, "--help"] if name else ["--help"]).output
        for line in text.splitlines():
            m = re.match(r"^\s+(deformclosure \S.*)$", line)
            if m:
                out.append((name or "deformclosure", m.group(1)))
    return out


EXAMPLES = _examples()


def test_every_command_has_an_example():
    shown = {shlex.split(line)[1] for _, line in EXAMPLES}
    assert shown >= set(cli.commands)


@pytest.mark.parametrize("where,line", EXAMPLES, ids=[f"{w}:{i}" for i, (w, _) in
                                                      enumerate(EXAMPLES)])
def test_example_parses_and_names_existing_inputs(where, line):
    args = shlex.split(line)[1:]
    command = cli.commands[args[0]]
    ctx = command.make_context(args[0], args[1:])       # raises on a bad option or value
    p = ctx.params
    inputs = [p.get("part"), p.get("fingers")]
    if p.get("material") and not p["material"].lstrip().startswith("{"):
        inputs.append(p["material"])
    if args[0] == "batch":
        inputs.append(p["jobs"])
    for f in inputs:
        if f is not None:
            assert (ROOT / f).exists(), f"{line}: {f} does not exist in the repository"


def _run_examples(examples, tmp_path, monkeypatch, capsys, check) -> int:
    """Run ``examples`` in order in a copy of ``examples/``; those ``check`` selects must
    exit 0. Returns how many were checked."""
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    ran = 0
    for _, line in examples:
        if line.startswith(NOT_RUN):
            continue
        rc = main(shlex.split(line)[1:])
        err = capsys.readouterr().err
        if check(line):
            assert rc == 0, f"{line}: exit {rc}: {err}"
            ran += 1
    return ran


def test_the_cheap_examples_run(tmp_path, monkeypatch, capsys):
    """In help order (the batch before the results it lists), the slow ones left out."""
    cheap = [(w, line) for w, line in EXAMPLES if not line.startswith(SLOW)]
    assert _run_examples(cheap, tmp_path, monkeypatch, capsys, lambda _: True) >= 10
    assert (tmp_path / "drawings.sqlite").is_file() and (tmp_path / "slice.npz").is_file()


@pytest.mark.slow
def test_the_slow_examples_run(tmp_path, monkeypatch, capsys):
    ran = _run_examples(EXAMPLES, tmp_path, monkeypatch, capsys,
                        lambda line: line.startswith(SLOW))
    assert ran >= 7
    assert (tmp_path / "squeeze.pvd").is_file()
