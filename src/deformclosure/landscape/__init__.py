"""The release landscape shared by every model: one minimax search, one noise-floor rule,
one elastic-limit rule and one σ*-search.

A release landscape is a graph of vertices with energies — node pairs (the paper model,
SPEC §4), grasp axes ``(θ, c)`` (pads, §6) or placements ``(x, y, φ)`` (fingers, §7). The
models (:mod:`deformclosure.grasp`, :mod:`deformclosure.pads`, :mod:`deformclosure.dspace`)
keep only their coordinates — the vertices, their neighbours and their energies — and
share what is the same on every landscape:

* :func:`~.search.minimax_escape` — the minimax (bottleneck) escape search over a lazy
  energy oracle; its compiled twin for CSR graphs, :func:`.kernels.minimax_search`, runs
  over a compiled vertex oracle (:func:`.kernels.vertex_oracle`) that may bound each
  energy over a cell of the landscape instead of knowing it — the paper planner's cells
  of separations; an energy vector is its point cell, :func:`.kernels.bottleneck_escape`
  (import :mod:`.kernels` where used: it needs numba); with friction (SPEC §9),
  :func:`~.search.dissipative_escape`, the same search on the work of each path (energy
  change plus each move's dissipation), label-setting on (peak work, dissipation);
* :mod:`.noise` — the noise-floor rule: from measured discretisation noise to the floor
  ``τ``, and the "beyond the floor" decisions;
* :mod:`.limit` — the elastic-limit rule;
* :mod:`.optimum` — the σ*-search over piecewise-quadratic curves.

It imports nothing of the models or above.
"""

from .noise import combined_floor, higher, jitter_floor, resolved, twin_floor
from .search import DissipativeEscape, Escape, dissipative_escape, minimax_escape

__all__ = ["Escape", "minimax_escape", "DissipativeEscape", "dissipative_escape", "twin_floor", "jitter_floor", "combined_floor", "higher",
           "resolved"]
