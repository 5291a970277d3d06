"""Reading the package's JSON input files with one-line errors."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from .errors import DeformClosureError

__all__ = ["read_json"]


def read_json(path: str | Path, error: type[DeformClosureError], what: str) -> Any:
    """Parse the JSON file ``path``.

    Parameters
    ----------
    path : str or Path
    error : DeformClosureError subclass
        Raised, with a one-line message naming the file, when the file cannot be read or
        is not valid JSON.
    what : str
        What the file is, for the message (``"part file"``, ``"finger file"``).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as err:
        reason = getattr(err, "strerror", None) or err
        raise error(f"{path}: cannot read the {what} ({reason})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        raise error(f"{path}: not valid JSON (line {err.lineno} column {err.colno}: {err.msg}); "
                    f"fix the {what}'s syntax") from None
