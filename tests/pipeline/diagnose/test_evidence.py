"""Evidence kernels of diagnose against hand computations and synthetic data of known noise."""
from __future__ import annotations

import numpy as np
import pytest

from dataclasses import replace
from types import SimpleNamespace

import xarray as xr
from scipy.optimize import linear_sum_assignment

from pipeline.diagnose.evidence import (Reference, bic, build_reference, chi_square, evaluate,
                                        evaluate_modes, gof_limit, holdout_mask, pair,
                                        pair_frequency_only, pairing_cost, partner_mixing,
                                        report_pairing, residual_basis, runs_test,
                                        seen_shapes, shape_noise, shape_residual, unit_rms)
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.correlation import mac
from structures.gvt import make_gvt_dataset
from structures.modal import compute_modes
from tests.pipeline.diagnose.test_screen import _perfect_reference, _with_mass
from tests.pipeline.diagnose.truth import frame


def test_chi_square_and_bic_by_hand():
    assert chi_square([3.0, 4.0]) == pytest.approx(25.0, rel=1e-15)
    # Schwarz 1978: chi^2 + p ln n; ln 100 = 4.605170186
    assert bic(25.0, 2, 100) == pytest.approx(25.0 + 2 * 4.605170186, rel=1e-9)
    with pytest.raises(InputError):
        bic(1.0, 1, 0)


def test_gof_limit_against_table():
    # chi-square 99.9 % quantiles (Abramowitz & Stegun table 26.8): 10 dof 29.588, 1 dof 10.828
    assert gof_limit(10) == pytest.approx(29.588, abs=1e-3)
    assert gof_limit(1) == pytest.approx(10.828, abs=1e-3)


def test_runs_test_by_hand():
    # ten + then ten -: 2 runs, mu = 2*10*10/20 + 1 = 11, var = 10*9/19, z = -9/sqrt(90/19)
    # = -4.1352, one-sided p = Phi(-4.1352) = 1.773e-5
    values = [1.0] * 10 + [-1.0] * 10
    assert runs_test(values) == pytest.approx(1.773e-5, rel=2e-3)
    assert runs_test([1.0, 2.0, 3.0]) == 1.0                  # one sign only
    assert runs_test([1.0, -1.0] * 10) > 0.01                 # alternating: many runs, not few


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


def test_frequency_only_pairing_by_hand():
    assert pair_frequency_only([10.0, 20.0], [9.0, 19.5, 30.0]).tolist() == [0, 1]
    # assignment, not nearest per row: both are nearest to 19.5; 18 -> 19, 20 -> 19.5 is the
    # smallest sum of |ln| ratios (0.0541 + 0.0253 < 0.0800 + 0.0513)
    assert pair_frequency_only([18.0, 20.0], [19.0, 19.5, 60.0]).tolist() == [0, 1]
    with pytest.raises(InputError):
        pair_frequency_only([1.0, 2.0, 3.0], [1.0, 2.0])


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


def _one_mode_reference(shape, frequency) -> Reference:
    """A test mode on three DOFs, the projector the identity, scales 0.1, sigma_f 1 %, its own
    coordinate (the first) left out."""
    shape = np.atleast_2d(np.asarray(shape, float))
    return Reference(name="hand", test_mode=np.array([7]), test_frequency=np.array([frequency]),
                     shapes=shape, sensor_index=np.arange(3), sensor_grid=np.array([1, 2, 3]),
                     sensor_component=np.array([3, 3, 3]), projector=np.eye(3),
                     shape_scale=np.full((1, 3), 0.1), shape_keep=np.array([[False, True, True]]),
                     frequency_sigma=np.array([0.01]), shape_sigma=np.array([0.05]),
                     train=np.array([True]), measured_mass={}, mass_scale={}, nmodes=2)


