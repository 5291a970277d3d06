"""Helpers shared by several test modules (not tests themselves)."""

from __future__ import annotations

import pytest
from hypothesis import strategies as st


class WorstMeasured:
    """The worst relative differences a module measured, printed at its end (``pytest -s``)."""

    def __init__(self, title: str = "worst measured (relative unless noted)"):
        self.title, self.values = title, {}

    def record(self, key: str, value: float) -> None:
        self.values[key] = max(self.values.get(key, 0.0), float(value))

    def fixture(self):
        """A module-scoped autouse fixture that prints the table after the module."""
        @pytest.fixture(scope="module", autouse=True)
        def _report_worst():
            yield
            if self.values:
                print(f"\n{self.title}:")
                for k in sorted(self.values):
                    print(f"  {k:<44s} {self.values[k]:.3e}")
        return _report_worst


@st.composite
def adjacency_sets(draw, max_v: int = 12) -> list[set[int]]:
    """A random undirected graph on ``1..max_v`` vertices as adjacency sets (no loops)."""
    V = draw(st.integers(1, max_v))
    pairs = draw(st.lists(st.tuples(st.integers(0, V - 1), st.integers(0, V - 1)),
                          max_size=3 * V))
    adj = [set() for _ in range(V)]
    for a, b in pairs:
        if a != b:
            adj[a].add(b)
            adj[b].add(a)
    return adj
