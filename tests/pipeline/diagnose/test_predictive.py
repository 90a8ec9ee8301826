"""Held-out predictive check (pipeline.diagnose.predictive) on hand-worked per-mode tables."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from pipeline.diagnose.predictive import held_out_evidence, held_out_modes, reproduced

ENTRIES = np.array([10, 10, 10])     # three held-out modes, 10 entries each


def test_reproduced_at_the_goodness_of_fit_quantile():
    """chi^2_0.999 with 10 degrees of freedom is 29.588 (statistical tables)."""
    assert reproduced([29.5, 29.7], [10, 10]).tolist() == [True, False]


def test_evidence_over_modes_either_model_reproduces():
    """"none" 8, 10, 12. A fit 8, 60, 12: all kept, c_ho = 80 / 30, (30 - 80) / (8 / 3)
    = -18.75. A fall 4, 5, 6: c_ho = 1, +15. A rise to 15, 17, 18 over modes still
    reproduced: c_ho = 50 / 30, -20 / (5 / 3) = -12."""
    none = [8.0, 10.0, 12.0]
    assert held_out_evidence(none, [8.0, 60.0, 12.0], ENTRIES) == pytest.approx(-18.75, rel=1e-12)
    assert held_out_evidence(none, [4.0, 5.0, 6.0], ENTRIES) == pytest.approx(15.0, rel=1e-12)
    assert held_out_evidence(none, [15.0, 17.0, 18.0], ENTRIES) == \
        pytest.approx(-12.0, rel=1e-12)


def test_a_mode_neither_model_reproduces_is_left_out():
    """Mode 2 at 3000 ("none") and 5000 (fit), both > 29.588: left out, (20 - 18) / 1 = +2
    (summed it would be -1998 / (5018 / 30) = -11.95). "none" at 25 there and the fit at 3000:
    kept, (45 - 3020) / (3020 / 30) = -29.55. No kept mode: 0."""
    assert held_out_evidence([8.0, 3000.0, 12.0], [8.0, 5000.0, 10.0], ENTRIES) == \
        pytest.approx(2.0, rel=1e-12)
    assert held_out_evidence([8.0, 25.0, 12.0], [8.0, 3000.0, 12.0], ENTRIES) == \
        pytest.approx(-2975.0 / (3020.0 / 30.0), rel=1e-12)
    assert held_out_evidence([100.0], [900.0], [10]) == 0.0


def test_held_out_modes_of_every_configuration():
    """Two configurations, modes (f residual, two shape entries): the held-out modes in
    configuration order, chi^2 = f^2 + shape^2: 4 + 400 + 441 = 845, 16 + 1600 + 1681 = 3297,
    3 entries each."""
    def ev(f, shape):
        return SimpleNamespace(frequency=np.array(f, float), shape=np.array(shape, float))

    refs = (SimpleNamespace(train=np.array([True, False, True])),
            SimpleNamespace(train=np.array([False, True])))
    evs = [ev([1.0, 2.0, 3.0], [[10, 11], [20, 21], [30, 31]]), ev([4.0, 5.0], [[40, 41], [50, 51]])]
    chi2, entries = held_out_modes(SimpleNamespace(refs=refs), evs)
    assert chi2.tolist() == [845.0, 3297.0]
    assert entries.tolist() == [3, 3]
