"""Statistics of a fit's residual: chi^2, the information criterion, goodness of fit, runs test.

Every residual of diagnose (:mod:`pipeline.diagnose.evidence`) has entries of unit variance when
the model is right, so chi^2 = |r|^2; BIC = chi^2 + p ln n (Schwarz 1978), n the number of
training residuals, p the parameters fitted; a BIC difference above 10 is "very strong" evidence
(Kass & Raftery 1995). A fit is good when chi^2 lies below the ``GOF_QUANTILE`` quantile of the
chi-square distribution with n - p degrees of freedom.
"""
from __future__ import annotations

import numpy as np
import scipy.stats

from structures.common.errors import InputError

#: Goodness-of-fit quantile: chi^2 above the 99.9 % chi-square quantile is a misfit (1 false alarm
#: in 1000 fits of a right model).
GOF_QUANTILE = 0.999


def chi_square(r) -> float:
    """chi^2 = |r|^2 of a residual vector r (any shape) of unit-variance entries."""
    r = np.asarray(r, float)
    return float(np.sum(r * r))


def bic(chi2: float, n_params: int, n_data: int) -> float:
    """Bayesian information criterion chi^2 + p ln n (Schwarz 1978) for Gaussian residuals."""
    if n_data < 1:
        raise InputError("BIC: no residuals. Fix: give test modes (or measured mass properties).")
    return float(chi2 + n_params * np.log(n_data))                           # Schwarz 1978, eq. 2


def gof_limit(dof: int, quantile: float = GOF_QUANTILE) -> float:
    """chi^2 quantile for ``dof`` degrees of freedom (at least 1)."""
    return float(scipy.stats.chi2.ppf(quantile, max(int(dof), 1)))


def runs_test(values) -> float:
    """One-sided p-value (too few runs) of the Wald-Wolfowitz runs test on the signs of ``values``.

    Few runs (long stretches of one sign along the modes) mean a structured residual. Normal
    approximation (Wald & Wolfowitz 1940): mu = 2 n+ n- / n + 1,
    var = (mu - 1)(mu - 2) / (n - 1). Returns 1.0 when one sign is absent.
    """
    signs = np.sign(np.asarray(values, float))
    signs = signs[signs != 0]
    n_pos, n_neg = int(np.sum(signs > 0)), int(np.sum(signs < 0))
    n = n_pos + n_neg
    if n_pos == 0 or n_neg == 0 or n < 3:
        return 1.0
    runs = 1 + int(np.sum(signs[1:] != signs[:-1]))
    mu = 2.0 * n_pos * n_neg / n + 1.0                                      # Wald & Wolfowitz 1940
    var = (mu - 1.0) * (mu - 2.0) / (n - 1.0)
    if var <= 0:
        return 1.0
    return float(scipy.stats.norm.cdf((runs - mu) / np.sqrt(var)))
