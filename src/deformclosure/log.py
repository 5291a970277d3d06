"""The package's logger: what ``--verbose`` shows.

Library modules log their main steps (meshing, factorisation, contact solves, searches)
at ``INFO`` on the logger ``"deformclosure"``; nothing is shown unless a handler is
attached — the CLI's ``--verbose`` attaches one that writes to standard error, and
Python users can call :func:`logging.basicConfig` or :func:`show_steps`.
"""

from __future__ import annotations

import logging
import time
from contextlib import contextmanager
from typing import Iterator

__all__ = ["logger", "step", "done", "show_steps"]

#: Logger of the whole package (children: ``deformclosure.<module>``).
logger = logging.getLogger("deformclosure")
logger.addHandler(logging.NullHandler())


@contextmanager
def step(what: str) -> Iterator[None]:
    """Log ``what`` and its wall-clock time (s) when the block ends.

    >>> with step("nothing"):
    ...     pass
    """
    if not logger.isEnabledFor(logging.INFO):
        yield
        return
    t0 = time.perf_counter()
    yield
    logger.info("%s [%.3f s]", what, time.perf_counter() - t0)


def done(what: str, t0: float, *args) -> None:
    """Log ``what % args`` with the time (s) since ``t0`` (a :func:`time.perf_counter`)."""
    if logger.isEnabledFor(logging.INFO):
        logger.info(what + " [%.3f s]", *args, time.perf_counter() - t0)


def show_steps(stream=None) -> logging.Handler:
    """Print the package's ``INFO`` messages to ``stream`` (default: standard error).

    Returns the handler, so that it can be removed with ``logger.removeHandler``.
    """
    handler = logging.StreamHandler(stream)
    handler.setFormatter(logging.Formatter("deformclosure: %(message)s"))
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    return handler