def test_pairing_by_likelihood_by_hand():
    """Test mode t = (1, 0, 0) at 19.5 Hz; analysis mode A = (1, 0, 0) at 10 Hz (MAC 1) and
    B = (1, 0.3, 0) at 20 Hz (MAC 1 / 1.09 = 0.917). Cost of A: shape 0 (alpha 1, d = 0),
    frequency ((10 - 19.5) / 19.5 / 0.01)^2 = 2373.4; of B: alpha = 1 / 1.09, d = (0.0826,
    -0.2752, 0), kept entries (-2.752, 0) -> 7.574, frequency (0.5 / 19.5 / 0.01)^2 = 6.575;
    14.149 in all. The MAC assignment takes A, the likelihood B."""
    ref = _one_mode_reference([1.0, 0.0, 0.0], 19.5)
    shapes = np.array([[1.0, 0.0, 0.0], [1.0, 0.3, 0.0]])
    cost = pairing_cost(ref, np.array([10.0, 20.0]), shapes)
    alpha = 1.0 / 1.09
    assert cost[0, 0] == pytest.approx((9.5 / 19.5 / 0.01) ** 2, rel=1e-12)
    assert cost[0, 1] == pytest.approx((0.3 * alpha / 0.1) ** 2 + (0.5 / 19.5 / 0.01) ** 2,
                                       rel=1e-12)
    assert np.argmax(mac(ref.shapes.T, shapes.T)[0]) == 0
    modes = xr.Dataset({"frequency": ("mode", [10.0, 20.0])},
                       coords={"rigid_motion": ("mode", ["", ""])})
    assert pair(ref, modes, sensor_shapes=shapes).tolist() == [1]
    # a mode the sensors do not see at all: alpha 0, the whole test shape is residual
    zero = pairing_cost(ref, np.array([19.5]), np.zeros((1, 3)))
    assert zero[0, 0] == pytest.approx(0.0, abs=1e-12)     # t's only entry is its own coordinate
    ref2 = replace(ref, shapes=np.array([[1.0, 0.5, 0.0]]))
    assert pairing_cost(ref2, np.array([19.5]), np.zeros((1, 3)))[0, 0] == pytest.approx(25.0)


def test_a_mode_the_sensors_do_not_see_explains_no_test_shape():
    """Test shape t = (1, 0.5, 0) at 19.5 Hz. Analysis mode A = (1, 0.4, 0) at 19.0 Hz;
    B at 19.6 Hz has a sensor shape of rounding noise (RMS 1e-12 of A's), here
    (1, 0.5, 0) 1e-12: at unit scale it would match t exactly, cost (0.1 / 19.5 / 0.01)^2 =
    0.263, and take the pairing from A, whose cost is (0.5 / 19.5 / 0.01)^2 +
    ((0.5 - 0.4 alpha) / 0.1)^2 with alpha = 1.2 / 1.16 (7.318). Seen as zero (seen_shapes),
    B explains none of t: 0.263 + (0.5 / 0.1)^2 = 25.263, and A is paired, whichever direction
    the noise has. Paired with B (a pairing held), the shape residual is t's own, (5, 0)."""
    ref = replace(_one_mode_reference([1.0, 0.0, 0.0], 19.5), shapes=np.array([[1.0, 0.5, 0.0]]))
    alpha = 1.2 / 1.16
    modes = xr.Dataset({"frequency": ("mode", [19.0, 19.6])},
                       coords={"rigid_motion": ("mode", ["", ""])})
    a = np.array([[1.0, 0.4, 0.0], [1e-12, 0.5e-12, 0.0]])
    seen = seen_shapes(a)
    assert seen[0] == pytest.approx(a[0], abs=0.0) and not seen[1].any()
    assert seen_shapes(a * [[1.0], [1e6]])[1] == pytest.approx(a[1] * 1e6, rel=1e-15)  # 1e-6
    assert pairing_cost(ref, [19.0, 19.6], a / np.linalg.norm(a, axis=1, keepdims=True))[0, 1] \
        == pytest.approx((0.1 / 19.5 / 0.01) ** 2, rel=1e-9)
    cost = pairing_cost(ref, [19.0, 19.6], seen)
    assert cost[0] == pytest.approx([(0.5 / 19.5 / 0.01) ** 2 + ((0.5 - 0.4 * alpha) / 0.1) ** 2,
                                     (0.1 / 19.5 / 0.01) ** 2 + 25.0], rel=1e-12)
    turned = np.array([[1.0, 0.4, 0.0], [0.3e-12, -1e-12, 0.2e-12]])       # other rounding
    props = SimpleNamespace(as_dict=dict)                                  # nothing weighed
    for shapes in (a, turned):
        assert pair(ref, modes, sensor_shapes=shapes).tolist() == [0]
        assert evaluate_modes(ref, [19.0, 19.6], shapes, props, modes=modes).paired.tolist() == [0]
        held = evaluate_modes(ref, [19.0, 19.6], shapes, props, modes=modes, paired=[1])
        assert held.shape[0] == pytest.approx([5.0, 0.0], abs=1e-12)


