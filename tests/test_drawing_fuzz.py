"""Fuzzing the drawing readers (issue 23 item 4): random bytes, and random mutations of a
valid DXF (examples/drawings/gasket.dxf) and a valid SVG, read by
:func:`deformclosure.drawing.read_drawing` and made into parts by
:func:`deformclosure.part.part_from_drawing`. The only acceptable outcomes are a drawing
(a part) or one of the package's own errors (:class:`DeformClosureError`), each within a
bounded time."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from deformclosure import DeformClosureError
from deformclosure.drawing import read_drawing
from deformclosure.jsonfile import Source
from deformclosure.part import part_from_drawing, read_material

ROOT = Path(__file__).resolve().parents[1]
GASKET = (ROOT / "examples" / "drawings" / "gasket.dxf").read_bytes()
MATERIAL = read_material('{"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1, '
                         '"elastic_limit_strain": 0.8, "units": "mm"}')
SVG = b"""<?xml version="1.0" encoding="UTF-8"?>
<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink"
     width="100mm" height="60mm" viewBox="0 0 100 60">
  <defs><circle id="peg" r="3"/></defs>
  <g id="part" transform="translate(0 0)">
    <path id="outline" d="M 0 0 H 80 A 20 20 0 0 1 80 40 C 70 50 60 55 50 60 H 0 Z"/>
    <circle id="hole" cx="30" cy="30" r="10"/>
    <rect id="slot" x="10" y="48" width="15" height="5" rx="1"/>
    <use xlink:href="#peg" x="70" y="20"/>
    <polygon points="10,5 20,5 15,12"/>
  </g>
</svg>
"""

#: Longest a single case may take (s): the readers' limits keep every drawing far below.
CASE_SECONDS = 20.0

#: Fragments a hostile drawing is made of, spliced into the valid ones.
HOSTILE = [b"nan", b"inf", b"-inf", b"1e308", b"-1e308", b"1e-300", b"0", b"-0", b"1e999",
           b"\x00", b"\xff\xfe", b"\r\n", b"<!ENTITY a 'aaaa'>", b"&a;", b"<!DOCTYPE svg [",
           b"]>", b'<use xlink:href="#part"/>', b'<g id="part">', b"</g>", b"M", b"Z", b"A",
           b"  0\nINSERT\n  2\n*Model_Space\n", b"  0\nEOF\n", b"  0\nLINE\n", b"  0\nSECTION\n",
           b" 40\n", b" 42\n", b"999999999", b'transform="scale(1e15)"', b"stroke-width"]


def _read(name: str, data: bytes) -> None:
    """Read ``data`` as a drawing and make a part of it; only the package's errors pass."""
    t0 = time.perf_counter()
    try:
        drawing = read_drawing(Source(name, data), default_units="mm")
        assert np.all(np.isfinite(drawing.outer))
        part_from_drawing(Source(name, data), MATERIAL, default_units="mm")
    except DeformClosureError as err:
        assert "\n" not in str(err), str(err)
    dt = time.perf_counter() - t0
    assert dt < CASE_SECONDS, f"{name}: {dt:.1f} s"


@st.composite
def _mutated(draw, base: bytes) -> bytes:
    """``base`` with up to four random edits: a slice deleted, duplicated, replaced by
    random bytes or by a hostile fragment."""
    data = bytearray(base)
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(data)))
        j = min(len(data), i + draw(st.integers(0, 64)))
        kind = draw(st.sampled_from(["delete", "duplicate", "random", "hostile"]))
        if kind == "delete":
            del data[i:j]
        elif kind == "duplicate":
            data[i:i] = data[i:j] * draw(st.integers(1, 3))
        elif kind == "random":
            data[i:j] = draw(st.binary(max_size=32))
        else:
            data[i:j] = draw(st.sampled_from(HOSTILE))
    return bytes(data)


def _numbers_mutated_dxf(draw) -> bytes:
    """The gasket with one value line replaced by a hostile number (the group codes stay
    valid, so ezdxf reads it and the geometry checks are reached)."""
    lines = GASKET.split(b"\n")
    numeric = [k for k in range(1, len(lines), 2) if lines[k].strip().replace(b".", b"", 1)
               .replace(b"-", b"", 1).replace(b"e+", b"", 1).isdigit()]
    k = draw(st.sampled_from(numeric))
    lines[k] = draw(st.sampled_from([b"nan", b"inf", b"1e308", b"-1e308", b"1e-300", b"0",
                                     b"-1", b"1e12", b"1e15"]))
    return b"\n".join(lines)


FUZZ = settings(max_examples=60, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@FUZZ
@given(st.binary(max_size=2048))
def test_random_bytes_as_dxf_and_svg(data):
    _read("fuzz.dxf", data)
    _read("fuzz.svg", data)


@FUZZ
@given(_mutated(GASKET))
def test_mutated_dxf(data):
    _read("gasket.dxf", data)


@FUZZ
@given(st.data())
def test_dxf_with_hostile_numbers(data):
    _read("gasket.dxf", _numbers_mutated_dxf(data.draw))


@FUZZ
@given(_mutated(SVG))
def test_mutated_svg(data):
    _read("part.svg", data)


def test_the_unmutated_examples_read():
    """The fuzzed bases are valid drawings (else the mutations would test nothing)."""
    d = read_drawing(Source("gasket.dxf", GASKET))
    assert len(d.holes) == 2
    s = read_drawing(Source("part.svg", SVG))
    assert s.units == "mm" and len(s.holes) == 4
