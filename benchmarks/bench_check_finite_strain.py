"""``check --elasticity neo-hookean`` against the linear ``check`` (SPEC §7, §8, issue 21).

Run:  python benchmarks/bench_check_finite_strain.py [--quick]

Side by side in one run, each grasp through ``reports.run("check", …)`` once with
``elasticity="linear"`` and once with ``"neo-hookean"`` (``--refine 1``: one mesh):

* a 12 × 20 mm rubber block squeezed 0.3 mm by two 2 mm discs at the middles of its long
  sides — a convex part between frictionless discs, never held;
* the notched bar with two 2 mm discs seated 0.3 mm in its notches (full run only: the
  finite-strain search takes its whole 120 s budget) — held by the linear model.

It prints the wall time of each model (the finite-strain one includes the linear run it
starts from), their ratio, the placements each solved and the command's time per
placement, ``U_A`` (the finite-strain bracket when the budget ran out) and the
verdicts.

Target: the verdicts follow mechanics — the convex block is *not held* by either model;
the seated bar is *held* by the linear model and *held* or *undecided* (never "not held")
at finite strain.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from deformclosure import reports

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

DISCS = {"block": [{"type": "disc", "center": [-1.7, 10], "radius": 2},
                   {"type": "disc", "center": [13.7, 10], "radius": 2}],
         "notched bar": [{"type": "disc", "center": [15, 0.47], "radius": 2},
                         {"type": "disc", "center": [15, 11.53], "radius": 2}]}
PARTS = {"block": "rectangle.json", "notched bar": "notched_bar.json"}


def run(name: str, max_area: float, elasticity: str, folder: Path):
    fingers = folder / f"{name.replace(' ', '_')}.json"
    fingers.write_text(json.dumps({"units": "mm", "fingers": DISCS[name]}))
    t = time.perf_counter()
    rep = reports.run("check", str(EXAMPLES / PARTS[name]),
                      {"fingers": str(fingers), "max_area": max_area, "refine": 1,
                       "elasticity": elasticity})
    return rep.data, time.perf_counter() - t


def joules(d: dict) -> str:
    if d.get("U_A_infinite"):
        return "inf"
    if d.get("U_A_is_upper_bound"):
        return f"{1e3 * (d['U_A_lower'] or 0):.3g}..{1e3 * d['U_A']:.3g} mJ"
    return f"{1e3 * d['U_A']:.4g} mJ"


def verdict(d: dict) -> str:
    if "finite_strain_verdict" in d:
        return d["finite_strain_verdict"]
    return "held" if d["deform_closure"] else "not held"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="the block on one coarse mesh only")
    args = ap.parse_args()
    cases = [("block", 4.0)] if args.quick else [("block", 4.0), ("block", 2.0), ("notched bar", 2.0)]
    want = {"block": ({"not held"}, {"not held"}), "notched bar": ({"held"}, {"held", "undecided"})}
    run("block", 8.0, "linear", Path(tempfile.mkdtemp()))          # compile the kernels first
    print("check, linear vs neo-Hookean (one mesh, --refine 1; times warm, in-process)")
    head = (f"{'grasp':<12} {'nodes':>6} {'t lin (s)':>9} {'t neo (s)':>9} {'ratio':>6} "
            f"{'placements lin/neo':>19} {'ms/pl lin/neo':>14} {'U_A lin':>10} {'U_A neo':>16} "
            f"{'verdict lin/neo':>20}")
    print(head)
    met = True
    with tempfile.TemporaryDirectory() as tmp:
        for name, area in cases:
            lin, t_lin = run(name, area, "linear", Path(tmp))
            neo, t_neo = run(name, area, "neo-hookean", Path(tmp))
            n_lin = lin["release"]["placements_solved"]
            n_neo = neo["release"]["placements_solved"]
            nodes = neo["finite_strain_levels"][-1]["nodes"]
            v = (verdict(lin), verdict(neo))
            met &= v[0] in want[name][0] and v[1] in want[name][1]
            print(f"{name:<12} {nodes:>6} {t_lin:>9.2f} {t_neo:>9.2f} {t_neo / t_lin:>6.1f} "
                  f"{f'{n_lin}/{n_neo}':>19} "
                  f"{f'{1e3 * t_lin / max(n_lin, 1):.2f}/{1e3 * t_neo / max(n_neo, 1):.1f}':>14} "
                  f"{joules(lin):>10} {joules(neo):>16} {f'{v[0]}/{v[1]}':>20}")
    print(f"target: verdicts follow mechanics (block not held; seated bar held, finite strain "
          f"held or undecided): {'met' if met else 'NOT met'}")


if __name__ == "__main__":
    main()
