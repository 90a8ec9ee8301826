"""HTML tables of the run's report (pipeline.report): formatting only, every header with its unit.

- :func:`correlation_section`: test vs FE frequency, error, MAC, the cross-orthogonality diagonal
  and the largest off-diagonal cross-orthogonality / orthogonality terms per test mode and the
  acceptance checks (structures.acceptance, merged into correlation.nc), paper Tables 1-4.
- :func:`mass_section`: mass, CG and inertias about the CG (paper J1..J10), and model against
  measured when the correlation holds the comparison.
- :func:`tuning_section`: frequencies before / after a stage's tuning (paper Tables 7, 14,
  structures.tuning_report.frequency_table); :func:`design_change_section`: design-variable changes
  of every stage (paper Table 24, structures.tuning_report.design_change_table).
- :func:`selection_section`: participation factors and the selected modes (paper Table 6, the
  text layout of pipeline.selection.selection_table).
"""
from __future__ import annotations

import html
from pathlib import Path

import numpy as np
import xarray as xr

from pipeline.selection import selection_table
from structures.common.files import read_dataset
from structures.tuning_report import design_change_table, frequency_table
from structures.units import UnitLabels


def table(header, rows, *, table_id: str | None = None) -> str:
    """An HTML table (cells escaped); ``table_id`` becomes the table's ``id``."""
    head = "".join(f"<th>{html.escape(str(h), quote=False)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c), quote=False)}</td>" for c in row)
                   + "</tr>"
                   for row in rows)
    ident = f' id="{html.escape(table_id)}"' if table_id else ""
    return f"<table{ident}><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def fmt(value, spec: str) -> str:
    """A number formatted with ``spec``; NaN (absent) as an en dash (-0 prints as 0)."""
    value = float(value) + 0.0
    return "\u2013" if not np.isfinite(value) else format(value, spec)


def note(text: str) -> str:
    """A one-line remark (e.g. why a section is left out)."""
    return f'<p class="note">{html.escape(text, quote=False)}</p>'


def _yes(flag) -> str:
    return "pass" if bool(flag) else "FAIL"


def correlation_section(corr: xr.Dataset, where: str, roles: dict | None = None) -> str:
    """Frequency / MAC / orthogonality table and acceptance summary of one correlation.nc;
    ``roles`` (FE mode -> "primary" / "secondary" / "rigid" / "") are the stage's selection."""
    roles = roles or {}
    checks = [str(c) for c in corr["check"].values] if "check" in corr.coords else []
    names = corr["test_name"].values if "test_name" in corr else [""] * corr.sizes["test_mode"]
    rows = []
    for i, mode in enumerate(corr["test_mode"].values):
        one = corr.isel(test_mode=i)
        rows.append([int(mode), str(names[i]), fmt(one["test_frequency"], ".4g"),
                     int(one["paired_fe_mode"]), fmt(one["paired_fe_frequency"], ".4g"),
                     fmt(one["frequency_error"], "+.2f"), fmt(one["paired_mac"], ".3f"),
                     fmt(abs(float(one["paired_cross_orthogonality"])), ".3f"),
                     fmt(one["max_cross_orthogonality_off_diagonal"], ".3f"),
                     fmt(one["max_orthogonality_off_diagonal"], ".3f"),
                     roles.get(int(one["paired_fe_mode"])) or "-"]
                    + [_yes(one["pass_all"].sel(check=c)) for c in checks])
    header = ["test mode", "name", "test frequency [Hz]", "FE mode", "FE frequency [Hz]",
              "frequency error [%]", "MAC [-]", "|S_ii| [-]", "max off-diagonal |S_ij| [-]",
              "max off-diagonal |M_ij| [-]", "selection role",
              *(f"{c} [pass/fail]" for c in checks)]
    out = (f"<h4>{html.escape(where)}: test-analysis correlation (paper Tables 1-4)</h4>"
           + table(header, rows))
    summary = [(c, f"{int(corr['pass_all'].sel(check=c).sum())} of {corr.sizes['test_mode']}",
                _yes(corr["pass_all"].sel(check=c).all()),
                str(corr.attrs.get(f"criteria {c}", ""))) for c in checks]
    if summary:
        out += table(("acceptance check", "test modes passing [count]", "all modes [pass/fail]",
                      "limits"), summary)
    swaps = corr.attrs.get("interchanges", "none")
    if swaps != "none":
        out += note(f"{where}: mode interchanges {swaps}.")
    hung = corr.attrs.get("suspension_modes", "none")
    if hung != "none":
        out += note(f"{where}: test modes {hung} are suspension modes (rigid-body motions at the "
                    "sensors below the first elastic analysis frequency), left out.")
    return out


def modes_section(modes: xr.Dataset, where: str) -> str:
    """In-vacuo FE frequencies of one modes.nc (shown when there is no correlation)."""
    rows = [(int(m), fmt(f, ".5g")) for m, f in zip(modes["mode"].values,
                                                    modes["frequency"].values)]
    return (f"<h4>{html.escape(where)}: FE modes</h4>"
            + table(("FE mode", "frequency [Hz]"), rows))


