"""The weighing's reference sizes, stated accuracies and residual against hand computations."""
from __future__ import annotations

import numpy as np
import pytest

from pipeline.diagnose.weighing import mass_residual, mass_scales
from structures.massprops import MassProperties


def test_mass_scales_and_residual_by_hand():
    measured = {"weight": 100.0, "x_cg": 2.0, "Ixx": 50.0, "Iyy": 200.0, "Izz": 220.0, "Ixy": 1.0}
    props = MassProperties(mass=101.0, cg=np.array([2.01, 0.0, 0.0]),
                           inertia=np.diag([51.0, 200.0, 220.0]) - np.array(
                               [[0, 1.0, 0], [1.0, 0, 0], [0, 0, 0]]),
                           rigid_body_mass=np.eye(6), reference_point=np.zeros(3))
    scales = mass_scales(measured, props)
    assert scales["weight"] == pytest.approx(0.5)             # 0.5 % of 100
    assert scales["Ixx"] == pytest.approx(1.0)                # 2 % of 50
    assert scales["Ixy"] == pytest.approx(4.4)                # 2 % of the largest moment 220
    assert scales["x_cg"] == pytest.approx(0.005 * np.sqrt(220.0 / 100.0))
    r = mass_residual(props, measured, scales)
    expected = [1.0 / 0.5, 0.01 / scales["x_cg"], 1.0 / 1.0, 0.0, 0.0, 0.0]
    assert r == pytest.approx(expected, abs=1e-12)
    # a CG without weight and inertias: the model's radius of gyration sqrt(220 / 101)
    alone = mass_scales({"x_cg": 2.0}, props)
    assert alone["x_cg"] == pytest.approx(0.005 * np.sqrt(220.0 / 101.0), rel=1e-12)
