"""Error estimates against a reference two uniform mesh levels finer (issue 20), opt-in.

The claim of ``tests/test_accuracy.py`` — the reported error of ``quality``, ``U_A`` and
``sigma_star`` bounds the difference to a much finer answer in at least 90 % of the
quantities, for rtol 0.2, 0.1 and 0.05 on three parts — checked against the reference the
issue names: the finest level's own mesh refined *twice* uniformly (every element's area /
16, its twin alike; 37k–51k nodes) and the landscape around the saddles two levels finer
(factor × 4), by the levels' own rule (:func:`~deformclosure.pads.refine.solve_level`).

Marked ``reference``: it takes 10–15 minutes and several GB on 2 cores (the critical-distance
averaging over 100k elements), beyond CI's budget, so neither the README's test command
nor ``-m slow`` runs it. Run it with::

    python -m pytest -q -p no:cacheprovider -m reference tests/test_accuracy_reference.py
"""

from __future__ import annotations

import pytest

from test_accuracy import bracketing_failures

pytestmark = pytest.mark.reference


def test_error_estimates_bound_the_difference_to_a_reference_two_levels_finer():
    checked, failures = bracketing_failures(16.0)
    assert len(failures) <= 0.1 * checked, failures