def mass_section(mp: xr.Dataset, corr: xr.Dataset | None, labels: UnitLabels, where: str) -> str:
    """Mass properties of one mass_properties.nc; model against measured when ``corr`` has them."""
    cg, inertia = mp["cg"].values, mp["inertia"].values
    wtmass = float(mp.attrs.get("wtmass", 1.0))
    values = {"mass": float(mp["mass"]), "x_cg": cg[0], "y_cg": cg[1], "z_cg": cg[2],
              "Ixx": inertia[0, 0], "Iyy": inertia[1, 1], "Izz": inertia[2, 2],
              # products of inertia: minus the tensor's off-diagonals (structures.massprops)
              "Ixy": -inertia[0, 1], "Iyz": -inertia[1, 2], "Izx": -inertia[2, 0]}
    if wtmass != 1.0:
        values["weight"] = values["mass"] / wtmass
    out = (f"<h4>{html.escape(where)}: mass properties (about the CG, basic axes)</h4>"
           + table([f"{q} [{labels.of_mass_property(q, wtmass)}]" for q in values],
                   [[fmt(v, ".6g") for v in values.values()]]))
    if corr is not None and "mass_model" in corr:
        rows = [(f"{q} [{labels.of_mass_property(str(q), wtmass)}]",
                 fmt(corr["mass_model"].sel(quantity=q), ".6g"),
                 fmt(corr["mass_measured"].sel(quantity=q), ".6g"),
                 fmt(corr["mass_relative_error"].sel(quantity=q), "+.2f"))
                for q in corr["quantity"].values]
        out += table(("quantity [unit]", "model [unit of the row]", "measured [unit of the row]",
                      "error [%]"), rows)
    return out


def tuning_section(k: int, path: Path) -> str:
    """Frequencies before / after the tuning of stage ``k`` (paper Tables 7, 14)."""
    if not path.exists():
        return note(f"Stage {k}: no tuning/history.nc (the tuning did not finish).")
    history = read_dataset(path)
    ft = frequency_table(history, after=int(history.attrs.get("chosen_iteration", -1)))
    rows = [(str(p), fmt(ft["test_frequency"].sel(pair=p), ".4g"),
             int(ft["fe_mode_before"].sel(pair=p)), fmt(ft["fe_frequency_before"].sel(pair=p), ".4g"),
             fmt(ft["error_before"].sel(pair=p), "+.2f"), int(ft["fe_mode_after"].sel(pair=p)),
             fmt(ft["fe_frequency_after"].sel(pair=p), ".4g"),
             fmt(ft["error_after"].sel(pair=p), "+.2f")) for p in ft["pair"].values]
    return (f"<h3>Stage {k}: tuning, frequencies before / after (paper Tables 7, 14)</h3>"
            + table(("configuration:test mode", "test frequency [Hz]", "FE mode before",
                     "FE frequency before [Hz]", "error before [%]", "FE mode after",
                     "FE frequency after [Hz]", "error after [%]"), rows))


def design_change_section(stages: list) -> str:
    """Design-variable values and changes of every tuning stage (paper Table 24).

    ``stages`` are the folders stage1, stage2, ...; a stage's change is from the start of its own
    tuning (:func:`structures.tuning_report.design_change_table`), the change from the baseline is
    against the start of stage 1's tuning.
    """
    head = '<h2 id="table24">Design-variable changes per stage (paper Table 24)</h2>'
    histories = {k: read_dataset(folder / "tuning" / "history.nc")
                 for k, folder in enumerate(stages, start=1)
                 if (folder / "tuning" / "history.nc").exists()}
    # after: the design the stage wrote out (pipeline.stages: the restart rule's pick)
    tables = {k: design_change_table(h, after=int(h.attrs.get("chosen_iteration", -1)))
              for k, h in histories.items()}
    if not tables:
        return head + note("No tuning stage in the run folder: no design-variable changes.")
    names = list(dict.fromkeys(str(v) for t in tables.values() for v in t["design_variable"].values))
    first = tables[min(tables)]
    header = ["design variable", "baseline value [deck units]"]
    for k in tables:
        header += [f"stage {k} value [deck units]", f"stage {k} change in stage [%]",
                   f"stage {k} change from baseline [%]"]
    rows = []
    for name in names:
        base = (float(first["before"].sel(design_variable=name))
                if name in first["design_variable"].values else np.nan)
        row = [name, fmt(base, ".6g")]
        for t in tables.values():
            if name not in t["design_variable"].values:
                row += ["\u2013"] * 3
                continue
            one = t.sel(design_variable=name)
            after = float(one["after"])
            bound = " (at bound)" if bool(one["at_bound"]) else ""
            row += [fmt(after, ".6g") + bound, fmt(one["change"], "+.2f"),
                    fmt(100.0 * (after - base) / abs(base), "+.2f")]
        rows.append(row)
    return (head + "<p>Values in the deck's units of each card field; \"at bound\": on a side "
            "constraint.</p>" + table(header, rows))


def selection_roles(path: Path) -> dict:
    """configuration -> {FE mode: role} of a stage's selection.nc ({} when there is none)."""
    if not path.exists():
        return {}
    sel = read_dataset(path)
    modes = [int(m) for m in sel["mode"].values]
    return {str(c): dict(zip(modes, sel["role"].sel(configuration=c).values.astype(str)))
            for c in sel["configuration"].values}


def selection_section(k: int, path: Path) -> str:
    """Participation factors of the critical roots and the selected modes (paper Table 6), as
    :func:`pipeline.selection.selection_table` lays them out."""
    head = f"<h3>Stage {k}: modal participation and mode selection (paper Table 6)</h3>"
    if not path.exists():
        return head + note(f"Stage {k}: no selection.nc (no [flutter] section, so no selection).")
    return head + f"<pre>{html.escape(selection_table(read_dataset(path)))}</pre>"
