"""Statistics of a fit's residual against hand computations and tables."""
from __future__ import annotations

import pytest

from pipeline.diagnose.fit_statistics import bic, chi_square, gof_limit, runs_test
from structures.common.errors import InputError


def test_chi_square_and_bic_by_hand():
    assert chi_square([3.0, 4.0]) == pytest.approx(25.0, rel=1e-15)
    # Schwarz 1978: chi^2 + p ln n; ln 100 = 4.605170186
    assert bic(25.0, 2, 100) == pytest.approx(25.0 + 2 * 4.605170186, rel=1e-9)
    with pytest.raises(InputError):
        bic(1.0, 1, 0)


def test_gof_limit_against_table():
    # chi-square 99.9 % quantiles (Abramowitz & Stegun table 26.8): 10 dof 29.588, 1 dof 10.828
    assert gof_limit(10) == pytest.approx(29.588, abs=1e-3)
    assert gof_limit(1) == pytest.approx(10.828, abs=1e-3)


def test_runs_test_by_hand():
    # ten + then ten -: 2 runs, mu = 2*10*10/20 + 1 = 11, var = 10*9/19, z = -9/sqrt(90/19)
    # = -4.1352, one-sided p = Phi(-4.1352) = 1.773e-5
    values = [1.0] * 10 + [-1.0] * 10
    assert runs_test(values) == pytest.approx(1.773e-5, rel=2e-3)
    assert runs_test([1.0, 2.0, 3.0]) == 1.0                  # one sign only
    assert runs_test([1.0, -1.0] * 10) > 0.01                 # alternating: many runs, not few
