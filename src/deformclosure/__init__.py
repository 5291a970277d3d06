"""deformclosure: D-space, deform closure and optimal two-jaw grasps of deformable planar parts.

Implements and extends K. Gopalakrishnan and K. Goldberg, "D-Space and Deform Closure
Grasps of Deformable Parts", International Journal of Robotics Research 24(11), 2005.

The public API (SPEC §5) is importable from the top level; each name is loaded from its
home module on first use (PEP 562), so ``import deformclosure`` stays light — no numpy,
scipy, numba, matplotlib, click, sqlite3 or multiprocessing until they are needed.

Layers, low to high (no module imports one above it, not even inside a function, and
there is no import cycle; ``docs/architecture.md``)::

    errors, choices, geometry, units, jsonfile, outputs, log, limits   foundation
    part, drawing, mesh                                                 inputs
    elasticity                                                          stiffness, solves
    contact, landscape                                                  mechanics
    grasp (paper model), dspace (fingers), pads, fields                 models
    planning, plotting                                                  planners, pictures
    reports (one function per command), batch                           commands as a library
    cli                                                                 the shell

Examples
--------
>>> import deformclosure as dc
>>> part = dc.Part.from_dict({"units": "mm", "outer": [[0, 0], [12, 0], [12, 20], [0, 20]],
...     "material": {"youngs_modulus": 2e6, "poisson_ratio": 0.1, "thickness": 1,
...                  "elastic_limit_strain": 0.8}, "mesh": {"max_area": 4}})
>>> mesh = dc.mesh_part(part)
>>> mesh.n_nodes > 20
True
"""

from __future__ import annotations

import importlib
from typing import Any

#: Public name -> the module that is its home.
_HOMES = {
    # inputs
    "Part": "part", "Material": "part", "MeshOptions": "part", "demo_part": "part",
    "notched_part": "part", "read_material": "part",
    "part_from_drawing": "part", "read_drawing": "drawing",
    "Source": "jsonfile",
    "Mesh": "mesh", "mesh_part": "mesh", "read_mesh": "mesh", "write_mesh": "mesh",
    # elasticity
    "stiffness_matrix": "elasticity", "element_strains": "elasticity",
    "principal_strains": "elasticity", "strain_magnitude": "elasticity",
    "FreeBodySolver": "elasticity", "rigid_modes": "elasticity", "read_stiffness": "elasticity",
    # the paper's two-jaw model (SPEC §4)
    "pair_stiffness": "grasp", "contact_graph": "grasp", "ContactGraph": "grasp",
    "release_energy": "grasp", "release_energies": "grasp", "grasp_model": "grasp",
    "optimize_separation": "grasp", "GraspAnalysis": "grasp",
    "plan_grasps": "planning.plan", "PlanResult": "planning.plan",
    # any finger set (SPEC §2, §3, §7)
    "load_fingers": "dspace", "PointFinger": "contact.bodies", "DiscFinger": "contact.bodies",
    "PolygonFinger": "contact.bodies", "HalfPlaneFinger": "contact.bodies",
    "Finger": "contact.bodies",
    "deform_closure": "dspace", "dfree_slice": "dspace", "equilibrium": "dspace",
    "release_energy_fingers": "dspace", "FingerRelease": "dspace",
    # pads (SPEC §6)
    "Pad": "pads", "GraspAxis": "pads", "pad_grasp": "pads",
    # errors
    "DeformClosureError": "errors", "PartError": "errors", "MeshError": "errors",
    "StiffnessError": "errors", "GraspError": "errors", "FingerError": "errors",
    "BatchError": "errors",
}

__all__ = ["__version__", *_HOMES]


def __getattr__(name: str) -> Any:
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            value = version("deformclosure")
        except PackageNotFoundError:  # pragma: no cover - running from a source tree
            value = "0.0.0"
    elif name in _HOMES:
        value = getattr(importlib.import_module(f".{_HOMES[name]}", __name__), name)
    else:
        raise AttributeError(f"module 'deformclosure' has no attribute {name!r}")
    globals()[name] = value          # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
