"""The package's logger: what ``--verbose`` shows.

Library modules log their main steps (meshing, factorisation, contact solves, searches)
at ``INFO`` on the logger ``"deformclosure"``; nothing is shown unless a handler is
attached — the CLI's ``--verbose`` attaches one that writes to standard error, and
Python users can call :func:`logging.basicConfig` or :func:`show_steps`.

Long work shows progress through :func:`progress_bar`: a tqdm bar on a terminal, plain
lines (no carriage returns) when standard error is a file or a pipe, so that logs stay
readable. :func:`compile_notice` says once when numba compiles the package's kernels (a
cold cache: the first run after an install or an edit).
"""

from __future__ import annotations

import logging
import sys
import time
from contextlib import contextmanager
from typing import Any, Callable, Iterator, TextIO

__all__ = ["logger", "step", "done", "show_steps", "progress_bar", "PlainProgress",
           "compile_notice", "COMPILE_NOTICE"]

#: What :func:`compile_notice` says before the first kernel compiles.
COMPILE_NOTICE = "compiling kernels (first run only, ~1 min)"

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


def _is_terminal(file: Any) -> bool:
    try:
        return bool(file.isatty())
    except (AttributeError, ValueError):      # no isatty, or closed
        return False


class PlainProgress:
    """Progress for a log file: one line ``desc: n/total unit [t s]`` when the work starts,
    at each tenth of the total (each doubling of ``n`` when the total is unknown) and at
    the end; never a carriage return. The subset of tqdm's interface the package uses.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> with PlainProgress(4, "plan", "axis", file=out, clock=lambda: 0.0) as bar:
    ...     for _ in range(4):
    ...         bar.update(1)
    >>> print(out.getvalue(), end="")
    plan: 0/4 axis [0 s]
    plan: 1/4 axis [0 s]
    plan: 2/4 axis [0 s]
    plan: 3/4 axis [0 s]
    plan: 4/4 axis [0 s]
    """

    def __init__(self, total: int | None, desc: str, unit: str, file: TextIO | None = None,
                 disable: bool = False, clock: Callable[[], float] = time.monotonic) -> None:
        self.total, self.desc, self.unit, self.disable = total, desc, unit, disable
        self.file = sys.stderr if file is None else file
        self.n, self._clock, self._t0 = 0, clock, clock()
        self._postfix, self._shown = "", -1
        self._next = 0
        self._line()

    def _line(self) -> None:
        if self.disable:
            return
        total = "" if self.total is None else f"/{self.total}"
        post = f" ({self._postfix})" if self._postfix else ""
        print(f"{self.desc}: {self.n}{total} {self.unit}{post} "
              f"[{self._clock() - self._t0:.0f} s]", file=self.file, flush=True)
        self._shown = self.n
        if self.total:
            step = max(1, -(-self.total // 10))
            self._next = (self.n // step + 1) * step
        else:
            self._next = max(1, 2 * self.n)

    def update(self, k: int = 1) -> None:
        """Count ``k`` more done."""
        self.n += k
        if self.n >= self._next:
            self._line()

    def set_postfix(self, refresh: bool = False, **kw: Any) -> None:
        """Shown after the count on the next line (``failed=2``)."""
        self._postfix = ", ".join(f"{k}={v}" for k, v in kw.items())

    def write(self, text: str, file: TextIO | None = None) -> None:
        """A message on its own line (on ``file``, default the progress' file)."""
        print(text, file=self.file if file is None else file, flush=True)

    def close(self) -> None:
        """The last count, if not shown yet."""
        if self.n != self._shown:
            self._line()
        self.disable = True

    def __enter__(self) -> "PlainProgress":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def progress_bar(total: int | None, desc: str, unit: str, file: TextIO | None = None,
                 disable: bool = False, **tqdm_options: Any):
    """A progress display on ``file`` (default standard error): a tqdm bar when ``file``
    is a terminal, else a :class:`PlainProgress` (plain lines, no ``\\r``).

    Parameters
    ----------
    total : int or None
        Units of work, if known.
    desc, unit : str
        Its label and the name of one unit (``"placements"``).
    disable : bool
        Show nothing.
    **tqdm_options
        Passed to tqdm on a terminal (``leave=False``, ``dynamic_ncols=True``).
    """
    file = sys.stderr if file is None else file
    if disable or not _is_terminal(file):
        return PlainProgress(total, desc, unit, file=file, disable=disable)
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, file=file, **tqdm_options)


@contextmanager
def compile_notice(echo: Callable[[str], Any], package: str = "deformclosure") -> Iterator[None]:
    """While the block runs, say :data:`COMPILE_NOTICE` through ``echo`` once, when numba
    starts to compile a function of ``package`` (numba's ``numba:compile`` event, which
    fires only when the on-disk cache has no machine code for it: a cold cache).

    >>> with compile_notice(print):
    ...     pass                   # nothing compiled, nothing said
    """
    try:
        from numba.core import event
    except ImportError:                       # pragma: no cover - numba is a dependency
        yield
        return

    class _Notice(event.Listener):
        said = False

        def on_start(self, ev) -> None:
            if self.said:
                return
            data = ev.data if isinstance(ev.data, dict) else {}
            func = getattr(data.get("dispatcher"), "py_func", None)
            module = getattr(func, "__module__", "") or ""
            if module == package or module.startswith(package + "."):
                self.said = True
                echo(COMPILE_NOTICE)

        def on_end(self, ev) -> None:
            pass

    with event.install_listener("numba:compile", _Notice()):
        yield
