"""The diagnose stage's outputs in a run folder, and the verdict as text.

:func:`write_diagnosis` runs :func:`pipeline.diagnose.diagnose` on a case's configurations and
writes, below ``folder`` (the stage's staging folder, run-folder layout):

- ``diagnose/diagnose.json``: the verdict record (:meth:`DiagnoseResult.to_json`);
- ``diagnose/diagnose.nc``: :meth:`DiagnoseResult.to_dataset`;
- ``diagnose/<config>_calibrated.bdf``: each configuration's deck with the calibrated nominal
  parameters (``result.calibrated``), the model of ``gap_before``;
- ``diagnose/<config>_diagnosed.bdf``: that with the final nominal parameters (``result.nominal``)
  and the named effects (:func:`pipeline.diagnose.apply.write_effect_deck`), the model of
  ``gap_after``, when an effect was named; a suspension identified from the test's suspension
  modes (``result.suspension``, the first ``len(sites)`` effects) belongs to the test, not to
  the aircraft: it is left out of this deck (the free model that flutter and tuning take) and
  written on top of it in ``diagnose/<config>_as_tested.bdf``, the model of ``gap_after``'s
  modal and mass metrics;
- ``diagnose/candidates.png`` and ``diagnose/gap.png`` (:mod:`pipeline.diagnose.plots`);
- with the case's ``[flutter]`` and ``[diagnose] flutter`` on: ``diagnose/<config>/flutter/*``,
  the flutter solutions of the calibrated decks (``diagnose/<config>/flutter_before/*``) and of
  the diagnosed decks, through the one chain (pipeline.chain.case_flutter on the baseline's grid
  GAFs). ``gap_before["flutter_speed"]`` / ``gap_after["flutter_speed"]`` is the lowest flutter
  crossing of the calibrated / diagnosed decks (the calibrated ones' when no effect was named), in
  the model's velocity unit: each gap metric is of one model (``result.GAP_MODELS``).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from flutter.results import is_flutter
from structures.common.files import read_dataset, write_dataset, write_json
from structures.bdf import read_model
from structures.units import unit_labels

#: The stage's folder in the run folder.
FOLDER = "diagnose"
#: Unit of each scalar gap metric (mass-property errors are in %; ``flutter_speed`` in the unit
#: system's velocity).
GAP_UNITS = {"frequency_rms_held_out": "%", "frequency_rms": "%",
             "frequency_rms_held_out_expected": "%", "n_held_out": "-",
             "max_cross_orthogonality_offdiag": "-",
             "max_cross_orthogonality_offdiag_held_out": "-",
             "max_cross_orthogonality_offdiag_unfiltered": "-", "mac_min": "-",
             "mac_min_held_out": "-", "mac_mean": "-", "frequency_rms_cross_validated": "%",
             "frequency_rms_cross_validated_expected": "%", "n_cross_validated": "-",
             "max_cross_orthogonality_offdiag_cross_validated": "-",
             "mac_min_cross_validated": "-"}


def final_deck(run_dir, config: str) -> Path:
    """The deck of the model a diagnosis ended with, for configuration ``config`` of a run folder:
    ``diagnose/<config>_diagnosed.bdf`` when an effect was named, else the calibrated deck (the
    models of ``gap_after``, :data:`pipeline.diagnose.result.GAP_MODELS`)."""
    folder = Path(run_dir) / FOLDER
    diagnosed = folder / f"{config}_diagnosed.bdf"
    return diagnosed if diagnosed.is_file() else folder / f"{config}_calibrated.bdf"


def lowest_flutter_speed(summaries) -> float | None:
    """The lowest velocity of the flutter crossings (not divergence) of ``summaries``.

    Parameters
    ----------
    summaries : iterable of list of dict
        Flutter ``summary.json`` entries (DESIGN.md section 6), one list per configuration.

    Returns
    -------
    float or None
        None when no summary has a flutter crossing.
    """
    speeds = [float(c["velocity"]) for entries in summaries for c in entries
              if is_flutter(c["kind"])]
    return min(speeds) if speeds else None


def _diagnosed_flutter(case, folder: Path, run_dir: Path, decks: dict, aero: dict,
                       progress=None, name: str = "flutter") -> float | None:
    """Lowest flutter speed of ``decks`` ({configuration: deck}; their flutter written to
    ``folder / FOLDER / <config> / name``)."""
    from pipeline.chain import case_flutter, configuration_modes

    summaries = []
    for config in case.configurations:
        diagnosed = replace(config, deck=decks[config.name])
        modes, _ = configuration_modes(diagnosed)
        grid = read_dataset(run_dir / f"stage0/aero/{aero[config.name][0]}/grid_gaf.nc")
        out = folder / FOLDER / config.name / name
        out.mkdir(parents=True, exist_ok=True)
        summaries.append(case_flutter(case, diagnosed, modes, out_dir=out, progress=progress,
                                      grid_gaf=grid)["summary"])
    return lowest_flutter_speed(summaries)


def write_diagnosis(case, folder, run_dir, aero: dict | None = None, progress=None):
    """Diagnose the case's configurations and write the outputs (module docstring).

    Parameters
    ----------
    case : pipeline.case.Case
    folder : path
        Where the outputs go (``folder / "diagnose" / ...``): the stage's staging folder.
    run_dir : path
        The run folder (stage 0's flutter summaries and grid GAFs, when flutter is on).
    aero : dict, optional
        :func:`pipeline.chain.aero_groups` of the case (needed when flutter is on).
    progress : callable(str), optional
        Receives progress notes of the diagnosis and the flutter solutions.

    Returns
    -------
    pipeline.diagnose.DiagnoseResult
        With ``flutter_speed`` filled in ``gap_before`` / ``gap_after`` when flutter is on.
    """
    from pipeline.diagnose import diagnose
    from pipeline.diagnose.calibrate import write_calibrated_deck
    from pipeline.diagnose.apply import write_effect_deck
    from pipeline.diagnose.inputs import case_diagnose_settings, configurations_from_case
    from pipeline.diagnose.plots import plot_candidates, plot_gap

    folder, run_dir = Path(folder), Path(run_dir)
    options = case_diagnose_settings(case)
    configurations = configurations_from_case(case)
    result = diagnose(configurations, options.workflow, progress=progress)
    effects = [(effect[0], effect[1]) for effect in result.effects]   # (Candidate, values)
    n_hung = len(result.suspension["sites"]) if result.suspension else 0
    hung, effects = effects[:n_hung], effects[n_hung:]
    calibrated, decks = {}, {}
    for data in configurations:
        calibrated[data.name] = write_calibrated_deck(
            data.deck, folder / FOLDER / f"{data.name}_calibrated.bdf", data.model,
            result.calibrated)
        if effects or hung:
            final = folder / FOLDER / f"{data.name}_diagnosed.bdf"
            write_calibrated_deck(data.deck, final, data.model, result.nominal)
            decks[data.name] = (write_effect_deck(final, final, read_model(final), effects)
                                if effects else final)
        if hung:
            write_effect_deck(final, folder / FOLDER / f"{data.name}_as_tested.bdf",
                              read_model(final), hung)
    if options.flutter and case.flutter is not None:
        before = _diagnosed_flutter(case, folder, run_dir, calibrated, aero, progress,
                                    "flutter_before")
        after = (_diagnosed_flutter(case, folder, run_dir, decks, aero, progress)
                 if decks else before)
        result = replace(result, gap_before={**result.gap_before, "flutter_speed": before},
                         gap_after={**result.gap_after, "flutter_speed": after})
    record = result.to_json()
    write_json(record, folder / FOLDER / "diagnose.json")
    speeds = [record["gap_before"].get("flutter_speed"), record["gap_after"].get("flutter_speed")]
    dataset = result.to_dataset().assign(flutter_speed=("when", [
        float("nan") if v is None else v for v in speeds], {
            "long_name": "lowest flutter crossing speed (NaN: none, or not computed)",
            "units": unit_labels(case.units).velocity}))
    write_dataset(dataset, folder / FOLDER / "diagnose.nc")
    plot_candidates(record).savefig(folder / FOLDER / "candidates.png", dpi=90,
                                    metadata={"Software": None})
    plot_gap(record, unit_labels(case.units).velocity).savefig(
        folder / FOLDER / "gap.png", dpi=90, metadata={"Software": None})
    return result


def flat_gap(gap: dict, prefix: str = "") -> dict:
    """A gap record with nested tables flattened: ``{"mass": {"weight": -3.5}}`` becomes
    ``{"mass weight": -3.5}``."""
    out = {}
    for key, value in gap.items():
        name = f"{prefix}{key}"
        out.update(flat_gap(value, f"{name} ") if isinstance(value, dict) else {name: value})
    return out


def gap_unit(key: str, velocity: str) -> str:
    """Unit of a :func:`flat_gap` key; ``velocity`` is the unit system's velocity label."""
    if key == "flutter_speed":
        return velocity
    return "%" if key.startswith("mass") else GAP_UNITS.get(key, "")


def _number(value, fmt: str = ".3g") -> str:
    return "-" if value is None else format(float(value), fmt)


def _location(location: dict) -> str:
    return ", ".join(f"{k} {list(v)}" for k, v in (location or {}).items() if v) or "-"


def _parameters(parameters: dict) -> str:
    return ", ".join(f"{k} = {_number(v, '.4g')}" for k, v in (parameters or {}).items())


def parameter_text(effect: dict) -> str:
    """``name = value +- error`` of each parameter of a named effect's JSON record
    (``value (not determined)`` where its standard error is null, the value alone where no
    errors were estimated)."""
    errors = effect.get("standard_errors")
    if errors is None:
        return _parameters(effect.get("parameters"))
    out = []
    for k, v in (effect.get("parameters") or {}).items():
        if errors.get(k) is None:
            out.append(f"{k} = {_number(v, '.4g')} (not determined)")
        else:
            out.append(f"{k} = {_number(v, '.4g')} +- {_number(errors[k], '.2g')}")
    return ", ".join(out)


def verdict_summary(record: dict, velocity: str = "model units", top: int = 5) -> str:
    """A few lines of a diagnosis' JSON record: the verdict, each named effect with its location,
    parameters (+- standard errors, :func:`parameter_text`) and what it adds (``quantities``,
    deck units), the ``top`` candidates and the gap before -> after (``velocity``: the unit of
    the flutter speed)."""
    lines = [f"verdict: {record['verdict']}"]
    n_hung = len((record.get("suspension") or {}).get("sites") or [])
    for i, effect in enumerate(record.get("effects") or [], 1):
        lines.append(f"  effect {i}: {effect['kind']} at {_location(effect.get('location'))}: "
                     f"{parameter_text(effect)}"
                     + (" (the test's suspension, from its suspension modes)" if i <= n_hung
                        else ""))
        if effect.get("quantities"):
            lines.append(f"    adds (deck units): {_parameters(effect['quantities'])}")
        if effect.get("elsewhere"):
            lines.append("    site uncertain, also fits within the margin: " + "; ".join(
                f"{e['label']} (+{_number(e['score'], '.1f')})" for e in effect["elsewhere"]))
    candidates = list(record.get("candidates") or [])[:top]
    if candidates:
        lines.append(f"candidates (best {len(candidates)} of {len(record['candidates'])}, score: "
                     "the verdict's BIC-type score minus the best's):")
        lines += [f"  {i}. {c['kind']:<18} {_number(c.get('score'), '9.2f')}  "
                  f"{c.get('label') or _location(c.get('location'))}"
                  for i, c in enumerate(candidates, 1)]
    before, after = (flat_gap(record.get(k) or {}) for k in ("gap_before", "gap_after"))
    lines.append("gap before -> after:")
    lines += [f"  {key} [{gap_unit(key, velocity)}]: {_number(before.get(key))} -> "
              f"{_number(after.get(key))}" for key in sorted(set(before) | set(after))
              if not key.startswith("mass_by_configuration")]   # the worst is "mass"
    lines += [f"note: {n}" for n in record.get("notes") or []]
    if record.get("separating_measurement"):
        lines.append(f"separating measurement: {record['separating_measurement']}")
    return "\n".join(lines)
