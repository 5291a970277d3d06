"""Every script in ``benchmarks/`` runs as shipped (issue 25), each with its quickest option.

A benchmark that no longer runs (a renamed function, a job list the batch loader refuses)
fails here instead of in a user's hands. Slow set only: together they take minutes.
``bench_limits.py`` is left out (it runs every command at its documented maximum, up to
the 4 GB budget and many minutes); it is run by hand.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parent.parent / "benchmarks"

#: Script -> its quickest arguments.
QUICK = {
    "bench_accuracy.py": ["--quick"],
    "bench_batch.py": ["--quick"],
    "bench_check.py": ["--quick"],
    "bench_check_finite_strain.py": ["--quick"],
    "bench_critical_distance.py": ["--quick"],
    "bench_dspace.py": ["--repeat", "1"],
    "bench_fem.py": ["--sizes", "1000", "--repeat", "1"],
    "bench_friction.py": ["--smoke"],
    "bench_large_deformation.py": ["--smoke"],
    "bench_neohookean.py": ["--quick"],
    "bench_kkt_solvers.py": ["--smoke"],
    "linear_model_error.py": ["--smoke"],
    "bench_grasp.py": ["--quick"],
    "bench_import.py": ["startup"],
    "bench_memory.py": ["--nodes", "2500", "--only", "optimize --refine 1"],
    "bench_condense.py": ["--quick"],
    "bench_pads.py": ["--quick"],
    "bench_plan.py": ["--quick"],
    "bench_plan_eps.py": ["--quick"],
    "bench_scale.py": ["--quick"],
    "bench_threads.py": ["--quick"],
    "convergence.py": [],
    "convergence_pads.py": [],
}
BY_HAND = {"bench_limits.py"}


def test_every_benchmark_is_listed():
    assert {p.name for p in BENCH.glob("*.py")} == set(QUICK) | BY_HAND


@pytest.mark.slow
@pytest.mark.parametrize("script", sorted(QUICK))
def test_benchmark_runs(script):
    paths = [str(BENCH.parent / "src"), os.environ.get("PYTHONPATH", "")]
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1",
           "PYTHONPATH": os.pathsep.join(p for p in paths if p)}
    out = subprocess.run([sys.executable, str(BENCH / script), *QUICK[script]], env=env,
                         capture_output=True, text=True, timeout=1200)
    assert out.returncode == 0, (out.stdout[-1500:], out.stderr[-1500:])
    assert out.stdout.strip(), "printed nothing"
