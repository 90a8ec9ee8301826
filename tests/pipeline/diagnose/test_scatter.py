"""The nominal scatter: per-quantity group matrices (Euler's theorem on the element matrices),
the first-order residual rows against exact reanalysis of a perturbed truth, and the whitening
of their covariance by hand and by sampling."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pipeline.diagnose.evidence import build_reference, evaluate
from pipeline.diagnose.scatter import (FIRST_ORDER_FLOOR, group_matrices, scatter_effects,
                                       scatter_scales, whitening)
from structures.bdf import read_model
from structures.gvt import make_gvt_dataset
from structures.modal import compute_modes
from structures.model import Property
from tests.pipeline.diagnose.truth import frame


@pytest.fixture(scope="module")
def frame_model(tmp_path_factory):
    return read_model(frame.write_frame(tmp_path_factory.mktemp("frame")))


def test_single_spring_mass(tmp_path):
    """One DOF: a CELAS2 (no property card: the spring scatters as a whole) and a CONM2 each
    err by s: df/f = (dk/k - dm/m) / 2, standard deviation s / sqrt(2)."""
    deck = tmp_path / "sdof.bdf"
    deck.write_text("GRID,1,,0.,0.,0.,,23456\nCELAS2,1,400.,1,1\nCONM2,2,1,,4.\nENDDATA\n")
    model = read_model(deck)
    modes = compute_modes(model, 1)
    lam = (2 * np.pi * modes["frequency"].values) ** 2
    assert lam[0] == pytest.approx(100.0, rel=1e-10)
    d_freq, d_mix = scatter_effects(model, modes["shape"].values.T, lam, np.array([0]))
    assert np.sort(d_freq[:, 0]) == pytest.approx([-0.5, 0.5], rel=1e-10)
    freq, mixing = scatter_scales(d_freq, d_mix, 0.03)
    assert freq[0] == pytest.approx(0.03 / np.sqrt(2.0), rel=1e-10)
    assert mixing.shape == (1, 1) and mixing[0, 0] == 1.0                 # own coordinate: cap


def test_groups_sum_to_the_modal_matrices(frame_model):
    """A beam's K and M without shear flexibility or NSM are homogeneous of degree one in
    (A, I1, I2, J) (Euler's theorem: sum_q q dK/dq = K), a CONM2's mass matrix in its mass: the
    groups' modal matrices sum to phi^T K phi = Lambda and phi^T M phi = I."""
    modes = compute_modes(frame_model, 20)
    bk, bm, labels = group_matrices(frame_model, modes["shape"].values.T)
    lam = (2 * np.pi * modes["frequency"].values) ** 2
    np.testing.assert_allclose(bk.sum(axis=0), np.diag(lam), atol=1e-9 * lam.max())
    np.testing.assert_allclose(bm.sum(axis=0), np.eye(20), atol=1e-9)
    pbar = [pid for pid, p in frame_model.properties.items() if p.card == "PBAR"]
    assert {(card, pid, q) for card, pid, q in labels if card == "PBAR"} == \
        {("PBAR", pid, q) for pid in pbar for q in ("A", "I1", "I2", "J")}
    assert sum(card == "CONM2" for card, _, _ in labels) == len(frame_model.masses.eids)


def test_rows_predict_the_residual_of_a_perturbed_truth(frame_model):
    """A truth whose PBAR I1 differs by eps from the model's: the model's residual entries
    (exact reanalysis, the test shapes' signs free) equal the group's row times eps / s to first
    order: the frequencies to 0.1 %, the shape coordinates (their signs agreeing with the
    frequencies') to 2 % of the largest, the 46 computed modes leaving out the higher ones."""
    pid = sorted(p for p, prop in frame_model.properties.items() if prop.card == "PBAR")[0]
    prop = frame_model.properties[pid]
    eps, s = 1e-4, 0.03
    truth = replace(frame_model, properties={**frame_model.properties, pid: Property(
        pid, prop.card, {**prop.fields, "I1": prop.fields["I1"] * (1.0 + eps)})})
    truth_modes = compute_modes(truth, 46)
    grid, comp = np.array(frame.sensors()).T
    dof = np.array([np.flatnonzero((truth_modes["grid"].values == g)
                                   & (truth_modes["component"].values == c))[0]
                    for g, c in zip(grid, comp)])
    flip = np.where(np.arange(20) % 2, -1.0, 1.0)[:, None]                 # test signs free
    gvt = make_gvt_dataset(truth_modes["frequency"].values[6:26],
                           flip * truth_modes["shape"].values[6:26][:, dof], grid, comp,
                           mode=np.arange(7, 27))
    modes = compute_modes(frame_model, 46)
    ref, _ = build_reference("frame", frame_model, gvt, None, modes, frequency_noise=0.01,
                             shape_noise_value=0.05, model_scatter=s, holdout=3, nmodes=46)
    ev = evaluate(ref, frame_model, modes)
    r = np.concatenate([ev.frequency[ref.train], ev.shape[ref.train].ravel()])
    labels = group_matrices(frame_model, modes["shape"].values[:2].T)[2]
    row = ref.scatter_rows[:, labels.index(("PBAR", pid, "I1"))] * eps / s
    first = np.all(np.isfinite(ref.scatter_rows), axis=1) & \
        (np.sum(ref.scatter_rows ** 2, axis=1) <= 1.0 - FIRST_ORDER_FLOOR)
    n_f = int(ref.train.sum())
    np.testing.assert_allclose(r[:n_f], row[:n_f], rtol=1e-3, atol=1e-3 * np.abs(row[:n_f]).max())
    shape = first & (np.arange(r.size) >= n_f)
    assert shape.sum() > 300
    assert np.abs(r[shape] - row[shape]).max() < 0.02 * np.abs(row[shape]).max()
    assert np.corrcoef(r[shape], row[shape])[0, 1] > 0.999


def test_whitening_by_hand():
    """W (Delta + G G^T) W^T = I with Delta_i = 1 - |G_i|^2; a row beyond first order (|G_i|^2
    above 1 - FIRST_ORDER_FLOOR, or not finite) is left independent with unit variance."""
    rng = np.random.default_rng(3)
    g = rng.standard_normal((12, 5))
    g *= np.sqrt(rng.uniform(0.1, 0.9, 12) / np.sum(g ** 2, axis=1))[:, None]
    g[4] *= np.sqrt(1.2 / np.sum(g[4] ** 2))                               # beyond first order
    g[7, 2] = np.inf                                                        # degenerate modes
    w = whitening(g)
    kept = np.ones(12, bool)
    kept[[4, 7]] = False
    g0 = np.where(kept[:, None], g, 0.0)
    cov = np.diag(1.0 - np.sum(g0 ** 2, axis=1)) + g0 @ g0.T
    np.testing.assert_allclose(w @ cov @ w.T, np.eye(12), atol=1e-12)
    np.testing.assert_allclose(w[4], np.eye(12)[4], atol=1e-12)
    independent = whitening(np.zeros((4, 3)))
    np.testing.assert_array_equal(independent, np.eye(4))


def test_whitened_chi_square_of_sampled_scatter():
    """Residuals drawn as G e + sqrt(Delta) n (e, n standard normal): |W r|^2 follows chi^2 with
    n_rows degrees of freedom (mean 40, variance 80), while the unwhitened |r|^2 does not (its
    variance is inflated by the common errors)."""
    rng = np.random.default_rng(11)
    g = rng.standard_normal((40, 3))
    g *= 0.9 / np.linalg.norm(g, axis=1, keepdims=True)                    # 81 % scatter
    w = whitening(g)
    n = 4000
    r = (g @ rng.standard_normal((3, n))
         + np.sqrt(1.0 - 0.81) * rng.standard_normal((40, n)))
    white = np.sum((w @ r) ** 2, axis=0)
    assert np.mean(white) == pytest.approx(40.0, abs=4 * np.sqrt(80.0 / n))
    assert np.var(white) == pytest.approx(80.0, rel=0.15)
    assert np.var(np.sum(r ** 2, axis=0)) > 3 * 80.0
