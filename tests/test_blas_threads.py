"""The BLAS thread cap of the package's dense steps (issue 25, ``limits.blas_threads``).

Checked against threadpoolctl's own report of the loaded BLAS libraries (an independent
reading of what OpenBLAS is set to), not against the helper's bookkeeping.
"""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from deformclosure import limits


def blas_threads_now() -> list[int]:
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


@pytest.fixture
def two_threads():
    """Every BLAS library at 2 threads for the test (restored after)."""
    if not blas_threads_now():
        pytest.skip("no BLAS library under threadpoolctl's control")
    with threadpool_limits(2, user_api="blas"):
        yield


def test_cap_inside_and_restored_after(two_threads):
    assert set(blas_threads_now()) == {2}
    with limits.blas_threads():
        assert set(blas_threads_now()) == {limits.BLAS_THREADS}
        with limits.blas_threads():                    # nested: still capped
            assert set(blas_threads_now()) == {limits.BLAS_THREADS}
        assert set(blas_threads_now()) == {limits.BLAS_THREADS}
    assert set(blas_threads_now()) == {2}


def test_restored_after_an_error(two_threads):
    with pytest.raises(ZeroDivisionError):
        with limits.blas_threads():
            1 / 0
    assert set(blas_threads_now()) == {2}
    with limits.blas_threads():                        # the depth count recovered too
        assert set(blas_threads_now()) == {limits.BLAS_THREADS}


def test_none_leaves_the_threads(two_threads, monkeypatch):
    monkeypatch.setattr(limits, "BLAS_THREADS", None)
    with limits.blas_threads():
        assert set(blas_threads_now()) == {2}


def test_contact_path_and_condensation_run_capped(two_threads, monkeypatch):
    """The per-axis contact path and the condensation's dpotri see one thread, and the
    numbers are those of an uncapped run (a thread count changes no result here beyond
    rounding)."""
    import deformclosure as dc
    import scipy.linalg as sla
    from deformclosure.contact import solve as contact_solve
    from deformclosure.pads import GraspAxis, Pad, PadContact

    seen: list[set[int]] = []
    trace = contact_solve.trace_contact_path
    potri = sla.lapack.dpotri

    def traced(*a, **k):
        seen.append(set(blas_threads_now()))
        return trace(*a, **k)

    def potri_seen(*a, **k):
        seen.append(set(blas_threads_now()))
        return potri(*a, **k)

    monkeypatch.setattr(contact_solve, "trace_contact_path", traced)
    monkeypatch.setattr(sla.lapack, "dpotri", potri_seen)
    mesh = dc.mesh_part(dc.notched_part(2.0))
    pc = PadContact(mesh)
    axis = GraspAxis.through([0.015, 0.0], [0.015, 0.012])
    c = pc.curve(axis, Pad(0.0, 0.002), 0.004)
    assert seen and all(s == {limits.BLAS_THREADS} for s in seen)
    assert set(blas_threads_now()) == {2}
    monkeypatch.setattr(limits, "BLAS_THREADS", None)
    pc2 = PadContact(mesh)
    c2 = pc2.curve(axis, Pad(0.0, 0.002), 0.004)
    assert seen[-1] == {2}
    np.testing.assert_allclose(c2.path.delta, c.path.delta, rtol=1e-9, atol=1e-15)
    s = np.linspace(0.004, c.sigma0, 7)
    np.testing.assert_allclose(c2.energy(s), c.energy(s), rtol=1e-9, atol=1e-15)


def test_cap_holds_in_a_worker_thread_after_the_main_thread_used_it(two_threads):
    """threadpoolctl lets one 'controlling' thread change a pthreads OpenBLAS pool and
    silently ignores the others: a block in a worker thread (a Dask job, a thread pool)
    must still cap the threads after the main thread has entered and left blocks."""
    from concurrent.futures import ThreadPoolExecutor

    with limits.blas_threads():
        pass

    def inside():
        with limits.blas_threads():
            return set(blas_threads_now())

    with ThreadPoolExecutor(1) as pool:
        assert pool.submit(inside).result() == {limits.BLAS_THREADS}
    assert set(blas_threads_now()) == {2}
    with limits.blas_threads():                        # and the main thread again after
        assert set(blas_threads_now()) == {limits.BLAS_THREADS}


def test_cap_stays_while_any_thread_is_inside(two_threads):
    """The limit is the process's: a thread leaving its block must not lift it under a
    block still open in another thread (its solves would run on other threads and add in
    another order), and the last block left restores it."""
    import threading

    entered, release = threading.Event(), threading.Event()
    seen: list[set[int]] = []

    def slow_block():
        with limits.blas_threads():
            entered.set()
            release.wait(10)
            seen.append(set(blas_threads_now()))

    t = threading.Thread(target=slow_block)
    t.start()
    assert entered.wait(10)
    with limits.blas_threads():                        # opened and closed here, meanwhile
        pass
    assert set(blas_threads_now()) == {limits.BLAS_THREADS}   # the other block is open
    release.set()
    t.join(10)
    assert seen == [{limits.BLAS_THREADS}]
    assert set(blas_threads_now()) == {2}
