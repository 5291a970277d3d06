"""Shared fixtures. Keep this file small: put helpers used by one test module in it."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from deformclosure import Part, mesh_part

TESTS = Path(__file__).resolve().parent
EXAMPLES = TESTS.parent / "examples"
BAD_INPUTS = TESTS / "bad_inputs"

#: Rubber of the paper's example (SPEC issue 2): E = 2 MPa, nu = 0.1, t = 1 mm.
RUBBER = {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1.0,
          "elastic_limit_strain": 0.8, "plane": "stress"}


#: Single parameter sets of parametrised tests that are slow (``file::test[id]``). Whole
#: tests and modules are marked in their own files (``@pytest.mark.slow``, ``pytestmark``);
#: this table is for the cases of a parametrisation whose other cases stay in the default
#: run as its cheap representatives. The default run (``addopts`` in pyproject.toml)
#: deselects ``slow``; ``python -m pytest -q -p no:cacheprovider -m slow tests`` runs them.
SLOW_PARAMS = {
    "test_docs_examples.py::test_doc_example_runs[README.md-1]",
    "test_docs_examples.py::test_doc_example_runs[batch.md-0]",
    "test_docs_examples.py::test_doc_example_runs[dspace.md-1]",     # placement-energy JIT
    "test_swing_reference.py::test_c_shape_example_matches_reference[fine_134_nodes]",
    "test_swing_reference.py::test_example_parts_match_reference[plate_with_hole]",
    "test_swing_reference.py::test_example_parts_match_reference[ring]",
    # One command-line subprocess each (about 1 s of interpreter start-up): the default run
    # keeps one or two cases per command (deep nesting, fifo, finger radius true, at 1e308,
    # slice extent 1e300; same node, outside, eps 0).
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[utf16 garbage]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[not utf-8]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[duplicate key]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[5000-digit integer]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[400-digit integer]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[NaN]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[obj zero-based]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[obj out of range]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[finger string coordinate]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[half-plane normal 1e308]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[eps 1e-300]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[units empty]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[jaw width 1e308]",
    "test_hostile_inputs.py::test_hostile_input_is_one_line_exit_2[pad radius 1e308]",
    "test_cli_optimize.py::test_bad_optimize_input_is_one_line_exit_2[args1-interior]",
    "test_cli_optimize.py::test_bad_optimize_input_is_one_line_exit_2[args4-eps]",
    "test_cli_optimize.py::test_bad_optimize_input_is_one_line_exit_2[args5-width]",
    "test_cli_optimize.py::test_bad_optimize_input_is_one_line_exit_2[args6-node]",
    "test_cli_optimize.py::test_bad_optimize_input_is_one_line_exit_2[args7-]",
    "test_cli_optimize.py::test_bad_optimize_input_is_one_line_exit_2[args8---at]",
    "test_cli_optimize.py::test_bad_optimize_input_is_one_line_exit_2[args9-jaws]",
}


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "late: run after all other tests (e.g. they read results of subprocesses "
        "started in the background when collection ends)")


@pytest.hookimpl(tryfirst=True)         # before -m/-k deselect, which read the marks
def pytest_collection_modifyitems(config, items):
    seen_files = {item.path.name for item in items}
    found = set()
    for item in items:
        key = f"{item.path.name}::{item.name}"
        if key in SLOW_PARAMS:
            item.add_marker(pytest.mark.slow)
            found.add(key)
    whole_files = not any("::" in a for a in config.args)     # not a run of single tests
    stale = {k for k in SLOW_PARAMS - found if k.partition("::")[0] in seen_files}
    if stale and whole_files:
        warnings.warn(pytest.PytestWarning(f"tests/conftest.py SLOW_PARAMS names tests that do "
                                           f"not exist (renamed?): {sorted(stale)}"))
    # Stable sort: order is kept within the early and the late groups.
    items.sort(key=lambda item: item.get_closest_marker("late") is not None)


def pytest_collection_finish(session):
    """Start the background work of each module with a selected ``late`` test (its
    ``start_background_runs()``), after -m/-k deselection: while the rest of the run goes
    on, and not at all in a run that leaves those tests out."""
    modules = {item.module for item in session.items
               if item.get_closest_marker("late") and getattr(item, "module", None)}
    for module in modules:
        start = getattr(module, "start_background_runs", None)
        if start is not None:
            start()


@pytest.fixture(scope="session")
def examples_dir() -> Path:
    """The ``examples/`` folder of the repository (part files)."""
    return EXAMPLES


@pytest.fixture(scope="session")
def bad_inputs_dir() -> Path:
    """The folder of malformed part and mesh files."""
    return BAD_INPUTS


@pytest.fixture(scope="session")
def make_part():
    """Factory: ``make_part(outer, holes=(), units="mm", points=(), **material)``.

    Builds a part through :meth:`Part.from_dict`, so the file-format path is exercised.
    """

    def _make(outer, holes=(), units="mm", points=(), max_area=None, min_angle=30.0,
              **material):
        mat = dict(RUBBER, **material)
        mesh = {"min_angle": min_angle, "points": [list(map(float, p)) for p in points]}
        if max_area is not None:
            mesh["max_area"] = float(max_area)
        return Part.from_dict({
            "name": "test-part", "units": units,
            "outer": np.asarray(outer, float).tolist(),
            "holes": [np.asarray(h, float).tolist() for h in holes],
            "material": mat, "mesh": mesh,
        })

    return _make


@pytest.fixture(scope="session")
def plate_part() -> Part:
    """``examples/plate_with_hole.json``: 30 × 20 mm plate with a 10 mm hole."""
    return Part.from_file(EXAMPLES / "plate_with_hole.json")


@pytest.fixture(scope="session")
def plate_mesh(plate_part):
    """Mesh of :func:`plate_part` with its own mesh options (about 240 nodes)."""
    return mesh_part(plate_part)
