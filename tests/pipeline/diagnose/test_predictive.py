"""Held-out predictive check (pipeline.diagnose.predictive) on hand-worked per-mode tables."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from pipeline.diagnose.predictive import held_out_evidence, held_out_modes, kept_modes, reproduced

ENTRIES = np.array([10, 10, 10])     # three held-out modes, 10 entries each


def test_reproduced_at_the_goodness_of_fit_quantile():
    """chi^2_0.999 with 10 degrees of freedom is 29.588 (statistical tables)."""
    assert reproduced([29.5, 29.7], [10, 10]).tolist() == [True, False]


def test_evidence_over_modes_either_model_reproduces():
    """"none" 8, 10, 12. A fit 8, 60, 12: all kept, (30 - 80) / c: -50 with c = 1, -25 with
    c = 2. A fall 4, 5, 6: +15. A rise to 15, 17, 18 over modes still reproduced: -20."""
    none = [8.0, 10.0, 12.0]
    assert held_out_evidence(none, [8.0, 60.0, 12.0], ENTRIES, 1.0) == pytest.approx(-50.0)
    assert held_out_evidence(none, [8.0, 60.0, 12.0], ENTRIES, 2.0) == pytest.approx(-25.0)
    assert held_out_evidence(none, [4.0, 5.0, 6.0], ENTRIES, 1.0) == pytest.approx(15.0)
    assert held_out_evidence(none, [15.0, 17.0, 18.0], ENTRIES, 1.0) == pytest.approx(-20.0)


def test_evidence_is_not_capped_by_the_fit_on_the_judged_modes():
    """Two frequency-only held-out modes (1 entry each, chi^2_0.999(1) = 10.828): "none" 1, 1
    (both reproduced, kept), a fit 1e6, 1e6: (2 - 2e6) / c = -1999998 with the training
    dispersion c = 1, -499999.5 with c = 4. Divided by the fit's own dispersion on these modes
    (1e6) it would be -1.999998, never a veto."""
    none, fit, entries = [1.0, 1.0], [1e6, 1e6], [1, 1]
    assert held_out_evidence(none, fit, entries, 1.0) == pytest.approx(-1999998.0, rel=1e-12)
    assert held_out_evidence(none, fit, entries, 4.0) == pytest.approx(-499999.5, rel=1e-12)


def test_a_mode_neither_model_reproduces_is_left_out():
    """Mode 2 at 3000 ("none") and 5000 (fit), both > 29.588: left out, 20 - 18 = +2 (summed
    it would be -1998). "none" at 25 there and the fit at 3000: kept, 45 - 3020 = -2975. No
    kept mode: 0."""
    assert kept_modes([8.0, 3000.0, 12.0], [8.0, 5000.0, 10.0], ENTRIES).tolist() == \
        [True, False, True]
    assert held_out_evidence([8.0, 3000.0, 12.0], [8.0, 5000.0, 10.0], ENTRIES, 1.0) == \
        pytest.approx(2.0, rel=1e-12)
    assert kept_modes([8.0, 25.0, 12.0], [8.0, 3000.0, 12.0], ENTRIES).all()
    assert held_out_evidence([8.0, 25.0, 12.0], [8.0, 3000.0, 12.0], ENTRIES, 1.0) == \
        pytest.approx(-2975.0, rel=1e-12)
    assert held_out_evidence([100.0], [900.0], [10], 1.0) == 0.0


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


def test_a_configuration_without_held_out_modes():
    """A configuration with shapes whose two paired modes both train (none held out) adds
    nothing; the other's held-out mode: 3^2 + 1 + 4 = 14, 3 entries."""
    refs = (SimpleNamespace(train=np.array([True, True])),
            SimpleNamespace(train=np.array([True, False])))
    evs = [SimpleNamespace(frequency=np.array([1.0, 2.0]), shape=np.ones((2, 2))),
           SimpleNamespace(frequency=np.array([5.0, 3.0]), shape=np.array([[9.0, 9.0],
                                                                          [1.0, 2.0]]))]
    chi2, entries = held_out_modes(SimpleNamespace(refs=refs[:1]), evs[:1])
    assert chi2.shape == (0,) and entries.shape == (0,)
    chi2, entries = held_out_modes(SimpleNamespace(refs=refs), evs)
    assert chi2.tolist() == [14.0] and entries.tolist() == [3]
