"""The examples in the docstrings run and show what they say (issue 10).

One test per module of the package (found with :mod:`pkgutil` without importing it); a
module that cannot be imported only because an optional dependency (the ``cluster``
extra: dask, distributed) is missing is skipped. Modules whose examples are slow are in
``SLOW`` and run with ``-m slow``. A second test lists the public names of
``deformclosure.__all__`` (functions and classes) whose docstring has no ``Examples``
section with an example in it.
"""

from __future__ import annotations

import doctest
import importlib
import importlib.util
import inspect
import pkgutil
import re

import matplotlib

matplotlib.use("Agg")
import pytest  # noqa: E402

import deformclosure  # noqa: E402

#: Optional dependencies: a module that needs one of them is skipped when it is missing.
OPTIONAL = {"dask", "distributed"}

#: Modules whose examples take seconds (run with ``-m slow``).
SLOW: set[str] = set()

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def all_modules() -> list[str]:
    """Every module of the package, walking the source tree with :mod:`pkgutil`."""
    out = ["deformclosure"]

    def walk(path, prefix):
        for info in pkgutil.iter_modules([path], prefix):
            out.append(info.name)
            if info.ispkg:
                walk(f"{path}/{info.name.rpartition('.')[2]}", info.name + ".")

    walk(deformclosure.__path__[0], "deformclosure.")
    return sorted(out)


MODULES = all_modules()


def _import(name: str):
    try:
        return importlib.import_module(name)
    except ImportError as err:
        missing = (getattr(err, "name", None) or "").split(".")[0]
        if missing in OPTIONAL and importlib.util.find_spec(missing) is None:
            pytest.skip(f"{name} needs the optional dependency {missing!r}")
        raise


@pytest.mark.parametrize("name", [pytest.param(m, marks=pytest.mark.slow) if m in SLOW else m
                                  for m in MODULES])
def test_examples_of_module(name, tmp_path, monkeypatch):
    module = _import(name)
    monkeypatch.chdir(tmp_path)            # examples that write files write them here
    finder = doctest.DocTestFinder(exclude_empty=True)
    tests = sorted(finder.find(module, name), key=lambda t: t.name)
    report: list[str] = []
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    for test in tests:
        runner.run(test, out=report.append, clear_globs=True)
    import matplotlib.pyplot as plt

    plt.close("all")
    result = runner.summarize(verbose=False)
    if result.failed:
        pytest.fail(f"{result.failed} of {result.attempted} examples of {name} failed:\n"
                    + "".join(report), pytrace=False)


_EXAMPLES = re.compile(r"^\s*Examples\s*\n\s*-{3,}\s*\n(.*?)(?:^\s*[A-Z][A-Za-z ]+\s*\n\s*-{3,}\s*$|\Z)",
                       re.M | re.S)


def has_examples(obj) -> bool:
    """Whether the docstring of ``obj`` has a numpydoc ``Examples`` section with at least
    one ``>>>`` example."""
    doc = inspect.getdoc(obj) or ""
    m = _EXAMPLES.search(doc)
    return bool(m and ">>>" in m.group(1))


def test_has_examples_reads_numpydoc_sections():
    def good():
        """Do.

        Examples
        --------
        >>> 1 + 1
        2
        """

    def empty():
        """Do.

        Examples
        --------
        See the guide.

        Notes
        -----
        >>> 1
        1
        """

    assert has_examples(good) and not has_examples(empty) and not has_examples(len)


def test_public_functions_and_classes_have_examples():
    missing = []
    for name in deformclosure.__all__:
        obj = getattr(deformclosure, name)
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and not has_examples(obj):
            missing.append(name)
    if missing:
        pytest.fail(f"{len(missing)} public names of deformclosure.__all__ have no Examples "
                    f"section with an example in their docstring: {', '.join(missing)}",
                    pytrace=False)
