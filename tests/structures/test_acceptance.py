"""Tests of structures.acceptance on hand-made correlation Datasets with known answers."""
from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from structures.acceptance import (MIL_STD_1540C, NASA_STD_5002, AcceptanceCriteria, evaluate_checks,
                                   off_diagonal_maxima)
from structures.common.errors import InputError


def corr_dataset():
    """Three test modes 7, 8, 9 paired with FE modes 8, 7, 10 (FE mode 9 unpaired)."""
    cross = np.array([[0.05, 0.97, 0.30, 0.02],     # rows: test 7, 8, 9; cols: FE 7, 8, 9, 10
                      [-0.92, 0.04, 0.00, 0.08],
                      [0.01, 0.12, 0.00, 0.99]])
    ortho = np.array([[1.0, 0.02, -0.11], [0.02, 1.0, 0.05], [-0.11, 0.05, 1.0]])
    return xr.Dataset(
        {"cross_orthogonality": (("test_mode", "fe_mode"), cross),
         "orthogonality": (("test_mode", "test_mode_2"), ortho),
         "paired_fe_mode": (("test_mode",), [8, 7, 10]),
         "frequency_error": (("test_mode",), [2.9, -4.0, 8.0])},
        coords={"test_mode": [7, 8, 9], "test_mode_2": [7, 8, 9], "fe_mode": [7, 8, 9, 10]})


def test_off_diagonal_maxima_use_the_paired_matrix():
    m = off_diagonal_maxima(corr_dataset())
    np.testing.assert_allclose(m["paired_cross_orthogonality"].values, [0.97, -0.92, 0.99])
    # paired S_p = [[.97 .05 .02], [.04 -.92 .08], [.12 .01 .99]]: FE 9's 0.30 is not a paired term
    np.testing.assert_allclose(m["max_cross_orthogonality_off_diagonal"].values, [0.12, 0.08, 0.12])
    np.testing.assert_allclose(m["max_orthogonality_off_diagonal"].values, [0.11, 0.05, 0.11])


def test_standard_checks_per_mode_with_primary_secondary_split():
    out = evaluate_checks(corr_dataset(), (MIL_STD_1540C, NASA_STD_5002), primary_modes=[7, 8])
    mil, nasa = out.sel(check="MIL-STD-1540C"), out.sel(check="NASA-STD-5002")
    assert out["primary"].values.tolist() == [True, True, False]
    assert nasa["frequency_limit"].values.tolist() == [5.0, 5.0, 10.0]
    assert mil["pass_frequency"].values.tolist() == [True, False, False]
    assert nasa["pass_frequency"].values.tolist() == [True, True, True]
    assert mil["pass_cross_orthogonality_diagonal"].values.tolist() == [True, False, True]
    assert nasa["pass_cross_orthogonality_diagonal"].values.tolist() == [True, True, True]
    assert mil["pass_cross_orthogonality_off_diagonal"].values.tolist() == [False, True, False]
    assert mil["pass_orthogonality"].values.tolist() == [False, True, False]
    assert nasa["pass_all"].values.tolist() == [False, True, False]
    assert not mil["pass_all"].values.any()


def test_limits_are_settings():
    loose = AcceptanceCriteria("loose", frequency_primary=10.0, frequency_secondary=10.0,
                               cross_orthogonality_diagonal=0.5, cross_orthogonality_off_diagonal=0.2,
                               orthogonality_off_diagonal=math.inf)
    out = evaluate_checks(corr_dataset(), [loose])
    assert out["pass_all"].sel(check="loose").values.tolist() == [True, True, True]


def test_bad_settings_raise():
    with pytest.raises(InputError, match="frequency_primary=-3"):
        AcceptanceCriteria("x", -3.0, 3.0, 0.9, 0.1, 0.1)
    with pytest.raises(InputError, match="must be in \\[0, 1\\]"):
        AcceptanceCriteria("x", 3.0, 3.0, 1.5, 0.1, 0.1)
    with pytest.raises(InputError, match=r"primary modes \[99\] are not test modes"):
        evaluate_checks(corr_dataset(), primary_modes=[99])
    with pytest.raises(InputError, match="duplicate check names"):
        evaluate_checks(corr_dataset(), [MIL_STD_1540C, MIL_STD_1540C])
