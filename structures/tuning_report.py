"""Tables of a tuning run from its history Dataset (structures.tuning), like the paper's tables.

- :func:`frequency_table`: per configuration and test mode, the test frequency and the paired
  analysis frequency and error (eq. 18, in %) before and after tuning (paper Tables 7 and 14), with
  the paired analysis mode (mode interchange shows as a changed pairing).
- :func:`design_change_table`: every design variable's start and tuned value and its change in %
  (paper Table 24), flagging variables on a side constraint.
- :func:`index_summary`: per configuration and index kind, the largest |term| before and after
  (off-diagonals of orthogonality eq. 15 and cross-orthogonality eq. 21 as |Mbar_ij|, |Sbar_ij|,
  frequency errors in %, smallest MAC diagonal eq. 24, mass-property errors in %).

Compute (Datasets) and formatting (:func:`format_table`) are separate; nothing here changes the
history.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from structures.common.errors import InputError


def _iteration(history: xr.Dataset, which) -> int:
    n = history.sizes["iteration"]
    if which == "last":
        return n - 1
    if which == "best":
        feasible = history["feasible"].values
        obj = history["objective"].values
        pool = np.flatnonzero(feasible) if feasible.any() else np.arange(n)
        return int(pool[np.argmin(obj[pool])])
    which = int(which)
    if not -n <= which < n:
        raise InputError(f"tuning report: iteration {which} is not in the history (0..{n - 1}).")
    return which % n


def frequency_table(history: xr.Dataset, after="last", before=0) -> xr.Dataset:
    """Frequencies and errors before/after (paper Tables 7, 14).

    Returns
    -------
    xarray.Dataset on dim ``pair`` (``CONFIG:TEST_MODE``): ``test_frequency`` [Hz],
    ``fe_frequency_before/after`` [Hz], ``error_before/after`` [%], ``fe_mode_before/after``.
    """
    i0, i1 = _iteration(history, before), _iteration(history, after)
    f_test = history["test_frequency"].values
    out = xr.Dataset(coords={"pair": history["pair"].values})
    out["test_frequency"] = ("pair", f_test, {"units": "Hz"})
    for tag, i in (("before", i0), ("after", i1)):
        f = history["paired_fe_frequency"].values[i]
        out[f"fe_frequency_{tag}"] = ("pair", f, {"units": "Hz"})
        out[f"error_{tag}"] = ("pair", 100.0 * (f - f_test) / f_test,
                               {"units": "%", "long_name": "100 (f_i - f_iG) / f_iG (eq. 18)"})
        out[f"fe_mode_{tag}"] = ("pair", history["paired_fe_mode"].values[i])
    out.attrs.update({"iteration_before": i0, "iteration_after": i1})
    return out


def design_change_table(history: xr.Dataset, after="last", before=0) -> xr.Dataset:
    """Design-variable changes in % (paper Table 24).

    Returns
    -------
    xarray.Dataset on dim ``design_variable``: ``before``, ``after``, ``change`` [%],
    ``lower``, ``upper``, ``at_bound`` (bool).
    """
    i0, i1 = _iteration(history, before), _iteration(history, after)
    x0, x1 = history["design"].values[i0], history["design"].values[i1]
    lower, upper = history["lower"].values, history["upper"].values
    span = upper - lower
    at_bound = (np.abs(x1 - lower) <= 1e-6 * span) | (np.abs(x1 - upper) <= 1e-6 * span)
    return xr.Dataset(
        {"before": ("design_variable", x0), "after": ("design_variable", x1),
         "change": ("design_variable", 100.0 * (x1 - x0) / np.abs(x0), {"units": "%"}),
         "lower": ("design_variable", lower), "upper": ("design_variable", upper),
         "at_bound": ("design_variable", at_bound)},
        coords={"design_variable": history["design_variable"].values},
        attrs={"iteration_before": i0, "iteration_after": i1})


def index_summary(history: xr.Dataset, after="last", before=0) -> xr.Dataset:
    """Worst term per configuration and index kind, before and after.

    Returns
    -------
    xarray.Dataset on dims (``configuration``, ``kind``): ``before``, ``after``: the largest
    |Mbar_ij| (orthogonality), |Sbar_ij| (cross_orthogonality), |frequency error| [%], relative
    mass-property error [%], and the smallest MAC_ii (mac); NaN where a kind has no index.
    """
    i0, i1 = _iteration(history, before), _iteration(history, after)
    names = [str(n) for n in history["index"].values]
    config = np.array([n.split(":")[0] for n in names])
    kind = np.array([n.split(":")[1] for n in names])
    configs = [c for c in dict.fromkeys(config) if c != "design"]    # design:change: regularisation
    kinds = ["mass", "orthogonality", "frequency", "cross_orthogonality", "mac"]
    out = {}
    for tag, i in (("before", i0), ("after", i1)):
        j = history["index_value"].values[i]
        table = np.full((len(configs), len(kinds)), np.nan)
        for a, c in enumerate(configs):
            for b, k in enumerate(kinds):
                sel = (config == c) & (kind == k)
                if not sel.any():
                    continue
                if k == "mac":
                    table[a, b] = j[sel].min()                             # eq. 24: MAC_ii
                elif k in ("frequency", "mass"):
                    table[a, b] = 100.0 * np.sqrt(j[sel].max())            # eqs. 1-10, 18 in %
                else:
                    table[a, b] = np.sqrt(j[sel].max())                    # eqs. 15, 21: |term|
        out[tag] = (("configuration", "kind"), table)
    return xr.Dataset(out, coords={"configuration": configs, "kind": kinds},
                      attrs={"iteration_before": i0, "iteration_after": i1,
                             "units": "mass, frequency: %; orthogonality, cross_orthogonality: "
                                      "|term|; mac: smallest diagonal"})


def format_table(ds: xr.Dataset, fmt: str = "{:>12.5g}") -> str:
    """A 1-D or 2-D table Dataset as aligned text (one line per entry of its first dim)."""
    dim = list(ds.sizes)[0]
    labels = [str(v) for v in ds[dim].values]
    width = max([len(dim)] + [len(s) for s in labels])
    columns = [name for name, var in ds.data_vars.items() if var.dims and var.dims[0] == dim]
    lines = []
    if all(ds[c].ndim == 1 for c in columns):
        widths = [max(12, len(c)) for c in columns]
        lines.append(f"{dim:<{width}} " + " ".join(f"{c:>{w}}" for c, w in zip(columns, widths)))
        for r, label in enumerate(labels):
            cells = []
            for c, w in zip(columns, widths):
                v = ds[c].values[r]
                text = str(v) if isinstance(v, (bool, np.bool_, str)) else fmt.format(v).strip()
                cells.append(f"{text:>{w}}")
            lines.append(f"{label:<{width}} " + " ".join(cells))
        return "\n".join(lines)
    other = [d for d in ds.dims if d != dim][0]
    cols = [str(v) for v in ds[other].values]
    for c in columns:
        lines.append(f"[{c}]")
        lines.append(f"{dim:<{width}} " + " ".join(f"{s:>20}" for s in cols))
        for r, label in enumerate(labels):
            lines.append(f"{label:<{width}} " + " ".join(f"{v:>20.4g}" for v in ds[c].values[r]))
    return "\n".join(lines)


def tuning_report(history: xr.Dataset, after="last", before=0) -> str:
    """The three tables as text."""
    parts = [("Frequencies before / after (paper Tables 7, 14)", frequency_table(history, after, before)),
             ("Design-variable changes (paper Table 24)", design_change_table(history, after, before)),
             ("Worst index term per configuration", index_summary(history, after, before))]
    return "\n\n".join(f"{title}\n{format_table(ds)}" for title, ds in parts)
