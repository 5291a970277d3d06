"""Shared fixtures. Keep this file small: put helpers used by one test module in it."""

from __future__ import annotations

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


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "late: run after all other tests (e.g. they read results of subprocesses "
        "started in the background at collection)")


def pytest_collection_modifyitems(config, items):
    # Stable sort: order is kept within the early and the late groups.
    items.sort(key=lambda item: item.get_closest_marker("late") is not None)


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
