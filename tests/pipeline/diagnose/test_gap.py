"""Gap metrics of diagnose (pipeline.diagnose.gap) against hand values."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

from pipeline.diagnose.gap import gap_metrics


def test_held_out_cross_orthogonality_and_mac_by_hand():
    """Three elastic modes, identity shapes at three sensors. Test mode 2 (held out) is
    cos(a) phi_2 + sin(a) phi_3, test mode 3 (training) cos(b) phi_3 + sin(b) phi_1, b > a: the
    largest off-diagonal cross-orthogonality is sin(b) over all rows, sin(a) over the held-out row;
    MAC min cos^2(b) over all, cos^2(a) held out. The gap pairs as a report does (mode k with
    test mode k here), whatever pairing the fit used (``paired``: modes 2 and 3 swapped)."""
    a, b = 0.2, 0.5
    shapes = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(a), np.sin(a)],
                       [np.sin(b), 0.0, np.cos(b)]])
    f_test = np.array([10.0, 20.0, 30.0])
    modes = xr.Dataset({"shape": (("mode", "dof"), np.eye(3)),
                        "frequency": ("mode", f_test * np.array([1.01, 0.98, 1.005]))},
                       coords={"mode": [1, 2, 3]})
    ref = SimpleNamespace(frequency_sigma=np.full(3, 0.01), train=np.array([True, False, True]),
                          has_shapes=True, sensor_index=np.arange(3), shapes=shapes,
                          measured_mass={}, name="c", test_frequency=f_test,
                          shape_sigma=np.full(3, 0.05))
    ev = SimpleNamespace(modes=modes, paired=np.array([0, 2, 1]), props=None)
    gap = gap_metrics(SimpleNamespace(refs=(ref,)), [ev])
    assert gap["max_cross_orthogonality_offdiag"] == pytest.approx(np.sin(b), rel=1e-12)
    assert gap["max_cross_orthogonality_offdiag_held_out"] == pytest.approx(np.sin(a), rel=1e-12)
    assert gap["mac_min"] == pytest.approx(np.cos(b) ** 2, rel=1e-12)
    assert gap["mac_min_held_out"] == pytest.approx(np.cos(a) ** 2, rel=1e-12)
    # frequency errors 1, -2, 0.5 % -> held-out RMS 2 %, all sqrt(5.25 / 3) %
    assert gap["frequency_rms_held_out"] == pytest.approx(2.0, rel=1e-12)
    assert gap["frequency_rms"] == pytest.approx(np.sqrt(5.25 / 3.0), rel=1e-10)