@pytest.fixture(scope="module")
def frame_case(tmp_path_factory):
    model = read_model(frame.write_frame(tmp_path_factory.mktemp("frame")))
    changed = _with_mass(model, 3009, 0.03 * model.masses.mass.sum())
    modes, ref = _perfect_reference(changed, model)
    return model, changed, ref


def test_pairing_cost_is_the_residual_and_the_pairing_its_minimum(frame_case):
    """On the frame against a test of the frame with 3 % of its mass added at a wing grid: the
    cost of the chosen pairing is every test mode's chi^2 (frequency and shape entries of
    evaluate) to round-off, and no other assignment gives less: the MAC assignment and every
    swap of two test modes' partners cost at least as much.

    Round-off: pairing_cost expands sum w (u - alpha v)^2 into three sums that cancel, so its
    error scales with the largest, sum w u^2 (1283 here), not with the chi^2 left (1e-28 for
    the perfect model): one CI machine gave 1.1e-12 = 9e-16 of it. Allowed: relative 1e-10 of
    the chi^2 plus 1e-13 of the cancelled sum."""
    model, changed, ref = frame_case
    cancelled = np.sum(ref.shape_keep * (ref.shapes @ ref.projector.T) ** 2
                       / ref.shape_scale ** 2, axis=1)                     # (n_test,)
    for m in (model, changed):
        ev = evaluate(ref, m)
        modes = ev.modes
        elastic = np.flatnonzero(modes["rigid_motion"].values == "")
        seen = modes["shape"].values[:, ref.sensor_index]
        cost = pairing_cost(ref, modes["frequency"].values[elastic], seen[elastic])
        col = np.searchsorted(elastic, ev.paired)
        per_mode = ev.frequency ** 2 + np.sum(ev.shape ** 2, axis=1)
        np.testing.assert_array_less(np.abs(cost[np.arange(col.size), col] - per_mode),
                                     1e-10 * per_mode + 1e-13 * cancelled)
        total = per_mode.sum()
        tol = 1e-10 * total + 1e-13 * cancelled.sum()
        rows, best = linear_sum_assignment(cost)
        assert abs(cost[rows, best].sum() - total) <= tol
        by_mac = linear_sum_assignment(mac(ref.shapes.T, seen[elastic].T), maximize=True)[1]
        mac_ev = evaluate_modes(ref, modes["frequency"].values, seen, ev.props,
                                paired=elastic[by_mac])
        assert np.sum(mac_ev.frequency ** 2) + np.sum(mac_ev.shape ** 2) >= total - tol
        for i in range(col.size - 1):
            swapped = col.copy()
            swapped[[i, i + 1]] = swapped[[i + 1, i]]
            assert cost[np.arange(col.size), swapped].sum() >= total - tol


def test_report_pairing_by_hand():
    """Test modes t1 = (1, 0, 0) at 10 Hz and t2 = (0, 1, 0) at 20 Hz, shape noise 5 % on three
    DOFs (n / sigma^2 = 1200), sigma_f 1 %; analysis modes A = (1, 0, 0) and B = (0.1, 1, 0).
    A at 10.1 Hz, B at 20.2 Hz: the MAC pairing (t1-A, t2-B), cost 1 + 0 + 1 + 1200 (1 - 1 / 1.01)
    = 13.9. A at 20.2 Hz, B at 10.1 Hz: the MAC pairing costs 102^2 + 0 + 49.5^2
    + 11.9 = 12866, the crossed one 1 + 1200 (1 - 0.01 / 1.01) + 1 + 1200 = 2390: on three
    DOFs the shapes tell the modes apart less than a 50 % frequency error does (on 120 DOFs
    the same MACs would weigh 40 times more)."""
    ref = replace(_one_mode_reference([1.0, 0.0, 0.0], 10.0),
                  test_mode=np.array([7, 8]), test_frequency=np.array([10.0, 20.0]),
                  shapes=np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
                  frequency_sigma=np.array([0.01, 0.01]), shape_sigma=np.array([0.05, 0.05]),
                  train=np.array([True, True]))
    shapes = np.array([[1.0, 0.0, 0.0], [0.1, 1.0, 0.0]])
    for freq, want in (([10.1, 20.2], [0, 1]), ([20.2, 10.1], [1, 0])):
        modes = xr.Dataset({"frequency": ("mode", freq)},
                           coords={"rigid_motion": ("mode", ["", ""])})
        assert report_pairing(ref, modes, sensor_shapes=shapes).tolist() == want
