"""Test-analysis acceptance checks (MIL-STD-1540C and NASA-STD-5002 style), limits as settings.

The paper (sec. IV) quotes the modal-survey requirements:

- MIL-STD-1540C: analysis frequencies within 3 % of test; cross-orthogonality of corresponding
  modes >= 0.95 and of dissimilar modes <= 0.10.
- NASA-STD-5002: frequencies within 5 % (goal, significant modes); test-mode orthogonality
  off-diagonals < 0.1 with the diagonal normalised to 1; corresponding cross-orthogonality > 0.9 and
  all other terms < 0.1.

Both are applied per test mode. The frequency limit has a primary/secondary split (the paper's
target errors are 5 % for primary and 10 % for secondary modes, Table 1); the presets take the
standard's number for primary modes, and for NASA-STD-5002 the paper's 10 % for secondary modes.
Off-diagonal checks of test mode i look at row i and column i of the *paired* cross-orthogonality
matrix S_p[i, k] = S[i, p(k)] (k over the test modes, p the pairing) and at row i of the
normalised orthogonality matrix; a limit of ``math.inf`` switches a check off.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from structures.common.errors import InputError


@dataclass(frozen=True)
class AcceptanceCriteria:
    """Limits of one acceptance check.

    Attributes
    ----------
    name : str
        Label of the check (becomes the ``check`` coordinate).
    frequency_primary, frequency_secondary : float
        Largest |frequency error| [%] for primary and secondary modes.
    cross_orthogonality_diagonal : float
        Smallest |S_ii| of corresponding modes.
    cross_orthogonality_off_diagonal : float
        Largest |S_ij| of dissimilar (paired) modes.
    orthogonality_off_diagonal : float
        Largest |M_ij|, i != j, of the normalised test-mode orthogonality matrix.
    """

    name: str
    frequency_primary: float
    frequency_secondary: float
    cross_orthogonality_diagonal: float
    cross_orthogonality_off_diagonal: float
    orthogonality_off_diagonal: float

    def __post_init__(self) -> None:
        if not self.name.strip():
            raise InputError("acceptance criteria: empty name. Fix: give the check a name.")
        for field in ("frequency_primary", "frequency_secondary", "cross_orthogonality_off_diagonal",
                      "orthogonality_off_diagonal"):
            value = getattr(self, field)
            if not (value > 0):
                raise InputError(f"acceptance criteria {self.name}: {field}={value} must be > 0 "
                                 "(math.inf switches the check off).")
        if not 0.0 <= self.cross_orthogonality_diagonal <= 1.0:
            raise InputError(f"acceptance criteria {self.name}: cross_orthogonality_diagonal="
                             f"{self.cross_orthogonality_diagonal} must be in [0, 1].")


MIL_STD_1540C = AcceptanceCriteria("MIL-STD-1540C", frequency_primary=3.0, frequency_secondary=3.0,
                                   cross_orthogonality_diagonal=0.95, cross_orthogonality_off_diagonal=0.10,
                                   orthogonality_off_diagonal=0.10)
NASA_STD_5002 = AcceptanceCriteria("NASA-STD-5002", frequency_primary=5.0, frequency_secondary=10.0,
                                   cross_orthogonality_diagonal=0.90, cross_orthogonality_off_diagonal=0.10,
                                   orthogonality_off_diagonal=0.10)
DEFAULT_CRITERIA = (MIL_STD_1540C, NASA_STD_5002)


def off_diagonal_maxima(corr: xr.Dataset) -> xr.Dataset:
    """Per test mode: |S_ii| and the largest off-diagonal |S| and |M| terms.

    Parameters
    ----------
    corr : xarray.Dataset
        Needs ``cross_orthogonality(test_mode, fe_mode)``, ``orthogonality(test_mode, test_mode_2)``
        and ``paired_fe_mode(test_mode)``.

    Returns
    -------
    xarray.Dataset
        ``paired_cross_orthogonality(test_mode)``, ``max_cross_orthogonality_off_diagonal(test_mode)``
        (row and column of the paired matrix) and ``max_orthogonality_off_diagonal(test_mode)``.
    """
    s_matrix = corr["cross_orthogonality"].sel(fe_mode=corr["paired_fe_mode"].values).values
    n = s_matrix.shape[0]
    off = ~np.eye(n, dtype=bool)
    masked = np.where(off, np.abs(s_matrix), 0.0)
    s_off = np.maximum(masked.max(axis=1), masked.max(axis=0)) if n > 1 else np.zeros(n)
    o_abs = np.where(off, np.abs(corr["orthogonality"].values), 0.0)
    o_off = o_abs.max(axis=1) if n > 1 else np.zeros(n)
    diag = np.diagonal(s_matrix).copy()
    dims = ("test_mode",)
    return xr.Dataset({"paired_cross_orthogonality": (dims, diag),
                       "max_cross_orthogonality_off_diagonal": (dims, s_off),
                       "max_orthogonality_off_diagonal": (dims, o_off)},
                      coords={"test_mode": corr["test_mode"].values})


def evaluate_checks(corr: xr.Dataset, criteria=DEFAULT_CRITERIA, primary_modes=None) -> xr.Dataset:
    """Pass/fail of every acceptance check for every test mode.

    Parameters
    ----------
    corr : xarray.Dataset
        Correlation Dataset with ``frequency_error(test_mode)`` [%], ``cross_orthogonality``,
        ``orthogonality`` and ``paired_fe_mode``.
    criteria : sequence of AcceptanceCriteria
        The checks; default MIL-STD-1540C and NASA-STD-5002 style.
    primary_modes : sequence of int, optional
        Test mode numbers that are primary; the others are secondary. Default: all primary.

    Returns
    -------
    xarray.Dataset
        Coordinate ``check``; ``primary(test_mode)``, ``frequency_limit(check, test_mode)`` [%] and
        booleans ``pass_frequency``, ``pass_cross_orthogonality_diagonal``,
        ``pass_cross_orthogonality_off_diagonal``, ``pass_orthogonality``, ``pass_all`` on
        (check, test_mode), plus the maxima of :func:`off_diagonal_maxima`.
    """
    criteria = tuple(criteria)
    if not criteria or not all(isinstance(c, AcceptanceCriteria) for c in criteria):
        raise InputError("acceptance: criteria must be a non-empty sequence of AcceptanceCriteria.")
    names = [c.name for c in criteria]
    if len(set(names)) != len(names):
        raise InputError(f"acceptance: duplicate check names {names}. Fix: name every check differently.")
    test_modes = corr["test_mode"].values
    if primary_modes is None:
        primary = np.ones(test_modes.size, dtype=bool)
    else:
        primary_modes = np.asarray(list(primary_modes), dtype=int)
        unknown = primary_modes[~np.isin(primary_modes, test_modes)]
        if unknown.size:
            raise InputError(f"acceptance: primary modes {unknown.tolist()} are not test modes "
                             f"{test_modes.tolist()}. Fix: give test (GVT) mode numbers.")
        primary = np.isin(test_modes, primary_modes)
    maxima = off_diagonal_maxima(corr)
    err = np.abs(corr["frequency_error"].values)
    f_lim = np.array([np.where(primary, c.frequency_primary, c.frequency_secondary) for c in criteria])
    s_diag = np.abs(maxima["paired_cross_orthogonality"].values)
    limit = {attr: np.array([getattr(c, attr) for c in criteria])[:, None]
             for attr in ("cross_orthogonality_diagonal", "cross_orthogonality_off_diagonal",
                          "orthogonality_off_diagonal")}
    pass_f = err[None, :] <= f_lim
    pass_sd = s_diag[None, :] >= limit["cross_orthogonality_diagonal"]
    pass_so = (maxima["max_cross_orthogonality_off_diagonal"].values[None, :]
               <= limit["cross_orthogonality_off_diagonal"])
    pass_o = maxima["max_orthogonality_off_diagonal"].values[None, :] <= limit["orthogonality_off_diagonal"]
    dims = ("check", "test_mode")
    out = xr.Dataset(
        {"primary": (("test_mode",), primary),
         "frequency_limit": (dims, f_lim, {"units": "%"}),
         "pass_frequency": (dims, pass_f),
         "pass_cross_orthogonality_diagonal": (dims, pass_sd),
         "pass_cross_orthogonality_off_diagonal": (dims, pass_so),
         "pass_orthogonality": (dims, pass_o),
         "pass_all": (dims, pass_f & pass_sd & pass_so & pass_o)},
        coords={"check": names, "test_mode": test_modes})
    for c in criteria:
        out.attrs[f"criteria {c.name}"] = (
            f"|df| <= {c.frequency_primary}% primary / {c.frequency_secondary}% secondary; "
            f"|S_ii| >= {c.cross_orthogonality_diagonal}; |S_ij| <= {c.cross_orthogonality_off_diagonal}; "
            f"|M_ij| <= {c.orthogonality_off_diagonal}")
    return xr.merge([out, maxima], combine_attrs="override")
