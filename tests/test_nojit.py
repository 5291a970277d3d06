"""The placement-energy kernels (``dspace/placement_energy.py``) in the default run, without
their JIT compilation.

Compiling them costs about a minute of CPU whenever numba's cache is cold (a fresh
checkout, CI, or after the file changes), so the tests that run them compiled are in the
slow set (``-m slow``). The default run still checks their algorithm: the Theorem 1
catalogue of ``test_release_fingers.py`` (the energy kernel against the independent rigid
form-closure test, 60-odd finger sets) runs in a subprocess with ``NUMBA_DISABLE_JIT=1``,
where the ``@njit`` functions run as the Python they are written in.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def test_theorem1_catalogue_without_jit():
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", MPLBACKEND="Agg")
    env.pop("PYTEST_ADDOPTS", None)
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", "slow or not slow",
         "-k", "theorem1_at_rest or catalogue", str(TESTS / "test_release_fingers.py")],
        capture_output=True, text=True, cwd=TESTS.parent, env=env, timeout=900)
    tail = proc.stdout.strip().splitlines()[-1] if proc.stdout.strip() else ""
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]
    m = re.search(r"(\d+) passed", tail)
    assert m and int(m.group(1)) >= 50, tail
    assert "failed" not in tail and "error" not in tail, tail
