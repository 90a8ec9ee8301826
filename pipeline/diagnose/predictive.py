"""Predictive check of a fitted effect on the held-out modes (issue 14, DESIGN.md section 5).

Every ``settings.holdout``-th paired mode is held out of the fits
(:func:`pipeline.diagnose.evidence.holdout_mask`). :func:`held_out_modes` gives each held-out
mode's chi^2 (frequency and shape entries on the training scales); :func:`held_out_evidence`
compares "none" and a fit on the modes that at least one of them reproduces
(:func:`reproduced`); :func:`pipeline.diagnose.workflow.decide` vetoes a name the held-out modes
contradict.
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnose.evidence import gof_limit


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
        f, shape = ev.frequency[~ref.train], ev.shape[~ref.train]
        chi2.append(f ** 2 + np.sum(np.reshape(shape, (len(f), -1)) ** 2, axis=1))
        entries.append(np.full(len(f), 1 + np.reshape(shape, (len(f), -1)).shape[1]))
    return np.concatenate(chi2), np.concatenate(entries).astype(int)


def held_out_evidence(none_modes, fit_modes, entries) -> float:
    """Evidence of the held-out modes for a fitted effect against "none", mode by mode.

    The held-out residual entries (:func:`held_out_modes`) were fitted by neither model, so
    their chi^2 difference is -2 ln of the two fitted models' likelihood ratio on new data (no
    parameter penalty; the predictive check of cross-validation, Stone 1974), on the scale of the
    BIC differences of :func:`decide`. That likelihood assumes each test mode is paired with the
    analysis mode it measures. A held-out mode that neither model reproduces within the
    goodness-of-fit limit of its own entries (chi^2_j > chi^2_{0.999}(m_j) for both; a local mode
    the model lacks, paired with another mode) breaks that assumption: its chi^2 (thousands, for
    a joint mode paired with a bending mode) measures the mis-pairing, and a small shift of the
    wrong partner decides the sum. Such modes are left out, as a gross outlier is by a trimmed
    likelihood (Huber & Ronchetti 2009 sec. 7.9; rejection at a goodness-of-fit quantile,
    Hampel et al. 1986 sec. 1.4): the evidence is the difference summed over the modes that at
    least one model reproduces, divided by the fit's dispersion on them,
    c_ho = max(1, sum chi^2_ho,fit / sum m_j) (quasi-likelihood, Burnham & Anderson 2002
    sec. 6.2). A wrong effect that distorts the model predicts a held-out mode "none" reproduced
    badly, and that mode is kept. Without a kept mode the held-out modes give no evidence (0).

    Parameters
    ----------
    none_modes, fit_modes : (n_ho_modes,) float, held-out chi^2 of each mode for "none" and the
        fit (frequency and shape entries of the mode).
    entries : (n_ho_modes,) int, residual entries of each held-out mode.

    Returns
    -------
    float
        (sum_kept chi2_none - chi2_fit) / c_ho: positive when the effect predicts the held-out
        modes better than "none", below -margin when they contradict it strongly.
    """
    none_modes, fit_modes = np.asarray(none_modes, float), np.asarray(fit_modes, float)
    kept = reproduced(none_modes, entries) | reproduced(fit_modes, entries)
    if not kept.any():
        return 0.0
    c_ho = max(1.0, fit_modes[kept].sum() / max(int(np.sum(np.asarray(entries)[kept])), 1))
    return float((none_modes[kept].sum() - fit_modes[kept].sum()) / c_ho)


def reproduced(mode_chi2, entries) -> np.ndarray:
    """(n_modes,) bool: each mode's chi^2 within the goodness-of-fit limit of its entries
    (:func:`pipeline.diagnose.evidence.gof_limit` with m_j degrees of freedom)."""
    limits = np.array([gof_limit(m) for m in np.asarray(entries, int)])
    return np.asarray(mode_chi2, float) <= limits
