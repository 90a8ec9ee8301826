"""The run's HTML report: one self-contained page built from the stage results (no computation)."""
from __future__ import annotations

import html
from pathlib import Path

from structures.common.files import write_text
from structures.units import UnitLabels, unit_labels


_STYLE = """body{font-family:sans-serif;margin:2em;max-width:70em}
table{border-collapse:collapse;margin:0.5em 0 1.5em}td,th{border:1px solid #bbb;padding:2px 8px;
text-align:right}th{background:#eee}h2{border-bottom:1px solid #999}"""


def _table(header, rows) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>"
                   for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _modes_section(name, result, labels: UnitLabels) -> str:
    modes = result["modes"]
    rows = [(int(m), f"{f:.5g}") for m, f in zip(modes["mode"].values, modes["frequency"].values)]
    mp = result["mass_properties"]
    cg = mp["cg"].values
    inertia = mp["inertia"].values
    values = [("mass", float(mp["mass"])), ("x_cg", cg[0]), ("y_cg", cg[1]), ("z_cg", cg[2]),
              ("Ixx", inertia[0, 0]), ("Iyy", inertia[1, 1]), ("Izz", inertia[2, 2]),
              ("Ixy", -inertia[0, 1]), ("Iyz", -inertia[1, 2]), ("Izx", -inertia[2, 0])]
    mass_rows = [(q, f"{v:.6g}", labels.of_mass_property(q)) for q, v in values]
    return (f"<h2>Configuration {html.escape(name)}</h2>"
            f"<p>Deck: {html.escape(str(modes.attrs.get('deck', '')))}; modes from "
            f"{html.escape(str(modes.attrs.get('source', '')))}.</p>"
            "<h3>Natural frequencies</h3>" + _table(("mode", "frequency [Hz]"), rows) +
            "<h3>Mass properties (about the CG, basic axes)</h3>" +
            _table(("quantity", "value", "unit"), mass_rows))


def _correlation_section(result, labels: UnitLabels, wtmass: float) -> str:
    corr = result["dataset"]
    names = corr["test_name"].values if "test_name" in corr else [""] * corr.sizes["test_mode"]
    rows = []
    for i, mode in enumerate(corr["test_mode"].values):
        rows.append((int(mode), names[i], f"{float(corr['test_frequency'][i]):.4g}",
                     int(corr["paired_fe_mode"][i]), f"{float(corr['paired_fe_frequency'][i]):.4g}",
                     f"{float(corr['frequency_error'][i]):+.2f}", f"{float(corr['paired_mac'][i]):.3f}",
                     "yes" if bool(corr["interchanged"][i]) else ""))
    table = _table(("test mode", "name", "test [Hz]", "FE mode", "FE [Hz]", "error [%]", "MAC",
                    "interchanged"), rows)
    mass = ""
    if "mass_model" in corr:
        mass_rows = [(q, f"{float(corr['mass_model'].sel(quantity=q)):.6g}",
                      f"{float(corr['mass_measured'].sel(quantity=q)):.6g}",
                      f"{float(corr['mass_relative_error'].sel(quantity=q)):+.2f}",
                      labels.of_mass_property(str(q), wtmass))
                     for q in corr["quantity"].values]
        mass = "<h3>Mass properties, model vs measured</h3>" + _table(
            ("quantity", "model", "measured", "error [%]", "unit"), mass_rows)
    figures = "".join(f"<img src='{html.escape(str(f))}' alt='correlation' width='420'>"
                      for f in result["figures"])
    return "<h3>Test-analysis correlation (paper Tables 1-4)</h3>" + table + mass + figures


def _flutter_section(result, labels: UnitLabels) -> str:
    rows = [(c["kind"], c["root"], f"{c['mach']:.3g}", f"{c['density']:.5g}",
             f"{c['velocity']:.5g}", f"{c['frequency']:.4g}") for c in result["summary"]]
    table = (_table(("kind", "root", "Mach", f"density [{labels.density}]",
                     f"velocity [{labels.velocity}]", f"frequency [{labels.frequency}]"), rows)
             if rows else "<p>No flutter or divergence crossing in the analysed range.</p>")
    figures = "".join(f"<img src='{html.escape(str(f))}' alt='V-g / V-f' width='560'>"
                      for f in result["figures"])
    return f"<h3>Flutter crossings ({html.escape(labels.system)})</h3>" + table + figures


def write_report(case, results: dict, out_dir) -> Path:
    """Write ``report.html`` into ``out_dir`` and return its path; every number is labelled with
    the case's unit system (structures.units)."""
    out = Path(out_dir) / "report.html"
    labels = unit_labels(case.units)
    sections = "".join(_modes_section(name, res, labels) +
                       (_correlation_section(res["correlation"], labels,
                                             float(res["mass_properties"].attrs.get("wtmass", 1.0)))
                        if "correlation" in res else "") +
                       (_flutter_section(res["flutter"], labels) if "flutter" in res else "")
                       for name, res in results.items())
    page = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(case.name)}"
            f"</title><style>{_STYLE}</style></head><body><h1>Case {html.escape(case.name)}</h1>"
            f"<p>Units: {html.escape(case.units)} (" +
            html.escape(", ".join(f"{q} {getattr(labels, q)}" for q in
                                  ("length", "velocity", "density", "mass", "inertia", "force",
                                   "frequency"))) + "). Configurations: "
            f"{len(case.configurations)}.</p>{sections}</body></html>")
    return write_text(page, out)
