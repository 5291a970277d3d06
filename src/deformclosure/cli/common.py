"""Helpers shared by the CLI subcommands: loading inputs, writing reports."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DeformClosureError
from ..mesh import Mesh, mesh_part, read_mesh
from ..mesh.io import is_mesh_file
from ..part import Part

__all__ = ["load_part_or_mesh", "write_json", "json_safe", "parse_xy"]


def load_part_or_mesh(path: str | Path, points: np.ndarray | None = None
                      ) -> tuple[Part | None, Mesh]:
    """Read a part file (and mesh it, inserting ``points`` in m) or a mesh file."""
    path = Path(path)
    if not path.exists():
        raise DeformClosureError(f"{path}: file not found; give a part file (.json) or a mesh file")
    if is_mesh_file(path):
        mesh = read_mesh(path)
        return None, mesh
    part = Part.from_file(path)
    return part, mesh_part(part, points=points)


def json_safe(obj: Any) -> Any:
    """Convert numpy scalars/arrays to Python; non-finite floats to ``None``."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    return obj


def write_json(report: dict, path: str | Path | None) -> None:
    """Write ``report`` as JSON to ``path`` (nothing if ``None``; ``-`` is stdout)."""
    if path is None:
        return
    text = json.dumps(json_safe(report), indent=2, allow_nan=False)
    if str(path) == "-":
        print(text)
        return
    try:
        Path(path).write_text(text + "\n")
    except OSError as err:
        raise DeformClosureError(f"{path}: cannot write report ({err.strerror})") from None


def parse_xy(text: str, field: str) -> tuple[float, float]:
    """Parse ``"X,Y"`` into a pair of floats."""
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise DeformClosureError(f"{field}: expected X,Y (two numbers separated by a comma), got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise DeformClosureError(f"{field}: coordinates must be finite, got {text!r}")
    return x, y
