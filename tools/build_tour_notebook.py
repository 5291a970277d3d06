"""Build ``examples/tour.ipynb`` from ``examples/tour.py`` (jupytext's percent format), and
with ``--execute`` its rendered copy ``docs/tour.ipynb`` (outputs and figures included).

Run from anywhere:  python tools/build_tour_notebook.py [--execute]

``tour.py`` is the one source: ``tests/test_tour_notebook.py`` checks that the committed
notebook is what this script builds from it, and runs the notebook.
"""

from __future__ import annotations

import argparse
import os
import re
from pathlib import Path

import nbformat

ROOT = Path(__file__).resolve().parents[1]
SOURCE, NOTEBOOK, RENDERED = (ROOT / "examples" / "tour.py", ROOT / "examples" / "tour.ipynb",
                              ROOT / "docs" / "tour.ipynb")
KERNEL = {"display_name": "Python 3", "language": "python", "name": "python3"}


def notebook_of(text: str) -> nbformat.NotebookNode:
    """The notebook of a percent-format script: its header (``# ---`` … ``# ---``) dropped,
    one cell per ``# %%`` marker, markdown cells with their ``# `` prefixes removed."""
    text = re.sub(r"\A# ---\n.*?\n# ---\n", "", text, flags=re.S)
    cells = []
    for chunk in re.split(r"^# %%", text, flags=re.M)[1:]:
        head, _, body = chunk.partition("\n")
        body = body.strip("\n")
        if "[markdown]" in head:
            lines = [ln[2:] if ln.startswith("# ") else ln.lstrip("#") for ln in body.splitlines()]
            cells.append(nbformat.v4.new_markdown_cell("\n".join(lines)))
        else:
            cells.append(nbformat.v4.new_code_cell(body))
    nb = nbformat.v4.new_notebook(cells=cells, metadata={"kernelspec": KERNEL})
    for i, cell in enumerate(nb.cells):      # stable ids: the file changes only with tour.py
        cell["id"] = f"cell-{i}"
    return nb


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--execute", action="store_true",
                    help="also run it and write the rendered copy to docs/tour.ipynb")
    args = ap.parse_args()
    nb = notebook_of(SOURCE.read_text())
    nbformat.write(nb, NOTEBOOK)
    print(f"wrote {NOTEBOOK.relative_to(ROOT)}")
    if args.execute:
        import nbclient

        os.environ.pop("MPLBACKEND", None)       # the kernel's inline figures
        os.environ["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"),
                                                    os.environ.get("PYTHONPATH", "")])
        nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                resources={"metadata": {"path": str(ROOT / "examples")}}).execute()
        # the batch cell prints a temporary folder: keep the rendered page stable
        for cell in nb.cells:
            for out in cell.get("outputs", []):
                if "text" in out:
                    out["text"] = re.sub(r"/tmp/catalogue-[^/\s]+/", "", out["text"])
        nbformat.write(nb, RENDERED)
        print(f"wrote {RENDERED.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
