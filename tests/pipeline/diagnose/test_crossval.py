"""The cross-validated gap (pipeline.diagnose.crossval): the splits hold every paired mode out
once, a split's residual is the one the preflight builds for that rotation, and the pooled
measures by hand. The workflow's use of it, on noise-free data whose effect is exact, is in
tests/pipeline/test_cmd_diagnose.py."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from pipeline.diagnose import crossval
from pipeline.diagnose.calibrate import Problem
from pipeline.diagnose.crossval import (Split, Support, cross_validated_note, extend, pooled,
                                        rotated, stable)
from pipeline.diagnose.evidence import build_reference
from structures.bdf import read_model
from structures.gvt import make_gvt_dataset
from structures.modal import compute_modes
from tests.pipeline.chain_deck import chain_deck


def _reference(model, modes, rotation: int):
    """The chain's 12 elastic modes at every translational DOF as its own test, scatter 3 %."""
    pick = modes.isel(dof=np.nonzero(modes["component"].values <= 3)[0]).sel(mode=range(7, 19))
    gvt = make_gvt_dataset(pick["frequency"].values, pick["shape"].values, pick["grid"].values,
                           pick["component"].values, mode=list(range(1, 13)))
    ref, _ = build_reference(f"c{rotation}", model, gvt, None, modes, frequency_noise=0.01,
                             shape_noise_value=0.05, model_scatter=0.03, holdout=3, nmodes=18,
                             rotation=rotation)
    return ref


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    deck = tmp_path_factory.mktemp("chain") / "chain.bdf"
    chain_deck(deck)
    model = read_model(deck)
    return model, compute_modes(model, 18)


