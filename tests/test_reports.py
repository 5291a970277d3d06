"""The command layer (``deformclosure.reports``): one option table, two parsers that agree,
and reports that do not depend on how the input reached them (a path or its bytes)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from deformclosure import reports
from deformclosure.cli.main import cli, main
from deformclosure.errors import DeformClosureError
from deformclosure.jsonfile import Source
from deformclosure.reports.options import OPTIONS, parse_argv

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
RECT = EXAMPLES / "rectangle.json"


def _value(opt, draw):
    """A valid command-line value of ``opt`` (text), drawn with hypothesis."""
    if opt.kind == "float":
        return repr(draw(st.floats(-1e6, 1e6, allow_nan=False)))
    if opt.kind == "int":
        return str(draw(st.integers(-1000, 1000)))
    if opt.kind == "choice":
        return draw(st.sampled_from(opt.choices))
    if opt.kind == "plot":          # a folder, or a file in a picture format (issue 24)
        return draw(st.from_regex(r"[a-c][a-c0-3]{0,5}(\.(png|svg|pdf|PDF))?", fullmatch=True))
    return draw(st.from_regex(r"[a-c][a-c0-3,.]{0,7}", fullmatch=True))   # no such file


@st.composite
def _argv(draw, command):
    """A random valid option list of ``command``: each option at most once (repeatable
    ones up to three times), long or short spelling, ``--name=value`` or two tokens."""
    argv = []
    for opt in draw(st.permutations(OPTIONS[command])):
        if not draw(st.booleans()):
            continue
        for _ in range(draw(st.integers(1, 3)) if opt.multiple else 1):
            flag = draw(st.sampled_from(opt.flags))
            if opt.kind == "flag":
                argv.append(flag)
                continue
            values = [_value(opt, draw) for _ in range(opt.nargs)]
            if opt.nargs == 1 and flag.startswith("--") and draw(st.booleans()):
                argv.append(f"{flag}={values[0]}")
            else:
                argv += [flag, *values]
    return argv


@pytest.mark.parametrize("command", sorted(OPTIONS))
def test_the_batch_parser_agrees_with_click(command):
    """parse_argv (no click, used by batch) and the click command built from the same
    table give the same parameters for any valid option list."""
    required = [o for o in OPTIONS[command] if o.required]

    @settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(_argv(command))
    def check(argv):
        for o in required:                      # click needs them too
            if not any(a.split("=")[0] in o.flags for a in argv):
                argv = argv + [o.flags[-1], "x.json"]
        ours = parse_argv(command, argv)
        ctx = cli.commands[command].make_context(command, ["part.json", *argv])
        theirs = {k: v for k, v in ctx.params.items() if k in ours}
        assert ours == theirs

    check()


def test_parse_argv_refuses_with_one_line():
    with pytest.raises(DeformClosureError, match=r"did you mean --pad-radius"):
        parse_argv("optimize", ["--pad-radus", "1"])
    with pytest.raises(DeformClosureError, match=r"--top: 'x' is not a whole number"):
        parse_argv("plan", ["--top", "x"])
    with pytest.raises(DeformClosureError, match=r"--model = 'fast': choose one of pads, paper"):
        parse_argv("plan", ["--model", "fast"])
    with pytest.raises(DeformClosureError, match=r"--at needs 2 value"):
        parse_argv("optimize", ["--at", "0,1"])
    with pytest.raises(DeformClosureError, match=r"missing option --fingers"):
        parse_argv("check", [])


def test_run_refuses_unknown_parameters_and_commands():
    with pytest.raises(DeformClosureError, match=r"no parameter 'pad_radus'"):
        reports.run("optimize", RECT, {"pad_radus": 1})
    with pytest.raises(DeformClosureError, match=r"command 'optimise'"):
        reports.run("optimise", RECT)


def test_a_report_is_the_same_from_a_path_and_from_its_bytes(tmp_path):
    """The batch worker's road (the bytes as a Source) and the CLI's (a path) give the
    same report, provenance included."""
    params = {"at": ("0,10", "12,10"), "pad_radius": 1.0, "grid_angles": 8, "grid_offsets": 8}
    by_path = reports.run("optimize", RECT, params)
    by_bytes = reports.run("optimize", Source(str(RECT), RECT.read_bytes()), params)
    assert by_path.data == by_bytes.data
    prov = by_path.data["provenance"]["inputs"]
    assert prov[0]["name"] == "rectangle.json" and len(prov[0]["sha256"]) == 64


def test_the_cli_writes_what_the_library_reports(tmp_path, capsys):
    """The CLI is a thin shell: its JSON is the library report, its stdout the report's
    summary lines."""
    out = tmp_path / "mesh.json"
    assert main(["mesh", str(RECT), "-o", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    rep = reports.run("mesh", RECT)
    assert json.loads(out.read_text()) == json.loads(json.dumps(rep.data))
    assert printed == rep.lines


def test_every_table_option_is_in_the_help():
    for command, table in OPTIONS.items():
        import click

        cmd = cli.commands[command]
        text = cmd.get_help(click.Context(cmd, info_name=command))
        for opt in table:
            assert opt.flags[-1] in text, (command, opt.flags)


def test_a_drawing_and_its_material_file_travel_together(tmp_path):
    """A drawing's ``<name>.material.json`` is read with it: by the CLI road (a path), and
    by batch workers (the bytes of both, the material file's digest in the job key)."""
    import shutil

    from deformclosure.batch import load_jobs, read_results, run_batch

    for name in ("gasket.dxf", "gasket.material.json"):
        shutil.copy(EXAMPLES / "drawings" / name, tmp_path / name)
    jobs_file = tmp_path / "jobs.json"
    jobs_file.write_text(json.dumps([{"part": "gasket.dxf", "command": "mesh"}]))
    direct = reports.run("mesh", tmp_path / "gasket.dxf").data
    assert [i["name"] for i in direct["provenance"]["inputs"]] == ["gasket.dxf",
                                                                  "gasket.material.json"]
    jobs = load_jobs(jobs_file)
    run_batch(jobs, tmp_path / "r.sqlite", scheduler="inline", progress=False)
    (row,) = read_results(tmp_path / "r.sqlite")
    assert row["status"] == "ok", row["error"]
    assert row["result"] == json.loads(json.dumps(direct))
    side = tmp_path / "gasket.material.json"
    side.write_text(side.read_text().replace("0.8", "0.7"))
    assert load_jobs(jobs_file)[0].key != jobs[0].key


@pytest.mark.parametrize("command", ["check", "slice"])
def test_a_missing_required_option_is_a_one_line_error(command, capsys):
    """``check part.json`` without ``--fingers`` was a TypeError traceback (issue 23)."""
    from deformclosure.cli.main import main

    with pytest.raises(DeformClosureError, match=r"--fingers: required"):
        reports.run(command, RECT, {})
    assert main([command, str(RECT)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: --fingers: required")
