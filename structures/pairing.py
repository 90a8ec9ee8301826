"""Pairing test modes with analysis modes by the assignment (Hungarian) method; mode interchange.

Each test mode is paired with a distinct analysis mode so that the sum of the pairing metric (MAC,
paper eq. 23, or |cross-orthogonality|, paper eq. 20) over all pairs is maximal
(``scipy.optimize.linear_sum_assignment``, Kuhn-Munkres). Unlike "best match per row", the
assignment never pairs two test modes with one analysis mode, and it is insensitive to the sign of
a shape because both metrics are (MAC is squared; the absolute value of cross-orthogonality is used).

Mode interchange (paper sec. V.B-C, modes 12/13): two test modes i, j are *interchanged* when the
analysis modes paired with them come in the opposite frequency order (f_Gi < f_Gj but the analysis
mode paired with i is above the one paired with j in frequency order).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from structures.common.errors import InputError


@dataclass(frozen=True)
class Pairing:
    """Result of :func:`pair_modes`.

    Attributes
    ----------
    fe_index : ndarray of int, shape (n_test,)
        Index (0-based, along the analysis-mode axis of the metric) of the analysis mode paired with
        each test mode.
    metric : ndarray, shape (n_test,)
        The pairing metric of each pair.
    interchanged : ndarray of bool, shape (n_test,)
        True for test modes that take part in an interchange.
    swaps : tuple of (int, int)
        Index pairs (i, j) of test modes, f_Gi < f_Gj, whose paired analysis modes are in inverted
        frequency order.
    """

    fe_index: np.ndarray
    metric: np.ndarray
    interchanged: np.ndarray
    swaps: tuple[tuple[int, int], ...]


def pair_modes(metric, test_frequency, fe_frequency) -> Pairing:
    """Pair every test mode with a distinct analysis mode, maximising the total metric.

    Parameters
    ----------
    metric : array_like, shape (n_test, n_fe)
        Pairing metric, larger is better: MAC (eq. 23) or |cross-orthogonality| (eq. 20).
        Needs n_test <= n_fe.
    test_frequency : array_like, shape (n_test,)
        Test frequencies [Hz] (used only to detect interchange).
    fe_frequency : array_like, shape (n_fe,)
        Analysis frequencies [Hz] (used only to detect interchange).

    Returns
    -------
    Pairing
    """
    metric = np.asarray(metric, dtype=float)
    test_frequency = np.asarray(test_frequency, dtype=float)
    fe_frequency = np.asarray(fe_frequency, dtype=float)
    if metric.ndim != 2 or metric.shape != (test_frequency.size, fe_frequency.size):
        raise InputError(f"pairing: metric of shape {metric.shape} does not match {test_frequency.size} "
                         f"test and {fe_frequency.size} analysis frequencies. Fix: pass (n_test, n_fe).")
    if metric.shape[0] > metric.shape[1]:
        raise InputError(f"pairing: {metric.shape[0]} test modes but only {metric.shape[1]} analysis modes. "
                         "Fix: compute at least as many analysis modes as test modes (plus rigid modes).")
    if not np.all(np.isfinite(metric)):
        raise InputError("pairing: the metric has NaN/inf entries. Fix: check the shapes for NaN.")
    rows, cols = linear_sum_assignment(metric, maximize=True)
    fe_index = np.empty(metric.shape[0], dtype=int)
    fe_index[rows] = cols
    interchanged, swaps = detect_interchange(test_frequency, fe_frequency, fe_index)
    return Pairing(fe_index=fe_index, metric=metric[np.arange(metric.shape[0]), fe_index],
                   interchanged=interchanged, swaps=swaps)


def detect_interchange(test_frequency, fe_frequency, fe_index) -> tuple[np.ndarray, tuple]:
    """Find test-mode pairs whose paired analysis modes are in inverted frequency order.

    Parameters
    ----------
    test_frequency : array_like, shape (n_test,)
    fe_frequency : array_like, shape (n_fe,)
    fe_index : array_like of int, shape (n_test,)
        Paired analysis-mode index of every test mode.

    Returns
    -------
    interchanged : ndarray of bool, shape (n_test,)
    swaps : tuple of (int, int)
        Test-mode index pairs (i, j) with f_Gi < f_Gj and rank(p(i)) > rank(p(j)), where rank is the
        analysis mode's position in frequency order (ties broken by mode order).
    """
    test_frequency = np.asarray(test_frequency, dtype=float)
    fe_rank = np.argsort(np.argsort(np.asarray(fe_frequency, dtype=float), kind="stable"), kind="stable")
    test_rank = np.argsort(np.argsort(test_frequency, kind="stable"), kind="stable")
    paired_rank = fe_rank[np.asarray(fe_index)]
    inverted = (test_rank[:, None] < test_rank[None, :]) & (paired_rank[:, None] > paired_rank[None, :])
    i, j = np.nonzero(inverted)
    interchanged = np.zeros(test_frequency.size, dtype=bool)
    interchanged[i] = True
    interchanged[j] = True
    return interchanged, tuple((int(a), int(b)) for a, b in zip(i, j))
