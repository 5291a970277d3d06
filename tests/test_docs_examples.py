"""The Python examples of README.md and docs/*.md run as written (STYLE.md §6).

Each fenced ``python`` block is executed in a scratch folder holding a copy of
``examples/``, so relative paths work as they do for a reader in the repository root.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCKS = [(doc, i, code) for doc in DOCS
          for i, code in enumerate(re.findall(r"```python\n(.*?)```", doc.read_text(), re.S))]


def test_the_docs_have_python_examples():
    assert {d.name for d, _, _ in BLOCKS} >= {"README.md", "dspace.md", "batch.md"}


@pytest.mark.parametrize("doc,i,code", BLOCKS, ids=[f"{d.name}-{i}" for d, i, _ in BLOCKS])
def test_doc_example_runs(doc, i, code, tmp_path, monkeypatch, capsys):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    exec(compile(code, f"{doc.name}[python block {i}]", "exec"), {"__name__": "__doc_example__"})
