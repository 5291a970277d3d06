"""The one JSON writer (``deformclosure.outputs``: ``json_safe``, ``json_text``,
``write_json``): numpy values made Python, non-finite floats made ``null``, strict JSON
always, and atomic files with one-line errors."""

from __future__ import annotations

import json
import math
import os
import threading
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from deformclosure.errors import DeformClosureError
from deformclosure.outputs import json_safe, json_text, write_json


def _refuse(name):
    raise AssertionError(f"non-standard JSON constant {name!r} in the output")


def strict_loads(text: str):
    """``json.loads`` that refuses ``NaN``, ``Infinity`` and ``-Infinity``."""
    return json.loads(text, parse_constant=_refuse)


def expected(obj):
    """What the writer must produce, written independently of it."""
    if isinstance(obj, dict):
        return {str(k): expected(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [expected(v) for v in obj]
    if isinstance(obj, np.ndarray):
        if obj.ndim == 0:
            return expected(obj[()])
        return [expected(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    return obj


# --------------------------------------------------------------------------- json_safe
def test_numpy_scalars_become_python():
    out = json_safe({"f32": np.float32(2.5), "f64": np.float64(0.1), "f16": np.float16(-1.5),
                     "i8": np.int8(-3), "u64": np.uint64(2**63), "b": np.bool_(True)})
    assert out == {"f32": 2.5, "f64": 0.1, "f16": -1.5, "i8": -3, "u64": 2**63, "b": True}
    assert type(out["f32"]) is float and type(out["i8"]) is int and type(out["b"]) is bool
    assert type(out["u64"]) is int


def test_arrays_and_tuples_become_lists():
    a = np.arange(6, dtype=np.int32).reshape(2, 3)
    out = json_safe(((1, 2), a, np.array([np.nan, 1.0, -np.inf]), np.array(7.0)))
    assert out == [[1, 2], [[0, 1, 2], [3, 4, 5]], [None, 1.0, None], 7.0]
    assert all(type(v) is int for v in out[1][0])


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, np.float32("nan"),
                                 np.float64("-inf"), np.float16("inf")])
def test_non_finite_becomes_null(bad):
    assert json_safe(bad) is None
    assert json_safe({"U_A": bad, "list": [bad, 1.0]}) == {"U_A": None, "list": [None, 1.0]}
    assert strict_loads(json_text({"x": bad})) == {"x": None}


def test_keys_become_strings_and_values_pass_through():
    out = json_safe({1: "a", np.int64(2): None, 2.5: True, "s": "text", (1, 2): 0})
    assert out == {"1": "a", "2": None, "2.5": True, "s": "text", "(1, 2)": 0}


def test_input_is_not_modified():
    obj = {"a": [1.0, math.nan], "b": np.array([math.inf])}
    json_safe(obj)
    assert math.isnan(obj["a"][1]) and np.isinf(obj["b"][0])


# --------------------------------------------------------------------------- json_text
def test_json_text_compact_is_sorted_without_spaces():
    assert json_text({"b": 1.0, "a": float("nan"), "c": [np.int64(1), (2,)]},
                     compact=True) == '{"a":null,"b":1.0,"c":[1,[2]]}'


def test_json_text_indent():
    text = json_text({"a": [1, 2]}, indent=2)
    assert text == '{\n  "a": [\n    1,\n    2\n  ]\n}'
    assert "\n" not in json_text({"a": [1, 2]}, indent=None)


def test_json_text_refuses_what_json_cannot_hold():
    with pytest.raises(TypeError):
        json_text({"x": object()})


def test_floats_round_trip_exactly():
    xs = [0.1, 1 / 3, 5e-324, 1.7976931348623157e308, -0.0, 2.0**-1074 * 3]
    assert strict_loads(json_text(xs)) == xs


_scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-(2**70), 2**70), st.text(max_size=8),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(allow_nan=True, allow_infinity=True, width=32).map(np.float32),
    st.floats(allow_nan=True, allow_infinity=True).map(np.float64),
    st.integers(-(2**63), 2**63 - 1).map(np.int64),
    st.integers(-(2**31), 2**31 - 1).map(np.int32),
    st.booleans().map(np.bool_),
)
_arrays = st.one_of(
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=6).map(np.array),
    st.lists(st.integers(-1000, 1000), min_size=1, max_size=6).map(
        lambda v: np.array(v, dtype=np.int64).reshape(-1, 1)),
    st.lists(st.booleans(), max_size=4).map(lambda v: np.array(v, dtype=bool)),
)
_nested = st.recursive(
    st.one_of(_scalars, _arrays),
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.lists(inner, max_size=4).map(tuple),
                            st.dictionaries(st.text(max_size=5), inner, max_size=4)),
    max_leaves=20,
)


