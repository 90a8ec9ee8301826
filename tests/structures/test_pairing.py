"""Tests of structures.pairing: Hungarian assignment against brute force, interchange detection."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from structures.common.errors import InputError
from structures.pairing import detect_interchange, pair_modes


def test_assignment_beats_greedy_and_matches_brute_force():
    """Greedy row-wise argmax pairs test modes 0 and 1 with the same analysis mode; the assignment
    is the best one-to-one pairing (checked by enumerating all 4P3 = 24 injections)."""
    metric = np.array([[0.90, 0.80, 0.10, 0.00],
                       [0.85, 0.20, 0.05, 0.00],
                       [0.10, 0.05, 0.70, 0.60]])
    assert np.argmax(metric, axis=1).tolist() == [0, 0, 2]
    p = pair_modes(metric, [1.0, 2.0, 3.0], [1.0, 2.0, 3.0, 4.0])
    best = max(itertools.permutations(range(4), 3), key=lambda c: metric[[0, 1, 2], list(c)].sum())
    assert p.fe_index.tolist() == list(best) == [1, 0, 2]
    np.testing.assert_allclose(p.metric, [0.80, 0.85, 0.70])
    assert p.interchanged.tolist() == [True, True, False] and p.swaps == ((0, 1),)


def test_random_metrics_against_brute_force():
    rng = np.random.default_rng(11)
    for _ in range(20):
        metric = rng.random((4, 6))
        p = pair_modes(metric, np.arange(4.0), np.arange(6.0))
        best = max(itertools.permutations(range(6), 4), key=lambda c: metric[np.arange(4), list(c)].sum())
        assert metric[np.arange(4), p.fe_index].sum() == pytest.approx(metric[np.arange(4), list(best)].sum(),
                                                                      abs=1e-12)


def test_interchange_follows_frequency_order_not_mode_order():
    """Test modes listed out of frequency order are not an interchange; a real inversion is."""
    inter, swaps = detect_interchange([3.0, 1.0, 2.0], [1.0, 2.0, 3.0], [2, 0, 1])
    assert not inter.any() and swaps == ()
    inter, swaps = detect_interchange([1.0, 2.0, 3.0], [1.0, 2.0, 3.0, 4.0], [0, 3, 1])
    assert inter.tolist() == [False, True, True] and swaps == ((1, 2),)


def test_bad_metric_raises():
    with pytest.raises(InputError, match="3 test modes but only 2 analysis modes"):
        pair_modes(np.ones((3, 2)), [1, 2, 3], [1, 2])
    with pytest.raises(InputError, match="NaN/inf"):
        pair_modes(np.array([[np.nan, 1.0]]), [1.0], [1.0, 2.0])
    with pytest.raises(InputError, match="does not match"):
        pair_modes(np.ones((2, 2)), [1.0], [1.0, 2.0])
