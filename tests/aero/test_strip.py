"""Theodorsen strip aerodynamics: analytic limits and consistency."""
from __future__ import annotations

import numpy as np
import pytest

from aero.strip import section_gaf, strip_gaf, theodorsen
from structures.common.errors import InputError


def test_theodorsen_known_values():
    """C(0) = 1, C(inf) = 1/2 and the tabulated C(0.1) = 0.8319 - 0.1723i (BAH Table 5-2 / H&P)."""
    C = theodorsen([0.0, 0.1, 1.0, 200.0])
    assert C[0] == 1.0
    assert abs(C[1] - (0.8319 - 0.1723j)) < 2e-4
    assert abs(C[2] - (0.5394 - 0.1003j)) < 2e-4
    assert abs(C[3] - 0.5) < 2e-3


def test_theodorsen_rejects_negative_k():
    with pytest.raises(InputError, match="k = omega"):
        theodorsen([-0.1])


def test_section_quasi_steady_lift_and_moment():
    """At k = 0: lift 2 pi q c alpha, moment about the elastic axis 2 pi q c b (a + 1/2) alpha."""
    a, b = -0.2, 0.7
    Q = section_gaf(0.0, a, b)
    assert np.isclose(-Q[0, 1], 2 * np.pi * 2 * b)
    assert np.isclose(Q[1, 1], 2 * np.pi * 2 * b * b * (a + 0.5))
    assert np.allclose(Q[:, 0], 0)  # plunge displacement alone makes no steady force


def test_section_damping_sign():
    """Plunge damping: the imaginary (velocity) part of the h-h term opposes the motion."""
    Q = section_gaf(np.array([0.05, 0.5]), -0.2, 1.0)
    assert np.all(Q[:, 0, 0].imag < 0)


def test_strip_gaf_uniform_wing_equals_section_times_span():
    """A rigid uniform wing in plunge / pitch gives span x the section matrix."""
    ns, span, b = 8, 4.0, 0.5
    y = (np.arange(ns) + 0.5) * span / ns
    ds = strip_gaf(np.array([0.1, 0.4]), y=y, width=np.full(ns, span / ns), semichord=np.full(ns, b),
                   a=np.full(ns, -0.2), plunge=np.array([np.ones(ns), np.zeros(ns)]),
                   pitch=np.array([np.zeros(ns), np.ones(ns)]), refc=2 * b)
    ref = span * section_gaf(np.array([0.1, 0.4]), -0.2, b)
    np.testing.assert_allclose(ds.Q.isel(mach=0).values, ref, rtol=1e-12)
    assert ds.attrs["refc"] == 2 * b
    assert ds.Q.dims == ("mach", "k", "mode_i", "mode_j")


def test_strip_gaf_inconsistent_shapes():
    with pytest.raises(InputError, match="inconsistent strip arrays"):
        strip_gaf([0.1], y=[0, 1], width=[1], semichord=[1, 1], a=[0, 0],
                  plunge=np.ones((1, 2)), pitch=np.ones((1, 2)), refc=1.0)
