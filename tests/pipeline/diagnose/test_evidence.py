"""Evidence kernels of diagnose against hand computations and synthetic data of known noise."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from pipeline.diagnose.apply import apply_effect
from pipeline.diagnose.effects import candidates, directional
from pipeline.diagnose.evidence import (build_reference, evaluate, holdout_mask, partner_mixing,
                                        residual_basis, shape_noise, shape_residual, unit_rms)
from structures.assembly import assemble
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.gvt import make_gvt_dataset
from structures.modal import compute_modes
from structures.singularity import SingularityWarning


def test_holdout_split():
    assert holdout_mask(7, 3).tolist() == [False, False, True, False, False, True, False]
    assert holdout_mask(4, 2).tolist() == [False, True, False, True]
    # the second and third configurations: rotated by one position each
    assert holdout_mask(7, 3, 1).tolist() == [False, True, False, False, True, False, False]
    assert holdout_mask(7, 3, 2).tolist() == [True, False, False, True, False, False, True]
    assert holdout_mask(7, 3, 3).tolist() == holdout_mask(7, 3).tolist()
    with pytest.raises(InputError, match="holdout"):
        holdout_mask(5, 1)


def test_shape_noise_recovers_known_sigma():
    rng = np.random.default_rng(7)
    n_dof, m, n_mode, sigma = 120, 30, 20, 0.05
    phi = rng.standard_normal((n_dof, m))
    clean = unit_rms((phi @ rng.standard_normal((m, n_mode))).T)
    noisy = clean + sigma * rng.standard_normal(clean.shape)
    est = shape_noise(phi, noisy)
    # per mode 90 DOFs outside the span: relative standard error ~ 1/sqrt(2*90) = 7.5 %
    assert np.median(est) == pytest.approx(sigma, rel=0.08)
    assert np.all(np.abs(est / sigma - 1.0) < 0.3)
    with pytest.raises(InputError):
        shape_noise(phi[:30], noisy[:, :30])


def test_shape_residual_by_hand():
    # basis = identity on 3 DOFs (projector = I); test t = (1, 0.2, 0); analysis a = (2, 0, 0)
    # alpha = a.t / a.a = 0.5; d = t - alpha a = (0, 0.2, 0); entries / scale 0.1 -> (0, 2, 0)
    proj = np.eye(3)
    t = np.array([[1.0, 0.2, 0.0]])
    keep = np.array([[False, True, True]])                    # own coordinate left out
    r = shape_residual(proj, t, np.array([[2.0, 0.0, 0.0]]), np.full((1, 3), 0.1), keep)
    assert r.shape == (1, 2)
    assert r[0] == pytest.approx([2.0, 0.0], abs=1e-14)
    r_neg = shape_residual(proj, t, np.array([[-3.0, 0.0, 0.0]]), np.full((1, 3), 0.1), keep)
    assert r_neg == pytest.approx(r, abs=1e-14)               # the analysis shape's sign is free
    r_flip = shape_residual(proj, -t, np.array([[2.0, 0.0, 0.0]]), np.full((1, 3), 0.1), keep)
    assert r_flip == pytest.approx(r, abs=1e-14)              # and the test shape's



def test_residual_basis_by_hand():
    """Positions 0-1 rigid, 2-7 elastic at 1, 2, 2.05, 3, 3.2, 10 Hz, 12 sensor DOFs; paired 2
    and 5, highest test frequency 3 Hz (band to 3.3 Hz): mode 3 joins (a shape of its own),
    mode 4 does not (mode 3's shape plus 1e-3: 99.9 % of it in the span), mode 6 does not (the
    sensors do not see it), mode 7 is above the band. With 8 DOFs A0 may have 8 - MIN_NOISE_DOF
    = 3 columns, fewer than the rigid and paired modes (always in): nothing joins."""
    rng = np.random.default_rng(0)
    shapes = rng.standard_normal((8, 12))
    shapes[4] = shapes[3] + 1e-3 * rng.standard_normal(12)
    shapes[6] *= 1e-9
    frequency = np.array([0.0, 0.0, 1.0, 2.0, 2.05, 3.0, 3.2, 10.0])
    basis = residual_basis(frequency, shapes, [0, 1], np.arange(2, 8), [5, 2], 3.0)
    np.testing.assert_array_equal(basis, [2, 3, 5])
    narrow = residual_basis(frequency, shapes[:, :8], [0, 1], np.arange(2, 8), [5, 2], 3.0)
    np.testing.assert_array_equal(narrow, [2, 5])


def test_partner_mixing_by_hand():
    """Band modes at 10, 10.2 and 15 Hz, each frequency known to 1 % (partners within 3 %):
    the test mode at 10.1 Hz may be either of the first two (the largest of their rows; its
    pairing with mode 0 alone would give row 0), the one at 15 Hz only the third."""
    mixing = np.array([[1.0, 0.2, 0.01, 0.3],
                       [0.1, 1.0, 0.05, 0.02],
                       [0.01, 0.03, 1.0, 0.4]])
    out = partner_mixing([10.1, 15.0], [10.0, 10.2, 15.0], [0.01, 0.01, 0.01], [0, 2], mixing)
    np.testing.assert_array_equal(out, [[1.0, 1.0, 0.05, 0.3], mixing[2]])
    far = partner_mixing([10.1, 15.0], [10.0, 10.2, 15.0], [0.001, 0.001, 0.001], [0, 2], mixing)
    np.testing.assert_array_equal(far, mixing[[0, 2]])


def test_self_orthogonality_of_mixed_modes_in_the_analysis_mass(tmp_path):
    """Test shapes psi_1 = cos(a) phi_1 + sin(a) phi_2 and psi_2 = phi_2 of mass-normalised modes:
    psi_1^T M psi_2 / sqrt(psi_1^T M psi_1 psi_2^T M psi_2) = sin(a) by hand, whatever the
    modes' amplitudes at the sensors (masses 1, 2, 3 give modes of different RMS)."""
    deck = tmp_path / "chain.bdf"
    deck.write_text("GRID,1,,0.,0.,0.,,23456\nGRID,2,,1.,0.,0.,,23456\nGRID,3,,2.,0.,0.,,23456\n"
                    "CELAS2,1,400.,1,1\nCELAS2,2,300.,1,1,2,1\nCELAS2,3,200.,2,1,3,1\n"
                    "CONM2,4,1,,1.\nCONM2,5,2,,2.\nCONM2,6,3,,3.\nENDDATA\n")
    model = read_model(deck)
    modes = compute_modes(model, 3)
    x = np.flatnonzero(modes["component"].values == 1)
    phi = modes["shape"].values[:2][:, x]
    rms = np.sqrt(np.mean(phi ** 2, axis=1))
    assert abs(rms[0] / rms[1] - 1.0) > 0.1                  # unit-RMS columns would differ
    a = 0.3
    shapes = np.array([np.cos(a) * phi[0] + np.sin(a) * phi[1], phi[1]])
    gvt = make_gvt_dataset(modes["frequency"].values[:2], shapes, modes["grid"].values[x],
                           modes["component"].values[x], mode=[1, 2])
    _, facts = build_reference("chain", model, gvt, None, modes, frequency_noise=0.01,
                               shape_noise_value=0.02, model_scatter=0.03, holdout=3, nmodes=3)
    assert facts["paired_fe_mode"] == [1, 2]
    assert facts["self_orthogonality"] == pytest.approx(np.sin(a), rel=1e-8)   # 0.29552


def test_a_candidates_singularities_are_not_warned_under_the_users_deck(frame_reference):
    """A candidate keeps the user's file name but not the user's stiffness: the frame's joint
    RBE2 7201 as a CBUSH nearly free in two rotations has a singularity table (warned by a plain
    assembly), which evaluating the candidate does not warn of (preflight warned of the deck's)."""
    model, _, ref = frame_reference
    joint = next(c for c in candidates(model, ("joint_flexibility",))
                 if c.label == "RBE2 7201 (5001-5002)")
    detailed, _ = directional(joint, [1.0, 0.0])
    changed = apply_effect(model, detailed, [1.0, 1.0, 1.0, 1e-6, 1e3, 1e3])
    with pytest.warns(SingularityWarning, match="frame.bdf: grid point singularities"):
        assemble(changed)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SingularityWarning)
        result = evaluate(ref, changed)
    assert np.all(np.isfinite(result.frequency))
