"""The neo-Hookean law's element loop (SPEC §8): compiled against the numpy form it replaced.

For each example part, plane stress and plane strain, at a random 5 % strain: the time of
one energy, one energy + force and one energy + force + tangent pass of the compiled law
(:class:`deformclosure.elasticity.NeoHookean`) and of the vectorised numpy form kept in
``tests/neohookean_reference.py``, side by side, with their ratio and the largest relative
difference of the results (the two are tested equal in ``tests/test_neohookean.py``).

Target: the full pass (energy, force and tangent — one per Newton step of the
finite-strain contact solver) ≥ 3× faster than the numpy form on every part.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_neohookean.py [--quick]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

from deformclosure import Part, mesh_part
from deformclosure.elasticity import NeoHookean

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from neohookean_reference import NumpyNeoHookean  # noqa: E402

PARTS = ("examples/notched_bar.json", "examples/rectangle.json", "examples/dogbone.json")
TARGET = 3.0


def per_call(fn, u, repeat: int) -> float:
    """Best of three runs of ``repeat`` calls, seconds per call."""
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        for _ in range(repeat):
            fn(u)
        best = min(best, (time.perf_counter() - t0) / repeat)
    return best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="one part, few repetitions")
    args = ap.parse_args()
    repeat = 3 if args.quick else 30
    print(f"{'part':26} {'plane':6} {'elems':>6}  {'pass':22} {'compiled':>10} {'numpy':>10} "
          f"{'ratio':>6} {'max rel diff':>12}")
    met = True
    for path in PARTS[:1] if args.quick else PARTS:
        base = mesh_part(Part.from_file(path))
        for plane in ("stress", "strain"):
            mesh = base.with_material(dataclasses.replace(base.material, plane=plane))
            law, ref = NeoHookean(mesh), NumpyNeoHookean(mesh)
            rng = np.random.default_rng(1)
            F = np.eye(2) + 0.05 * rng.uniform(-1, 1, (2, 2))
            u = (mesh.nodes @ (F - np.eye(2)).T).ravel()
            u += 0.01 * np.sqrt(mesh.areas.min()) * rng.uniform(-1, 1, u.size)
            law.energy_gradient_tangent(u)                 # compile (or load the cache)
            for name, attr in (("energy", "energy"), ("energy + force", "energy_gradient"),
                               ("energy + force + tangent", "energy_gradient_tangent")):
                a, b = getattr(law, attr), getattr(ref, attr, None)
                if b is None:                              # the numpy form had no fused E, f
                    b = lambda v: (ref.energy(v), ref.gradient(v))  # noqa: E731
                t_c, t_n = per_call(a, u, repeat), per_call(b, u, repeat)
                ra, rb = a(u), b(u)
                ra, rb = (ra if isinstance(ra, tuple) else (ra,)), \
                    (rb if isinstance(rb, tuple) else (rb,))
                diff = 0.0
                for x, y in zip(ra, rb):
                    x = x.toarray() if hasattr(x, "toarray") else np.atleast_1d(x)
                    y = y.toarray() if hasattr(y, "toarray") else np.atleast_1d(y)
                    diff = max(diff, float(np.abs(x - y).max() / np.abs(y).max()))
                ratio = t_n / t_c
                if attr == "energy_gradient_tangent":
                    met &= ratio >= TARGET
                print(f"{Path(path).stem:26} {plane:6} {len(mesh.triangles):>6}  {name:22} "
                      f"{1e3 * t_c:>8.3f}ms {1e3 * t_n:>8.3f}ms {ratio:>6.1f} {diff:>12.1e}")
    print(f"target: full pass >= {TARGET:.0f}x the numpy form on every part: "
          f"{'met' if met else 'NOT met'}")


if __name__ == "__main__":
    main()