@settings(max_examples=150, deadline=None)
@given(obj=_nested, compact=st.booleans(), indent=st.sampled_from([None, 0, 2, 4]))
def test_any_nested_value_gives_strict_json_of_the_expected_value(obj, compact, indent):
    want = expected(obj)
    assert json_safe(obj) == want
    text = json_text(obj, indent=indent, compact=compact)
    assert strict_loads(text) == want


# --------------------------------------------------------------------------- write_json
def _no_leftovers(folder: Path, keep: set[str]) -> None:
    assert {p.name for p in folder.iterdir()} == keep


def test_write_json_writes_strict_json_with_newline(tmp_path):
    target = tmp_path / "report.json"
    obj = {"U_A": np.inf, "k": np.float32(2.5), "jaws": (np.int64(3), 4), "x": np.zeros(2)}
    write_json(target, obj)
    text = target.read_text(encoding="utf-8")
    assert text.endswith("}\n")
    assert strict_loads(text) == {"U_A": None, "k": 2.5, "jaws": [3, 4], "x": [0.0, 0.0]}
    _no_leftovers(tmp_path, {"report.json"})


def test_write_json_replaces_and_keeps_usual_permissions(tmp_path):
    target = tmp_path / "r.json"
    write_json(target, {"a": 1})
    mask = os.umask(0)
    os.umask(mask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~mask
    target.chmod(0o640)
    write_json(target, {"a": 2})
    assert strict_loads(target.read_text()) == {"a": 2}
    assert target.stat().st_mode & 0o777 == 0o640
    _no_leftovers(tmp_path, {"r.json"})


def test_failed_serialisation_keeps_the_previous_file(tmp_path):
    target = tmp_path / "r.json"
    write_json(target, {"good": True})
    before = target.read_bytes()
    with pytest.raises(TypeError):
        write_json(target, {"bad": object()})
    assert target.read_bytes() == before
    _no_leftovers(tmp_path, {"r.json"})


def test_a_reader_only_ever_sees_a_complete_file(tmp_path):
    """While reports of ~0.5 MB are rewritten, a concurrent reader always parses one of
    them whole: never an empty, missing or half-written file."""
    target = tmp_path / "r.json"
    objs = [{"n": n, "data": np.full(20000, float(n))} for n in range(12)]
    write_json(target, objs[0])
    stop = threading.Event()
    seen, problems = set(), []

    def reader():
        while not stop.is_set():
            try:
                data = strict_loads(target.read_text(encoding="utf-8"))
            except Exception as err:     # noqa: BLE001 - any failure is a finding
                problems.append(repr(err)[:200])
                continue
            if data["data"] != [float(data["n"])] * 20000:
                problems.append(f"mixed content in report {data['n']}")
            seen.add(data["n"])

    t = threading.Thread(target=reader)
    t.start()
    try:
        for obj in objs[1:]:
            write_json(target, obj)
    finally:
        stop.set()
        t.join()
    assert not problems, problems[:3]
    assert strict_loads(target.read_text())["n"] == 11
    _no_leftovers(tmp_path, {"r.json"})


def test_missing_folder_is_one_line_error(tmp_path):
    target = tmp_path / "nodir" / "r.json"
    with pytest.raises(DeformClosureError) as info:
        write_json(target, {"a": 1})
    msg = str(info.value)
    assert "\n" not in msg and str(target) in msg and "cannot write" in msg
    assert not target.parent.exists()


def test_unwritable_folder_is_one_line_error_and_leaves_nothing(tmp_path):
    if hasattr(os, "geteuid") and os.geteuid() == 0:   # root ignores folder permissions
        folder = Path("/sys")                             # sysfs refuses new files, even to root
        if not folder.is_dir():
            pytest.skip("running as root without /sys: no unwritable folder to try")
    else:
        folder = tmp_path / "ro"
        folder.mkdir()
        folder.chmod(0o500)
    target = folder / f"deformclosure-test-{os.getpid()}.json"
    before = {p.name for p in folder.iterdir()}
    try:
        with pytest.raises(DeformClosureError) as info:
            write_json(target, {"a": 1}, what="plan report")
        msg = str(info.value)
        assert "\n" not in msg and str(target) in msg and "plan report" in msg
        assert {p.name for p in folder.iterdir()} == before
    finally:
        if folder != Path("/sys"):
            folder.chmod(0o700)


def test_target_that_is_a_folder_is_one_line_error(tmp_path):
    (tmp_path / "r.json").mkdir()
    with pytest.raises(DeformClosureError) as info:
        write_json(tmp_path / "r.json", {"a": 1})
    assert "\n" not in str(info.value)
    _no_leftovers(tmp_path, {"r.json"})
