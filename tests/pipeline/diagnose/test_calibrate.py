"""Nominal calibration of diagnose (pipeline.diagnose.calibrate): model-form flags."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from pipeline.diagnose.calibrate import calibrate
from pipeline.diagnose.evidence import holdout_mask, runs_test


def test_calibration_runs_test_sees_the_training_modes_only():
    """30 modes, every third held out. Training residuals +1 (first ten) then -1 (last ten): two
    runs in 20, p = 1.8e-5, flagged. The held-out modes carry the opposite sign of their
    neighbours: with them the sequence has 20 runs (p > 0.01), so a flag proves that the
    held-out modes were left out."""
    held = holdout_mask(30, 3)
    train = ~held
    v = np.where(np.arange(30) < 15, 1.0, -1.0)
    v[held] *= -1.0
    assert runs_test(v) > 0.01 and runs_test(v[train]) < 1e-4

    def evaluate(theta, effects=()):
        r = v + theta[0]
        return [SimpleNamespace(frequency=r, vector=lambda keep, r=r: r[keep])]

    ref = SimpleNamespace(train=train, name="c")
    problem = SimpleNamespace(n_theta=1, names=("E1",), refs=(ref,), evaluate=evaluate,
                              vector=lambda evs: evs[0].vector(train))
    cal = calibrate(problem)
    assert abs(cal.theta[0]) < 1e-6                       # ten +1, ten -1: no shift
    assert any("runs test" in flag for flag in cal.flags)
