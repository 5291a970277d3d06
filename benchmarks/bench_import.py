"""Importing CAD drawings: time to read a DXF of many entities (issue 13: 5,000 ≤ 2 s).

The drawing is a plate whose outline is a chain of LINE and ARC entities in random order
and direction, with circular holes: every piece must be found, flattened and chained.
Run: ``python benchmarks/bench_import.py``.
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import ezdxf
import numpy as np
import shapely

from deformclosure.drawing import read_drawing


def write_drawing(path: Path, n_entities: int, seed: int = 0) -> float:
    """A circle of radius 100 drawn as alternating LINE and ARC pieces, plus CIRCLE holes;
    returns the exact area."""
    rng = np.random.default_rng(seed)
    n_holes = n_entities // 10
    n_pieces = n_entities - n_holes
    doc = ezdxf.new(units=4)
    msp = doc.modelspace()
    R = 100.0
    angles = np.linspace(0, 2 * math.pi, n_pieces + 1)
    area = 0.0
    order = rng.permutation(n_pieces)
    for k in order:
        a0, a1 = angles[k], angles[k + 1]
        p0 = (R * math.cos(a0), R * math.sin(a0))
        p1 = (R * math.cos(a1), R * math.sin(a1))
        if k % 2:
            msp.add_arc((0, 0), R, math.degrees(a0), math.degrees(a1))
            area += 0.5 * R * R * (a1 - a0)
        else:
            msp.add_line(*((p0, p1) if rng.random() < 0.5 else (p1, p0)))
            area += 0.5 * R * R * math.sin(a1 - a0)
    side = int(math.ceil(math.sqrt(n_holes)))
    r = 0.2 * 120 / side
    xs = np.linspace(-60, 60, side)
    count = 0
    for x in xs:
        for y in xs:
            if count == n_holes:
                break
            msp.add_circle((x, y), r)
            area -= math.pi * r * r
            count += 1
    doc.saveas(path)
    return area


def main() -> None:
    print(f"{'entities':>9} {'vertices':>9} {'holes':>6} {'ezdxf parse (s)':>16} "
          f"{'read_drawing (s)':>17} {'ours/parse':>10} {'area rel. err':>14}")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (500, 5000, 20000):
            path = Path(tmp) / f"plate{n}.dxf"
            exact = write_drawing(path, n)
            t0 = time.perf_counter()
            ezdxf.readfile(path)
            parse = time.perf_counter() - t0
            t0 = time.perf_counter()
            d = read_drawing(path)
            dt = time.perf_counter() - t0
            area = shapely.Polygon(d.outer, list(d.holes)).area
            nv = len(d.outer) + sum(len(h) for h in d.holes)
            print(f"{n:>9} {nv:>9} {len(d.holes):>6} {parse:>16.2f} {dt:>17.2f} "
                  f"{(dt - parse) / parse:>10.2f} {abs(area - exact) / exact:>14.2e}")


if __name__ == "__main__":
    main()