def test_splits_hold_out_every_mode_once_with_the_preflights_residual(chain):
    """Two configurations (rotations 0 and 1, as the preflight numbers them), holdout 3: over
    shifts 0, 1, 2 every mode of each configuration is held out exactly once, and the split at
    shift s carries the scatter rows and whitening that build_reference gives rotation i + s
    itself (an independent path: the derivatives computed again)."""
    model, modes = chain
    refs = (_reference(model, modes, 0), _reference(model, modes, 1))
    problem = Problem.build(refs, (model, model), 0.03)
    held = np.zeros((2, 12), int)
    for shift in range(3):
        split = rotated(problem, 3, shift)
        assert split.names == problem.names and split.models == problem.models
        for i, ref in enumerate(split.refs):
            held[i] += ~ref.train
            direct = _reference(model, modes, i + shift)
            np.testing.assert_array_equal(ref.train, direct.train)
            np.testing.assert_allclose(ref.scatter_rows, direct.scatter_rows, rtol=1e-12,
                                       atol=1e-14)
            np.testing.assert_allclose(ref.whitening, direct.whitening, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(held, 1)
    assert rotated(problem, 3, 0).refs[1].train.tolist() == refs[1].train.tolist()


def _gap(n, rms, expected, cross, mac):
    return {"n_held_out": n, "frequency_rms_held_out": rms,
            "frequency_rms_held_out_expected": expected,
            "max_cross_orthogonality_offdiag_held_out": cross, "mac_min_held_out": mac}


def test_pooled_by_hand():
    """Splits of 6, 7 and 7 modes at RMS 1, 2 and 3 %: sqrt((6 + 7 * 4 + 7 * 9) / 20) =
    sqrt(4.85) = 2.2023 %; the off-diagonal the largest, the MAC the smallest; a split without
    held-out modes does not count, nor a None (no shapes)."""
    gaps = [_gap(6, 1.0, 1.5, 0.2, 0.95), _gap(7, 2.0, 1.5, 0.6, 0.90),
            _gap(7, 3.0, 1.5, None, None), _gap(0, None, None, None, None)]
    out = pooled(gaps)
    assert out["frequency_rms_cross_validated"] == pytest.approx(np.sqrt(4.85), rel=1e-12)
    assert out["frequency_rms_cross_validated"] == pytest.approx(2.2023, abs=1e-4)
    assert out["frequency_rms_cross_validated_expected"] == pytest.approx(1.5, rel=1e-12)
    assert out["n_cross_validated"] == 20
    assert out["max_cross_orthogonality_offdiag_cross_validated"] == 0.6
    assert out["mac_min_cross_validated"] == 0.90
    none = pooled([_gap(0, None, None, None, None)])
    assert none["frequency_rms_cross_validated"] is None and none["n_cross_validated"] == 0
    note = cross_validated_note(pooled(gaps[:2]), out, 3)
    # before: sqrt((6 + 7 * 4) / 13) = 1.617 %
    assert "1.62 -> 2.20 % over 20 modes" in note and "0.600 -> 0.600" in note


def _supports(*gains):
    return [Support(i + 1, g, np.zeros(1), 0.0) for i, g in enumerate(gains)]


@pytest.mark.parametrize("holdout, gains, kept", [
    (3, (5.0, -1.0), True),          # the naming split and one other: 2 of 3
    (3, (-9.5, -9.5), False),        # the naming split alone: 1 of 3 (the wing box's seed 1)
    (3, (0.0, 0.0), False),          # no gain is no support
    (2, (0.1,), True), (2, (-0.1,), False),
    (4, (1.0, -1.0, -1.0), False),   # 2 of 4 is no majority
    (4, (1.0, 1.0, -1.0), True)])
def test_stable_is_a_majority_of_the_splits(holdout, gains, kept):
    assert stable(_supports(*gains), holdout) is kept


class _Rows:
    """A problem whose training residual is the evaluations themselves, rows 0-1 modal."""

    def residual(self, theta, evaluations):
        return np.asarray(evaluations, float)

    def modal_rows(self):
        return np.array([True, True, False])


@pytest.mark.parametrize("after, c, kept", [
    ((0.0, 0.0, 0.0), 1.0, True),      # gain 3^2 + 4^2 - 1 ln 3 = 23.90
    ((3.0, 4.0, 0.0), 1.0, False),     # no change: gain -ln 3
    ((0.0, 0.0, 0.0), 25.0, False),    # modal rows at dispersion 25: gain 1 - ln 3 = -0.10
    ((3.0, 4.0, 0.5), 25.0, False)])   # a stated row worse
def test_extend_keeps_the_effect_where_the_split_wants_it(monkeypatch, after, c, kept):
    """The split's gain by hand (chi2_modal / c + chi2_stated, one parameter at n = 3); a split
    that does not gain goes on as it was (module docstring), its refit still reported."""
    fit = SimpleNamespace(theta=np.ones(1), evaluations=np.array(after), values=np.array([0.5]))
    monkeypatch.setattr(crossval, "continued", lambda *args, **kwargs: fit)
    # one held-out mode of one entry, its chi^2 the square of evaluation 0 (3^2 = 9 before,
    # within chi^2_0.999(1) = 10.8, so kept)
    monkeypatch.setattr(crossval, "held_out_modes",
                        lambda problem, evaluations: (np.array([evaluations[0] ** 2]),
                                                      np.array([1])))
    split = Split(1, _Rows(), SimpleNamespace(n_data=3, jacobian=None), {}, (), np.zeros(1),
                  np.array([3.0, 4.0, 0.0]))
    candidate = SimpleNamespace(parameters=("mass",))
    out, support = extend(split, candidate, np.array([0.4]), c)
    before = 25.0 / c
    gain = before - (after[0] ** 2 + after[1] ** 2) / c - after[2] ** 2 - np.log(3.0)
    assert support.gain == pytest.approx(gain, rel=1e-12)
    assert bool(gain > 0) is kept
    assert support.shift == 1 and support.values.tolist() == [0.5]
    assert support.evidence == pytest.approx((9.0 - after[0] ** 2) / c, rel=1e-12)
    if kept:
        assert out.effects == ((candidate, fit.values),) and out.theta.tolist() == [1.0]
    else:
        assert out is split
