"""Import benchmarks: the package's start-up cost, and importing CAD drawings.

``startup`` (issue 10): ``python -X importtime -c "import deformclosure"`` (total and the
heaviest modules), the wall time of ``python -c "import deformclosure"`` and of
``deformclosure --help`` (best of 5, warm: after one untimed run), against the targets.
Each run is a fresh interpreter, as a user's shell command is.

``drawing`` (issue 13): time to read a DXF of many entities (5,000 ≤ 2 s). The drawing
is a plate whose outline is a chain of LINE and ARC entities in random order and
direction, with circular holes: every piece must be found, flattened and chained.

Run: ``python benchmarks/bench_import.py [startup|drawing]`` (both when omitted).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: Targets (s) of issue 10; ``None``: shown for reference.
TARGETS = {"deformclosure --help": 0.3, "import deformclosure": None, "python -c pass": None}

#: What ``import deformclosure`` alone must not load (tests/test_layers.py checks it too).
HEAVY = ("sqlite3", "multiprocessing", "dask", "distributed", "matplotlib", "click", "numba",
         "scipy", "numpy")


# --------------------------------------------------------------------------- start-up
def _cli() -> list[str]:
    """The installed ``deformclosure`` entry point (beside this interpreter), or
    ``python -m deformclosure``."""
    exe = Path(sys.executable).parent / "deformclosure"
    if exe.exists():
        return [str(exe)]
    found = shutil.which("deformclosure")
    return [found] if found else [sys.executable, "-m", "deformclosure"]


def best_wall(cmd: list[str], repeat: int = 5) -> float:
    """Best wall time (s) of ``cmd`` over ``repeat`` runs, after one untimed warm-up."""
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    subprocess.run(cmd, capture_output=True, env=env, check=True)
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(cmd, capture_output=True, env=env, check=True)
        best = min(best, time.perf_counter() - t0)
    return best


def importtime(code: str = "import deformclosure", repeat: int = 5):
    """``-X importtime`` of ``code``, best of ``repeat``: the total (s, the sum of every
    module's own time) and the run's rows ``(cumulative s, module)`` sorted, heaviest
    first."""
    best = None
    for _ in range(repeat + 1):
        proc = subprocess.run([sys.executable, "-X", "importtime", "-c", code],
                              capture_output=True, text=True, check=True)
        rows = []
        for line in proc.stderr.splitlines():
            m = re.match(r"import time:\s+(\d+)\s+\|\s+(\d+)\s+\|(\s*)(\S+)", line)
            if m:
                rows.append((int(m.group(1)) * 1e-6, int(m.group(2)) * 1e-6,
                             len(m.group(3)) - 1, m.group(4)))
        total = sum(r[0] for r in rows)
        if best is None or total < best[0]:
            best = (total, rows)
    total, rows = best
    return total, sorted(((c, name) for _, c, _, name in rows), reverse=True)


def loaded_modules(code: str = "import deformclosure") -> list[str]:
    out = subprocess.run([sys.executable, "-c", f"{code}; import sys, json; "
                          "print(json.dumps(sorted(sys.modules)))"],
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def startup() -> None:
    print(f"start-up of deformclosure ({sys.executable}; best of 5, warm)")
    total, rows = importtime()
    walls = {
        "python -c pass": best_wall([sys.executable, "-c", "pass"]),
        "import deformclosure": best_wall([sys.executable, "-c", "import deformclosure"]),
        "deformclosure --help": best_wall([*_cli(), "--help"]),
    }
    print(f"{'measure':<42} {'time (s)':>9} {'target (s)':>11} {'':>5}")

    def row(name, value, target):
        ok = "" if target is None else ("ok" if value <= target else "SLOW")
        tgt = "-" if target is None else f"<= {target:g}"
        print(f"{name:<42} {value:>9.3f} {tgt:>11} {ok:>5}")

    row("-X importtime: import deformclosure (sum)", total, None)
    for name, value in walls.items():
        row(f"wall: {name}", value, TARGETS[name])
    mods = loaded_modules()
    ours = [m for m in mods if m == "deformclosure" or m.startswith("deformclosure.")]
    heavy = sorted({m.split(".")[0] for m in mods} & set(HEAVY))
    print(f"\nimport deformclosure loads {len(mods)} modules, {len(ours)} of the package; "
          f"heavy libraries: {', '.join(heavy) or 'none'}")
    print("heaviest imports (cumulative, s):")
    for c, name in rows[:8]:
        print(f"  {c:8.3f}  {name}")


# --------------------------------------------------------------------------- drawings
def write_drawing(path: Path, n_entities: int, seed: int = 0) -> float:
    """A circle of radius 100 drawn as alternating LINE and ARC pieces, plus CIRCLE holes;
    returns the exact area."""
    import ezdxf
    import numpy as np

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


def drawing() -> None:
    import ezdxf
    import shapely

    from deformclosure.drawing import read_drawing

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("which", nargs="?", choices=["startup", "drawing"],
                    help="one table only (default: both)")
    args = ap.parse_args()
    if args.which in (None, "startup"):
        startup()
    if args.which is None:
        print()
    if args.which in (None, "drawing"):
        drawing()


if __name__ == "__main__":
    main()
