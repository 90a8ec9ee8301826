"""Figures of a correlation Dataset (plotting only; the numbers come from structures.correlation).

- :func:`plot_mac`, :func:`plot_cross_orthogonality`, :func:`plot_orthogonality`: annotated heat maps
  with the test modes as rows ("7 SW1B") and the paired analysis modes as columns, as in the
  paper's Tables 2-4;
- :func:`plot_frequency_comparison`: test vs analysis frequency bars per test mode with the error
  in percent (the paper's Figs. 7-8);
- :func:`save_correlation_figures`: all four as PNG files.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure  # no pyplot: no global figure state, no display backend


def mode_labels(corr: xr.Dataset) -> list[str]:
    """Labels "7 SW1B" (mode number and name when the GVT names it) of the test modes."""
    names = corr["test_name"].values if "test_name" in corr else [""] * corr.sizes["test_mode"]
    return [f"{int(m)} {n}".strip() for m, n in zip(corr["test_mode"].values, names)]


def _heat_map(values, row_labels, col_labels, title, *, vmin, vmax, cmap, ax, xlabel, ylabel):
    fig = ax.figure if ax is not None else Figure(figsize=(1.0 + 0.6 * len(col_labels),
                                                             1.2 + 0.45 * len(row_labels)))
    ax = ax if ax is not None else fig.add_subplot()
    image = ax.imshow(values, vmin=vmin, vmax=vmax, cmap=cmap, aspect="auto")
    ax.set_xticks(np.arange(len(col_labels)), labels=col_labels, rotation=90)
    ax.set_yticks(np.arange(len(row_labels)), labels=row_labels)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    span = vmax - vmin
    for (i, j), v in np.ndenumerate(values):
        dark = abs(v - vmin) / span > 0.6 if cmap != "RdBu_r" else abs(v) > 0.6
        ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=7, color="white" if dark else "black")
    fig.colorbar(image, ax=ax, shrink=0.8)
    fig.tight_layout()
    return fig


def plot_mac(corr: xr.Dataset, *, paired_only: bool = True, ax=None):
    """MAC heat map (eq. 23); columns are the paired analysis modes in test order unless
    ``paired_only`` is False (then all analysis modes)."""
    fe = corr["paired_fe_mode"].values if paired_only else corr["fe_mode"].values
    values = corr["mac"].sel(fe_mode=fe).values
    return _heat_map(values, mode_labels(corr), [str(int(m)) for m in fe], "MAC", vmin=0.0, vmax=1.0,
                     cmap="viridis", ax=ax, xlabel="analysis mode", ylabel="test mode")


def plot_cross_orthogonality(corr: xr.Dataset, *, paired_only: bool = True, ax=None):
    """Signed cross-orthogonality heat map (eq. 20, unit generalised masses)."""
    fe = corr["paired_fe_mode"].values if paired_only else corr["fe_mode"].values
    values = corr["cross_orthogonality"].sel(fe_mode=fe).values
    return _heat_map(values, mode_labels(corr), [str(int(m)) for m in fe], "cross-orthogonality",
                     vmin=-1.0, vmax=1.0, cmap="RdBu_r", ax=ax, xlabel="analysis mode", ylabel="test mode")


def plot_orthogonality(corr: xr.Dataset, *, ax=None):
    """Test-mode mass orthogonality heat map (eq. 11, diagonal normalised to 1)."""
    labels = mode_labels(corr)
    return _heat_map(corr["orthogonality"].values, labels, labels, "test-mode orthogonality", vmin=-1.0,
                     vmax=1.0, cmap="RdBu_r", ax=ax, xlabel="test mode", ylabel="test mode")


def plot_frequency_comparison(corr: xr.Dataset, *, ax=None):
    """Test and paired analysis frequencies as grouped bars, error [%] above each pair."""
    labels = mode_labels(corr)
    fig = ax.figure if ax is not None else Figure(figsize=(max(5.0, 0.7 * len(labels) + 2), 4.0))
    ax = ax if ax is not None else fig.add_subplot()
    pos = np.arange(len(labels))
    f_test, f_fe = corr["test_frequency"].values, corr["paired_fe_frequency"].values
    ax.bar(pos - 0.2, f_test, width=0.4, label="GVT")
    ax.bar(pos + 0.2, f_fe, width=0.4, label="analysis")
    for x, top, err in zip(pos, np.maximum(f_test, f_fe), corr["frequency_error"].values):
        ax.annotate(f"{err:+.1f}%", (x, top), ha="center", va="bottom", fontsize=7)
    ax.set_xticks(pos, labels=labels, rotation=90)
    ax.set_ylabel(f"frequency [{corr['test_frequency'].attrs.get('units', 'Hz')}]")
    ax.set_title("measured and computed frequencies")
    ax.legend()
    fig.tight_layout()
    return fig


def save_correlation_figures(corr: xr.Dataset, directory) -> list[Path]:
    """Write mac.png, cross_orthogonality.png, orthogonality.png, frequencies.png; return the paths."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, plot in (("mac", plot_mac), ("cross_orthogonality", plot_cross_orthogonality),
                       ("orthogonality", plot_orthogonality), ("frequencies", plot_frequency_comparison)):
        fig = plot(corr)
        paths.append(directory / f"{name}.png")
        fig.savefig(paths[-1], dpi=120)
    return paths
