"""What every report command returns and shares: :class:`Report`, the provenance of its
inputs, and the reading of the part (or mesh, or drawing) with its options."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

__all__ = ["Report", "provenance", "write_report"]


@dataclass
class Report:
    """The result of one command.

    Attributes
    ----------
    command : str
    data : dict
        The JSON report (SI units, SPEC §5), with ``provenance``.
    lines : list of str
        Summary for people (the CLI prints them on standard output).
    warnings : list of str
        Warnings for people (standard error), without the ``warning:`` prefix.
    params : dict
        The parameters the command ran with.
    result : object
        The library result the report was made from (for plots and fields).
    writer : callable(Report, bool) -> list of str, optional
        Writes the outputs named in ``params``; see :meth:`save`.
    """

    command: str
    data: dict
    lines: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    params: dict = field(default_factory=dict)
    result: Any = None
    writer: Callable[["Report", bool], list[str]] | None = None

    def save(self, report: bool = True) -> list[str]:
        """Write the outputs the parameters name: the report (``output``, unless ``report``
        is false; ``-``, standard output, is the caller's), then plots and exports.
        Returns the paths written besides the report."""
        if self.writer is not None:
            return self.writer(self, report)
        write_report(self, report)
        return []


def write_report(rep: Report, report: bool = True) -> None:
    """Write ``rep.data`` as JSON to the ``output`` parameter, if any (not ``-``)."""
    from ..outputs import write_json

    out = rep.params.get("output")
    if report and out is not None and out != "-":
        write_json(out, rep.data)


def provenance(sources) -> dict:
    """Package version and the name and SHA-256 of every input file read."""
    from .. import __version__

    files = [{"name": Path(s.name).name, "sha256": s.sha256} for s in sources if s is not None]
    return {"package": "deformclosure", "version": __version__, "inputs": files}
