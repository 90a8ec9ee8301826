"""Predictive check of a fitted effect on the held-out modes (issue 14, DESIGN.md section 5).

Every ``settings.holdout``-th paired mode is held out of the fits
(:func:`pipeline.diagnose.evidence.holdout_mask`). :func:`held_out_modes` gives each held-out
mode's chi^2 (frequency and shape entries on the training scales); :func:`held_out_evidence`
compares "none" and a fit on the modes that at least one of them reproduces
(:func:`kept_modes`); :func:`pipeline.diagnose.verdict.decide` vetoes a name the held-out modes
contradict.
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnose.fit_statistics import gof_limit


def held_out_modes(problem, evaluations) -> tuple:
    """chi^2 of each held-out mode: its frequency and shape entries (the training vector's
    entries and scales, :meth:`pipeline.diagnose.calibrate.Problem.vector`, on the modes no fit
    saw, ``~ref.train``; unit variance each when the model is right).

    Returns
    -------
    chi2 : (n_ho_modes,) float, in configuration order.
    entries : (n_ho_modes,) int, residual entries of each mode (1 + shape entries).
    """
    chi2, entries = [], []
    for ev, ref in zip(evaluations, problem.refs):
        f, shape = ev.frequency[~ref.train], ev.shape[~ref.train]      # (n_ho,), (n_ho, n_b)
        chi2.append(f ** 2 + np.sum(shape ** 2, axis=1))
        entries.append(np.full(len(f), 1 + shape.shape[1]))
    return np.concatenate(chi2), np.concatenate(entries).astype(int)


def held_out_evidence(none_modes, fit_modes, entries, dispersion: float) -> float:
    """Evidence of the held-out modes for a fitted effect against "none", mode by mode.

    The held-out residual entries (:func:`held_out_modes`) were fitted by neither model, so
    their chi^2 difference is -2 ln of the two fitted models' likelihood ratio on new data (no
    parameter penalty; the predictive check of cross-validation, Stone 1974). Divided by the
    round's modal dispersion c (:func:`pipeline.diagnose.verdict.round_scores`: the
    quasi-likelihood dispersion of the best fit's training modal rows, Burnham & Anderson 2002
    sec. 6.2; the held-out rows are modal rows, frequencies and shapes, with the same scales) it
    is on the scale of the BIC differences of
    :func:`pipeline.diagnose.verdict.decide`, and set by the training data alone, not by how
    well the fit predicts the modes it is judged on. That likelihood assumes each test mode is
    paired with the analysis mode it measures. A held-out mode that neither model reproduces
    within the goodness-of-fit limit of its own entries (chi^2_j > chi^2_{0.999}(m_j) for both;
    a local mode the model lacks, paired with another mode) breaks that assumption: its chi^2
    (thousands, for a joint mode paired with a bending mode) measures the mis-pairing, and a
    small shift of the wrong partner decides the sum. Such modes are left out
    (:func:`kept_modes`), as a gross outlier is by a trimmed likelihood (Huber & Ronchetti 2009
    sec. 7.9; rejection at a goodness-of-fit quantile, Hampel et al. 1986 sec. 1.4). A wrong
    effect that distorts the model predicts a held-out mode "none" reproduced badly, and that
    mode is kept. Without a kept mode the held-out modes give no evidence (0).

    Parameters
    ----------
    none_modes, fit_modes : (n_ho_modes,) float, held-out chi^2 of each mode for "none" and the
        fit (frequency and shape entries of the mode).
    entries : (n_ho_modes,) int, residual entries of each held-out mode.
    dispersion : float, the round's modal dispersion c >= 1.

    Returns
    -------
    float
        (sum_kept chi2_none - chi2_fit) / c: positive when the effect predicts the held-out
        modes better than "none", below -margin when they contradict it strongly.
    """
    none_modes, fit_modes = np.asarray(none_modes, float), np.asarray(fit_modes, float)
    kept = kept_modes(none_modes, fit_modes, entries)
    return float((none_modes[kept].sum() - fit_modes[kept].sum()) / dispersion)


def kept_modes(none_modes, fit_modes, entries) -> np.ndarray:
    """(n_ho_modes,) bool: the held-out modes "none" or the fit reproduces (:func:`reproduced`),
    the ones :func:`held_out_evidence` sums over."""
    return reproduced(none_modes, entries) | reproduced(fit_modes, entries)


def reproduced(mode_chi2, entries) -> np.ndarray:
    """(n_modes,) bool: each mode's chi^2 within the goodness-of-fit limit of its entries
    (:func:`pipeline.diagnose.fit_statistics.gof_limit` with m_j degrees of freedom)."""
    limits = np.array([gof_limit(m) for m in np.asarray(entries, int)])
    return np.asarray(mode_chi2, float) <= limits
