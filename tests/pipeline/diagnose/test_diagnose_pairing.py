"""Pairing of test with analysis modes against hand computations and the residual it minimises."""
from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr
from scipy.optimize import linear_sum_assignment

from pipeline.diagnose.evidence import Reference, evaluate, evaluate_modes
from pipeline.diagnose.pairing import (pair, pair_frequency_only, pairing_cost, report_pairing,
                                       seen_shapes)
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.correlation import mac
from tests.pipeline.diagnose.perfect_frame import perfect_reference, with_mass
from tests.pipeline.diagnose.truth import frame


def test_frequency_only_pairing_by_hand():
    assert pair_frequency_only([10.0, 20.0], [9.0, 19.5, 30.0]).tolist() == [0, 1]
    # assignment, not nearest per row: both are nearest to 19.5; 18 -> 19, 20 -> 19.5 is the
    # smallest sum of |ln| ratios (0.0541 + 0.0253 < 0.0800 + 0.0513)
    assert pair_frequency_only([18.0, 20.0], [19.0, 19.5, 60.0]).tolist() == [0, 1]
    with pytest.raises(InputError):
        pair_frequency_only([1.0, 2.0, 3.0], [1.0, 2.0])


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
    changed = with_mass(model, 3009, 0.03 * model.masses.mass.sum())
    modes, ref = perfect_reference(changed, model)
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
