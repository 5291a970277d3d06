"""A Dask cluster as a batch scheduler (optional: ``pip install "deformclosure[cluster]"``).

:mod:`distributed` is imported only when a scheduler address (or a client) is given. An
address is checked without network access (scheme, host, port), then the scheduler is
asked who it is — :data:`CONNECT_TIMEOUT` seconds at most — before the client connects,
so a wrong or dead address fails at once with one line, before the results file is
touched. Jobs and results travel pickled: use trusted schedulers only (docs/batch.md).
"""

from __future__ import annotations

import concurrent.futures as cf
from typing import Any

from ..errors import BatchError
from .jobs import one_line as _one_line

__all__ = ["CONNECT_TIMEOUT", "check_scheduler", "is_dask", "connect"]

#: Seconds to wait for a Dask scheduler to answer before giving up.
CONNECT_TIMEOUT = 10.0
#: What to install for Dask.
_INSTALL = 'pip install "deformclosure[cluster]"'


def _dask_error(address: str, reason: str) -> BatchError:
    return BatchError(f"--scheduler {address}: {reason}")


def _probe_scheduler(distributed, address: str, timeout: float) -> None:
    """Check, within ``timeout`` seconds, that ``address`` is a Dask scheduler we can
    reach (TLS from the Dask configuration); one-line errors. Run in its own thread and
    event loop, so it works from a notebook (a running loop) too."""
    import asyncio

    from distributed.comm import connect

    security = None
    try:   # as distributed.Client does: a configured security loader, else the config
        from distributed.client import _maybe_call_security_loader

        security = _maybe_call_security_loader(address)
    except ImportError:  # pragma: no cover - another version of distributed
        pass
    except Exception as err:  # noqa: BLE001 - the user's loader failed
        raise _dask_error(address, f"the Dask security loader failed ({type(err).__name__}: "
                                   f"{_one_line(str(err))[:200]})") from None
    if not isinstance(security, distributed.Security):
        security = distributed.Security()   # the Dask configuration's TLS settings, if any

    async def identity():
        comm = await connect(address, timeout=timeout, **security.get_connection_args("client"))
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            await comm.close()

    def run():
        return asyncio.run(asyncio.wait_for(identity(), timeout))

    with cf.ThreadPoolExecutor(1, thread_name_prefix="deformclosure-probe") as pool:
        fut = pool.submit(run)
        try:
            reply = fut.result(timeout + 5.0)
        except (TimeoutError, asyncio.TimeoutError, cf.TimeoutError):
            raise _dask_error(address, f"no answer within {timeout:g} s; check the address and "
                                       "that the scheduler runs (dask scheduler)") from None
        except OSError as err:
            raise _dask_error(address, f"cannot connect ({_one_line(str(err)) or type(err).__name__}); "
                                       "check the address and that the scheduler runs") from None
        except TypeError as err:
            if "ssl" in str(err).lower() or "tls" in str(err).lower():
                raise _dask_error(address, "tls:// needs the TLS settings in the Dask configuration "
                                           "(distributed.comm.tls.ca-file, .client.cert, "
                                           ".client.key); see docs/batch.md") from None
            raise _dask_error(address, f"not a Dask scheduler ({type(err).__name__})") from None
        except Exception as err:  # noqa: BLE001 - garbage from whatever listens there
            raise _dask_error(address, f"not a Dask scheduler, or it does not speak to us "
                                       f"({type(err).__name__})") from None
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise _dask_error(address, f"answers as {str(kind)[:40]!r}, not a Dask scheduler; give "
                                   "the scheduler's address (port 8786 by default)")


def _distributed(address: str):
    """The :mod:`distributed` module; one line saying what to install if it is missing."""
    try:
        import distributed
        import distributed.comm
    except ImportError:
        raise _dask_error(address, f"Dask is not installed; {_INSTALL} (or use --scheduler "
                                   "processes)") from None
    return distributed


def _check_address(address: str) -> None:
    """Reject, without any network access, an address Dask cannot use."""
    _distributed(address)
    from distributed.comm import parse_address, parse_host_port
    from distributed.comm.registry import get_backend

    try:
        scheme, loc = parse_address(address)
        get_backend(scheme)
        if scheme in ("tcp", "tls", "ws", "wss"):
            host, port = parse_host_port(loc)
            if not host or not 0 < int(port) < 65536:
                raise ValueError("no host, or a port outside 1-65535")
    except (ValueError, TypeError) as err:
        raise _dask_error(address, f"not a usable scheduler address ({_one_line(str(err))}); "
                                   "give one like tcp://HOST:8786") from None


def check_scheduler(scheduler: Any, workers: int | None) -> None:
    """Reject a bad scheduler or worker count before anything else is done."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise BatchError(f"--workers = {workers!r}: must be a whole number >= 1")
    if isinstance(scheduler, str):
        if scheduler in ("processes", "inline"):
            return
        if "://" in scheduler:
            _check_address(scheduler)
            return
    elif hasattr(scheduler, "submit") and hasattr(scheduler, "nthreads"):
        return
    shown = repr(scheduler) if len(repr(scheduler)) < 100 else repr(scheduler)[:100] + "..."
    raise BatchError(f"--scheduler {shown}: choose 'processes', 'inline' or a Dask "
                     "scheduler address such as tcp://host:8786")


def is_dask(scheduler: Any) -> bool:
    """Whether ``scheduler`` is a Dask address or client (not a local one)."""
    return not (isinstance(scheduler, str) and scheduler in ("processes", "inline"))


def connect(scheduler: Any):
    """A :class:`distributed.Client` for ``scheduler`` and whether it is ours to close:
    an address is checked, probed, then connected; a client is used as given."""
    if not isinstance(scheduler, str):
        return scheduler, False
    _check_address(scheduler)
    distributed = _distributed(scheduler)
    timeout = float(CONNECT_TIMEOUT)
    _probe_scheduler(distributed, scheduler, timeout)
    try:
        client = distributed.Client(scheduler, timeout=f"{timeout:g}s", set_as_default=False)
    except Exception as err:  # noqa: BLE001 - one line, whatever Dask raised
        raise _dask_error(scheduler, f"cannot connect to the Dask scheduler "
                                     f"({_one_line(str(err)) or type(err).__name__})") from None
    return client, True


def capacity(client, workers: int | None) -> int:
    """Jobs in flight on a cluster: ``workers``, else twice its threads."""
    if workers:
        return workers
    return max(2, 2 * sum(client.nthreads().values()))


def wait_first(client, futures) -> set:
    """The futures done, waiting for at least one."""
    import distributed

    with client.as_current():  # wait() looks up "the" client; ours is not the default
        return distributed.wait(futures, return_when="FIRST_COMPLETED").done
