"""The report's diagnose section, from the run folder's ``diagnose/`` (no computation).

:func:`diagnose_section` reads ``diagnose/diagnose.json`` (pipeline.diagnose.outputs) and shows the
verdict, the named effects with their location, parameters (with their standard errors) and what
they add (deck units), the ranked candidates, the gap before and after (frequency errors, MAC,
cross-orthogonality, mass properties, flutter speed) with units, the notes, and the
candidate-ranking and gap figures
(``diagnose/*.png``) embedded. A run folder without ``diagnose/diagnose.json`` gives an empty
section.
"""
from __future__ import annotations

import html
import json
from pathlib import Path

from pipeline.diagnose.outputs import flat_gap, gap_unit, parameter_text
from pipeline.report_figures import png_data_uri
from pipeline.report_tables import fmt, note, table
from structures.units import UnitLabels

#: Candidates listed in the table.
TOP = 10


def _value(value) -> str:
    return fmt(float("nan") if value is None else value, ".4g")


def _location(location: dict) -> str:
    return "; ".join(f"{k}: {', '.join(str(i) for i in v)}"
                     for k, v in (location or {}).items() if v) or "\u2013"


def _gap_rows(before: dict, after: dict, labels: UnitLabels) -> list:
    before, after = flat_gap(before), flat_gap(after)
    return [(key, gap_unit(key, labels.velocity), _value(before.get(key)), _value(after.get(key)))
            for key in sorted(set(before) | set(after))]


def diagnose_section(run_dir, labels: UnitLabels) -> str:
    """The HTML section of a run folder's diagnosis ("" when it has none).

    Parameters
    ----------
    run_dir : path
        The run folder.
    labels : structures.units.UnitLabels
        The case's unit labels (the flutter speed's unit).

    Returns
    -------
    str
        ``<h2 id="diagnose">`` and its tables and figures.
    """
    folder = Path(run_dir) / "diagnose"
    path = folder / "diagnose.json"
    if not path.is_file():
        return ""
    record = json.loads(path.read_text())
    out = ('<h2 id="diagnose">Diagnose: the missing effect</h2>'
           f"<p>Verdict: <b>{html.escape(str(record['verdict']))}</b>.</p>")
    effects = record.get("effects") or []
    if effects:
        out += table(("round", "kind", "location", "parameters (+- standard error)",
                      "adds (deck units)", "also fits within the margin"), [
            (i, e["kind"], _location(e.get("location")), parameter_text(e),
             ", ".join(f"{k} = {_value(v)}" for k, v in (e.get("quantities") or {}).items()),
             "; ".join(f"{o['label']} (+{_value(o['score'])})" for o in e.get("elsewhere") or [])
             or "-")
            for i, e in enumerate(effects, 1)], table_id="diagnose-effects")
    else:
        out += note("No effect was named, so the model is unchanged.")
    suspension = record.get("suspension")
    if suspension:
        out += "<h3>The test's suspension, from its suspension modes</h3>"
        unit = f"{labels.force}/{labels.length}"
        out += table(("site [grids]", *(f"k_{d} [{unit}]" for d in "xyz")),
                     [("+".join(str(g) for g in site), *(_value(v) for v in k))
                      for site, k in zip(suspension["sites"], suspension["stiffness"])],
                     table_id="diagnose-suspension")
        out += table(("configuration", "test frequency [Hz]", "model frequency [Hz]"),
                     [(name, _value(t), _value(m))
                      for name, pair in suspension["frequencies"].items()
                      for t, m in zip(pair["test"], pair["model"])],
                     table_id="diagnose-suspension-frequencies")
        out += note(f"The first {len(suspension['sites'])} effects are the test's suspension: "
                    "they are in the as-tested decks (the gap after), not in the diagnosed "
                    "decks that flutter and tuning take.")
    candidates = list(record.get("candidates") or [])
    out += (f"<h3>Candidates of the first round (best {min(TOP, len(candidates))} of "
            f"{len(candidates)})</h3>")
    out += table(("rank", "kind", "candidate", "location", "score [BIC difference to the best]"),
                 [(i, c["kind"], c.get("label") or "", _location(c.get("location")),
                   _value(c.get("score"))) for i, c in enumerate(candidates[:TOP], 1)],
                 table_id="diagnose-candidates")
    out += "<h3>Gap between test and analysis, before and after the named effects</h3>"
    out += table(("metric", "unit", "before", "after"),
                 _gap_rows(record.get("gap_before") or {}, record.get("gap_after") or {}, labels),
                 table_id="diagnose-gap")
    out += "".join(note(str(n)) for n in record.get("notes") or [])
    if record.get("separating_measurement"):
        out += note(f"Measurement that would separate the candidates: "
                    f"{record['separating_measurement']}")
    out += "".join(f'<img src="{png_data_uri(p.read_bytes())}" alt="diagnose {html.escape(p.stem)}"'
                   f' width="640">' for p in sorted(folder.glob("*.png")))
    return out
