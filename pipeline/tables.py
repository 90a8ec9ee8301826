"""Plain-text tables for the terminal and the report (formatting only, no computation)."""
from __future__ import annotations

import numpy as np
import xarray as xr

from structures.massprops import MassProperties
from structures.units import unit_labels


def frequency_table(modes: xr.Dataset) -> str:
    """Mode number, frequency [Hz] and generalized mass, one line per mode."""
    lines = [f"{'mode':>5} {'frequency [Hz]':>16} {'gen. mass':>12}"]
    for mode, f, gm in zip(modes["mode"].values, modes["frequency"].values,
                           modes["generalized_mass"].values):
        lines.append(f"{mode:5d} {f:16.6g} {gm:12.5g}")
    return "\n".join(lines)


def mass_table(props: MassProperties, units: str | None = None) -> str:
    """Mass, CG and inertias about the CG (the paper's J1..J10 quantities), each with its unit.

    Parameters
    ----------
    props : MassProperties
    units : {"si", "english_in", "english_ft"} or None
        The case's unit system (structures.units); None: "model units".
    """
    labels = unit_labels(units)
    values = props.as_dict()
    if props.wtmass == 1.0:
        del values["weight"]
    lines = [f"{'quantity':>10} {'value':>16}  unit"]
    lines += [f"{name:>10} {value:16.8g}  {labels.of_mass_property(name, props.wtmass)}"
              for name, value in values.items()]
    return "\n".join(lines)


def format_matrix(values, row_labels, col_labels, fmt="{:6.3f}") -> str:
    """A labelled matrix (e.g. MAC) as text."""
    values = np.asarray(values)
    width = max(6, max(len(str(c)) for c in col_labels))
    head = " " * 8 + " ".join(f"{str(c):>{width}}" for c in col_labels)
    rows = [f"{str(r):>8}" + " ".join(f"{fmt.format(v):>{width}}" for v in row)
            for r, row in zip(row_labels, values)]
    return "\n".join([head, *rows])
