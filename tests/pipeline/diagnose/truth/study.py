"""The blind study of ``pipeline.diagnose``: cases from the truth generator, the workflow run on
each through its public names only (``pipeline.case.read_case``,
``pipeline.diagnose.inputs.configurations_from_case`` / ``settings_from_case``,
``pipeline.diagnose.diagnose``), its verdict scored against ``truth.json``.

Scores (issue 14, "Must show"):

* named kind: the first named effect's kind when the verdict is "effect", else the verdict
  ("none", "ambiguous", "unexplained"); "error" when the workflow raised;
* top-1 kind accuracy: named kind == truth kind, over the library's kinds;
* location hit (a case whose kind is right): the named effect's grids or elements meet the
  truth's location grown by one element layer (``truth.json`` ``neighbours``: the element / grid
  named or its neighbour; a shared property alone is no hit, a PID can span the structure);
* no effect named on "none" data: verdict != "effect";
* an effect outside the library: "ambiguous" or "unexplained" rather than a name;
* the gap: held-out RMS frequency error and largest cross-orthogonality off-diagonal before and
  after, per case, beside the truth's own (:func:`truth_gap`: the truth models, the ones the
  test data were drawn from, against those data; their gap is the noise's, the least any model
  can reach). A case's ``truth_gap.json`` holds it; ``--truth-gap DIR ...`` computes it for
  cases run without it. Beside it, the cross-validated RMS frequency error of every paired mode
  (:mod:`pipeline.diagnose.crossval`; the truth's own: its RMS over every paired mode, it fits
  nothing): ``gap_shrinks_cross_validated`` counts a case when that RMS and the largest
  off-diagonal both drop.

Run ``python -m tests.pipeline.diagnose.truth.study [--structures frame x56 wingbox windy]
[--kinds ...] [--seeds 10] [--first-seed 0] [--noise 0.01 0.05] [--frequency-only]
[--suspension] [--out DIR]`` from the repository root (``--noise``: the test's frequency and
shape noise, :func:`make_case`; the workflow is not told it; ``--frequency-only``: the workflow
gets the frequencies alone; ``--suspension``: the truths hang on three bungees and the GVTs list
their suspension modes first):
prints the confusion matrix, the scores and the gap of every correctly named case, writes
``DIR/study.nc`` and every case's ``diagnose.json``, ``diagnose.nc`` and ``score.json``. A study
split over processes (kinds or seeds per core) is scored as one with ``--score DIR [DIR ...]``
(:func:`rescore`; no case is run). ``--oracle DIR [DIR ...]`` adds, to the cases run there, the gap
of the truth's own effect on the nominal model (:mod:`.oracle`: what the right answer scores; a
miss it shares is the data's, not the naming's) and scores them.
"""
from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

from structures.common.files import write_dataset, write_text

from .generate import (FREQUENCY_NOISE, KINDS, SHAPE_NOISE, STRUCTURE_KINDS, STRUCTURES,
                       TRUTH_DECKS, TRUTH_KINDS, make_case)
from .oracle import ORACLE_GAP, add_oracle_gap

#: Columns of the confusion matrix: every kind the workflow can name and its other verdicts.
NAMED = KINDS + ("none", "ambiguous", "unexplained", "error")
#: A case's file of the truth's own gap (:func:`truth_gap`).
TRUTH_GAP = "truth_gap.json"


def _configurations(case, frequency_only: bool) -> tuple:
    """The case's configurations, their test shapes dropped when ``frequency_only``."""
    from dataclasses import replace

    from pipeline.diagnose.inputs import configurations_from_case

    configurations = tuple(configurations_from_case(case))
    if frequency_only:
        configurations = tuple(replace(c, gvt=c.gvt.drop_vars("shape")) for c in configurations)
    return configurations


def _case_inputs(case_toml: Path, frequency_only: bool) -> tuple:
    """(configurations, settings) of a case: what the workflow is given (``frequency_only``:
    the test frequencies alone)."""
    from pipeline.case import read_case
    from pipeline.diagnose.inputs import settings_from_case

    case = read_case(case_toml)
    return _configurations(case, frequency_only), settings_from_case(case)


def diagnose_case(case_toml: Path, *, frequency_only: bool = False,
                  dataset: Path | None = None) -> dict:
    """Run the workflow on a case (only what the case names; with ``frequency_only`` its test
    frequencies alone, as a published GVT without shapes gives them); returns its JSON and, given
    ``dataset``, writes its netCDF there (the result's Dataset, as ``pipeline diagnose`` does)."""
    from pipeline.diagnose import diagnose

    result = diagnose(*_case_inputs(case_toml, frequency_only))
    if dataset is not None:
        write_dataset(result.to_dataset(), dataset)
    return result.to_json()


def case_references(case_toml: Path, frequency_only: bool = False) -> tuple:
    """(configurations, settings, references) of a case as the workflow reads and checks it
    (its ``preflight``): what a gap of another model is set against, with the workflow's
    pairing, held-out modes and noise."""
    from pipeline.diagnose import preflight

    configurations, settings = _case_inputs(case_toml, frequency_only)
    return configurations, settings, preflight(configurations, settings)[0]


def truth_gap(case_toml: Path, decks: Path, *, frequency_only: bool = False) -> dict:
    """The gap (``gap_after``'s keys) of a case's truth models against its test data.

    Each configuration's truth deck (``decks``: a ``make_case(..., decks=)`` folder) is
    analysed and set against the reference the workflow builds from the case
    (:func:`case_references`): the same pairing, held-out modes and noise as the workflow's gap.
    """
    from types import SimpleNamespace

    from pipeline.diagnose.evidence import evaluate
    from pipeline.diagnose.gap import gap_metrics
    from structures.bdf import read_model

    configurations, _, refs = case_references(case_toml, frequency_only)
    names = json.loads((Path(decks) / TRUTH_DECKS).read_text())
    evaluations = []
    for ref, conf in zip(refs, configurations):
        ev = evaluate(ref, read_model(Path(decks) / names[conf.name]))
        if ref.has_shapes:
            got = (ev.modes["grid"].values[ref.sensor_index],
                   ev.modes["component"].values[ref.sensor_index])
            if not (np.array_equal(got[0], ref.sensor_grid)
                    and np.array_equal(got[1], ref.sensor_component)):
                raise ValueError(f"{case_toml}: the truth deck of {conf.name} orders its DOFs "
                                 "unlike the analysis deck; the sensors would not line up.")
        evaluations.append(ev)
    return gap_metrics(SimpleNamespace(refs=refs), evaluations)


def add_truth_gap(folder: Path) -> dict:
    """Write ``folder / truth_gap.json`` for a case run without it: the case made again from its
    ``truth.json`` (structure, kind, seed) with its truth decks kept, its GVT files checked
    byte for byte against the folder's, then :func:`truth_gap` on the folder's case."""
    import filecmp

    folder = Path(folder)
    truth = json.loads((folder / "truth.json").read_text())
    with tempfile.TemporaryDirectory() as tmp:
        again = Path(tmp) / "case"
        noise = truth.get("noise", {"frequency": FREQUENCY_NOISE, "shape": SHAPE_NOISE})
        make_case(truth["structure"], truth["kind"], truth["seed"], again,
                  decks=Path(tmp) / "decks", noise=(noise["frequency"], noise["shape"]),
                  suspension=truth.get("suspension") is not None)
        for gvt in sorted(folder.glob("gvt_*.unv")):
            if not filecmp.cmp(gvt, again / gvt.name, shallow=False):
                raise ValueError(f"{folder}: {gvt.name} differs from the one made again: the "
                                 "generator has changed since the case was made.")
        gap = truth_gap(folder / "case.toml", Path(tmp) / "decks")
    write_text(json.dumps(gap, indent=1) + "\n", folder / TRUTH_GAP)
    return gap


def score(truth: dict, result: dict, floor: dict | None = None,
          oracle: dict | None = None) -> dict:
    """Score one verdict against its truth (module docstring); ``floor`` the truth's own gap
    (:func:`truth_gap`), ``oracle`` its effect's on the nominal model
    (:func:`.oracle.oracle_gap`), each None when not computed."""
    effect = result.get("effect") if result.get("verdict") == "effect" else None
    named = effect["kind"] if effect else result.get("verdict", "error")
    hit = False
    if effect and named == truth["kind"]:
        loc = effect["location"]
        hit = bool(set(loc.get("grids", ())) & set(truth["neighbours"]["grids"])
                   or set(loc.get("elements", ())) & set(truth["neighbours"]["elements"]))

    def gap(when, metric):
        value = (result.get(when) or {}).get(metric)
        return np.nan if value is None else float(value)

    def least(metric, of=floor):
        value = (of or {}).get(metric)
        return np.nan if value is None else float(value)

    return {"named": named, "kind_correct": named == truth["kind"], "location_hit": hit,
            "rms_before": gap("gap_before", "frequency_rms_held_out"),
            "rms_after": gap("gap_after", "frequency_rms_held_out"),
            "rms_truth": least("frequency_rms_held_out"),
            "rms_oracle": least("frequency_rms_held_out", oracle),
            "xo_before": gap("gap_before", "max_cross_orthogonality_offdiag"),
            "xo_after": gap("gap_after", "max_cross_orthogonality_offdiag"),
            "xo_truth": least("max_cross_orthogonality_offdiag"),
            "xo_oracle": least("max_cross_orthogonality_offdiag", oracle),
            "rms_expected": least("frequency_rms_held_out_expected"),
            "n_held_out": least("n_held_out"),
            "cv_before": gap("gap_before", "frequency_rms_cross_validated"),
            "cv_after": gap("gap_after", "frequency_rms_cross_validated"),
            "cv_truth": least("frequency_rms"),                 # the truth fits nothing
            "cv_oracle": least("frequency_rms_cross_validated", oracle),
            "cv_expected": gap("gap_before", "frequency_rms_cross_validated_expected")}


def _floor(folder: Path, name: str = TRUTH_GAP) -> dict | None:
    found = Path(folder) / name
    return json.loads(found.read_text()) if found.is_file() else None


def run_study(structures=STRUCTURES, kinds=TRUTH_KINDS, seeds=range(10), out=None, *,
              diagnose: dict | None = None, noise=(FREQUENCY_NOISE, SHAPE_NOISE),
              frequency_only: bool = False, suspension: bool = False,
              progress=print) -> xr.Dataset:
    """Generate and diagnose every (structure, kind, seed) case; the scored study.

    Parameters
    ----------
    structures : sequence of STRUCTURES
    kinds : sequence of TRUTH_KINDS (each structure runs those it can hold, ``STRUCTURE_KINDS``)
    seeds : sequence of int
    out : folder of the cases (``out/<structure>/<kind>/<seed>/``) and ``study.nc``
    diagnose : dict, optional, the cases' ``[diagnose]`` table (default: none, the defaults)
    noise : (frequency, shape) noise of the test data (:func:`make_case`)
    frequency_only : bool, the workflow gets the test frequencies alone (:func:`diagnose_case`)
    suspension : bool, the truths hang on three bungees and their GVTs list the suspension modes
        (:func:`make_case`)
    progress : callable(str) or None, one line per case

    Returns
    -------
    xarray.Dataset
        Per ``case``: ``structure``, ``truth_kind``, ``seed``, ``named_kind``, ``kind_correct``,
        ``location_hit``, ``seconds`` (diagnose only), ``frequency_rms_held_out`` and
        ``max_cross_orthogonality_offdiag`` on ``when`` (before, after, truth: the truth's own,
        NaN without ``truth_gap.json``; oracle: the truth's effect on the nominal model, NaN
        without ``oracle_gap.json``, :mod:`.oracle`), ``error``;
        ``confusion(truth_kind_row, named_kind_column)`` counts; attrs: the scores
        ``top1_kind_accuracy``, ``location_accuracy``, ``none_kept``, ``outside_not_named``,
        ``gap_shrinks`` (fractions, NaN when no case counts) and the numbers of cases.
    """
    out = Path(out)
    rows = []
    for structure in structures:
        for kind in (k for k in kinds if k in STRUCTURE_KINDS[structure]):
            for seed in seeds:
                folder = out / structure / kind / str(seed)
                with tempfile.TemporaryDirectory() as decks:
                    case = make_case(structure, kind, seed, folder, diagnose=diagnose,
                                     decks=decks, noise=noise, suspension=suspension)
                    floor = truth_gap(case, Path(decks), frequency_only=frequency_only)
                write_text(json.dumps(floor, indent=1) + "\n", folder / TRUTH_GAP)
                truth = json.loads((folder / "truth.json").read_text())
                start, error = time.perf_counter(), ""
                try:
                    result = diagnose_case(case, frequency_only=frequency_only,
                                           dataset=folder / "diagnose.nc")
                except Exception as exc:  # a study records a crash and goes on
                    result, error = {"verdict": "error"}, f"{type(exc).__name__}: {exc}"
                seconds = time.perf_counter() - start
                write_text(json.dumps(result, indent=1) + "\n", folder / "diagnose.json")
                row = {"structure": structure, "truth_kind": kind, "seed": int(seed),
                       "seconds": seconds, "error": error, **score(truth, result, floor)}
                write_text(json.dumps(row, indent=1) + "\n", folder / "score.json")
                rows.append(row)
                if progress:
                    progress(f"{structure:6s} {kind:18s} seed {seed:3d}: {row['named']:18s} "
                             f"location {'hit' if row['location_hit'] else '-':3s} "
                             f"{seconds:6.1f} s {error[:80]}")
    ds = study_dataset(rows)
    write_dataset(ds, out / "study.nc")
    return ds


def rescore(folders) -> xr.Dataset:
    """The scored study of the cases already run under ``folders`` (each as ``run_study``'s
    ``out``: ``<structure>/<kind>/<seed>/`` with ``truth.json`` and ``diagnose.json``); a case in
    a later folder replaces the same case in an earlier one (a rerun). Scored by :func:`score`
    again; ``seconds`` and ``error`` from the case's ``score.json``, or without one the
    workflow's own time (its note "diagnose took ... s").

    Parameters
    ----------
    folders : sequence of path

    Returns
    -------
    xarray.Dataset, as :func:`run_study`'s.
    """
    cases = {}
    for folder in map(Path, folders):
        for found in sorted(folder.glob("*/*/*/diagnose.json")):
            structure, kind, seed = found.parts[-4:-1]
            cases[structure, kind, int(seed)] = found.parent
    if not cases:
        raise FileNotFoundError(f"no <structure>/<kind>/<seed>/diagnose.json under {folders}")
    rows = []
    for (structure, kind, seed), case in sorted(cases.items()):
        result = json.loads((case / "diagnose.json").read_text())
        stored = case / "score.json"
        row = json.loads(stored.read_text()) if stored.is_file() else {
            "seconds": next((float(n.split()[2]) for n in result.get("notes", ())
                             if n.startswith("diagnose took")), np.nan), "error": ""}
        rows.append({"structure": structure, "truth_kind": kind, "seed": seed,
                     "seconds": row["seconds"], "error": row["error"],
                     **score(json.loads((case / "truth.json").read_text()), result,
                             _floor(case), _floor(case, ORACLE_GAP))})
    return study_dataset(rows)


#: The gaps a case is scored on: the workflow's before and after, the truth model's own
#: (:func:`truth_gap`) and its effect's on the nominal model (:mod:`.oracle`).
WHEN = ("before", "after", "truth", "oracle")


def _when(col: dict, measure: str) -> np.ndarray:
    """(n_case, len(WHEN)) of a measure's columns ``<measure>_<when>``."""
    return np.array([col[f"{measure}_{w}"] for w in WHEN], float).T


def study_dataset(rows: list[dict]) -> xr.Dataset:
    """The scored study as a Dataset (see ``run_study``) from per-case rows of ``score``."""
    col = {k: [r[k] for r in rows] for k in rows[0]}
    truth = np.array(col["truth_kind"], dtype=str)
    named = np.array(col["named"], dtype=str)
    confusion = np.array([[np.sum((truth == t) & (named == n)) for n in NAMED]
                          for t in TRUTH_KINDS], dtype=int)
    ds = xr.Dataset(
        {"structure": ("case", np.array(col["structure"], dtype=str)),
         "truth_kind": ("case", truth), "seed": ("case", np.array(col["seed"], int)),
         "named_kind": ("case", named),
         "kind_correct": ("case", np.array(col["kind_correct"], bool)),
         "location_hit": ("case", np.array(col["location_hit"], bool)),
         "seconds": ("case", np.array(col["seconds"], float), {"units": "s"}),
         "error": ("case", np.array(col["error"], dtype=str)),
         "frequency_rms_held_out": (("case", "when"), _when(col, "rms"), {"units": "%"}),
         "frequency_rms_held_out_expected": ("case", np.array(col["rms_expected"], float),
                                             {"units": "%"}),
         "n_held_out": ("case", np.array(col["n_held_out"], float)),
         "frequency_rms_cross_validated": (("case", "when"), _when(col, "cv"), {"units": "%"}),
         "frequency_rms_cross_validated_expected": ("case", np.array(col["cv_expected"], float),
                                                    {"units": "%"}),
         "max_cross_orthogonality_offdiag": (("case", "when"), _when(col, "xo")),
         "confusion": (("truth_kind_row", "named_kind_column"), confusion)},
        coords={"case": np.arange(len(rows)), "when": list(WHEN),
                "truth_kind_row": list(TRUTH_KINDS), "named_kind_column": list(NAMED)})
    ds.attrs.update(scores(ds))
    return ds


def _fraction(mask: np.ndarray) -> float:
    return float(np.mean(mask)) if mask.size else float("nan")


def scores(ds: xr.Dataset) -> dict:
    """The issue's scores of a study Dataset (fractions; NaN where no case counts)."""
    truth, named = ds["truth_kind"].values, ds["named_kind"].values
    lib = np.isin(truth, KINDS)
    right = lib & ds["kind_correct"].values
    rms, xo = ds["frequency_rms_held_out"].values, ds["max_cross_orthogonality_offdiag"].values
    cv = ds["frequency_rms_cross_validated"].values
    xo_drops = (xo[:, 1] < xo[:, 0]) | np.isnan(xo[:, 0])
    shrinks = (rms[:, 1] < rms[:, 0]) & xo_drops
    return {"top1_kind_accuracy": _fraction(right[lib]),
            "location_accuracy": _fraction(ds["location_hit"].values[right]),
            "none_kept": _fraction(~np.isin(named[truth == "none"], KINDS)),
            "outside_not_named": _fraction(np.isin(named[truth == "outside"],
                                                   ("ambiguous", "unexplained"))),
            "gap_shrinks": _fraction(shrinks[right]),
            "gap_shrinks_cross_validated": _fraction(((cv[:, 1] < cv[:, 0]) & xo_drops)[right]),
            "errors": int(np.sum(named == "error")), "cases": int(truth.size)}


def confusion_text(ds: xr.Dataset) -> str:
    """The confusion matrix and the scores as text."""
    cols = list(NAMED)
    short = {c: c.replace("member_", "").replace("_flexibility", "").replace("_stiffness", "")
             .replace("lumped_", "")[:9] for c in cols}
    lines = ["truth \\ named       " + " ".join(f"{short[c]:>9s}" for c in cols)]
    for t in TRUTH_KINDS:
        row = ds["confusion"].sel(truth_kind_row=t).values
        if row.sum():
            lines.append(f"{t:20s}" + " ".join(f"{v:9d}" for v in row))
    lines.append("")
    lines += [f"{k}: {v:.3f}" if isinstance(v, float) else f"{k}: {v}" for k, v in ds.attrs.items()
              if k in ("top1_kind_accuracy", "location_accuracy", "none_kept",
                       "outside_not_named", "gap_shrinks", "gap_shrinks_cross_validated",
                       "errors", "cases")]
    lines.append(f"diagnose time per case: median {np.median(ds['seconds'].values):.1f} s, "
                 f"max {np.max(ds['seconds'].values):.1f} s")
    return "\n".join(lines)


#: Half the last printed digit of the gap text's measures: an off-diagonal, an RMS error [%].
RESOLUTION = {"xo": 0.5e-3, "rms": 0.005}


def gap_text(ds: xr.Dataset) -> str:
    """The gap of every correctly named case (a library kind named right): held-out RMS
    frequency error [%] and largest cross-orthogonality off-diagonal before -> after, marked
    where one of them does not drop, and how many cases each drops in."""
    from pipeline.diagnose.gap import HELD_OUT_SIGMAS, held_out_upper

    right = ds["kind_correct"].values & np.isin(ds["truth_kind"].values, KINDS)
    rms, xo = ds["frequency_rms_held_out"].values, ds["max_cross_orthogonality_offdiag"].values
    rms_drops, xo_drops = rms[:, 1] < rms[:, 0], (xo[:, 1] < xo[:, 0]) | np.isnan(xo[:, 0])
    cv = ds["frequency_rms_cross_validated"].values
    cv_drops = cv[:, 1] < cv[:, 0]
    quiet = rms[:, 0] <= held_out_upper(ds["frequency_rms_held_out_expected"].values,
                                         ds["n_held_out"].values)
    oracle = (cv[:, 3] < cv[:, 0]) & ((xo[:, 3] < xo[:, 0]) | np.isnan(xo[:, 0]))
    known = ~np.isnan(cv[:, 3])
    # on a measure the named effect misses, the truth's effect lowers it by no more than the
    # printed resolution either: the miss is the data's
    shared = known & ((~cv_drops & (cv[:, 3] > cv[:, 0] - RESOLUTION["rms"]))
                      | (~xo_drops & (xo[:, 3] > xo[:, 0] - RESOLUTION["xo"])))
    lines = [f"gap of the {int(right.sum())} correctly named cases (held-out RMS frequency error "
             "%, largest cross-orthogonality off-diagonal, cross-validated RMS frequency error "
             "% of every paired mode; before -> after (the truth's own; what noise and scatter "
             "alone give) [the truth's effect on the nominal model, where computed]):"]
    for i in np.flatnonzero(right):
        same = abs(xo[i, 1] - xo[i, 0]) < RESOLUTION["xo"]          # equal as printed
        marks = [m for m, ok in (("RMS up", rms_drops[i]),
                                 ("off-diagonal the same" if same else "off-diagonal up",
                                  xo_drops[i]),
                                 ("held-out within noise before", not quiet[i]),
                                 ("cross-validated RMS not down", cv_drops[i]),
                                 ("the truth's effect no better", not shared[i]))
                 if not ok]
        right_effect = (f" [{xo[i, 3]:.3f} {cv[i, 3]:6.2f}]" if known[i] else "")
        lines.append(f"  {ds['structure'].values[i]:6s} {ds['truth_kind'].values[i]:18s} seed "
                     f"{int(ds['seed'].values[i]):3d}: {rms[i, 0]:6.2f} -> {rms[i, 1]:6.2f} "
                     f"({rms[i, 2]:5.2f}; "
                     f"{float(ds['frequency_rms_held_out_expected'].values[i]):5.2f})  "
                     f"{xo[i, 0]:.3f} -> {xo[i, 1]:.3f} ({xo[i, 2]:.3f})  "
                     f"{cv[i, 0]:6.2f} -> {cv[i, 1]:6.2f} ({cv[i, 2]:5.2f}; "
                     f"{float(ds['frequency_rms_cross_validated_expected'].values[i]):5.2f})"
                     f"{right_effect}  {', '.join(marks)}".rstrip())
    both = right & rms_drops & xo_drops
    lines.append(f"drops: RMS {int(np.sum(right & rms_drops))}, off-diagonal "
                 f"{int(np.sum(right & xo_drops))}, both {int(both.sum())} of {int(right.sum())}; "
                 f"of the {int(np.sum(right & ~both))} others, "
                 f"{int(np.sum(right & ~both & quiet))} "
                 "start with a held-out error within what noise and scatter alone give "
                 f"({HELD_OUT_SIGMAS:g} standard deviations); cross-validated RMS "
                 f"{int(np.sum(right & cv_drops))}, it and the off-diagonal both "
                 f"{int(np.sum(right & cv_drops & xo_drops))} of {int(right.sum())}")
    miss = right & ~(cv_drops & xo_drops) & known
    if np.any(right & known):
        lines.append(f"the truth's effect on the nominal model (computed for "
                     f"{int(np.sum(right & known))}): its cross-validated RMS and off-diagonal "
                     f"both drop in {int(np.sum(right & known & oracle))}; of the "
                     f"{int(miss.sum())} cases above where the named effect's do not, on the "
                     f"measure missed it does no better than {RESOLUTION['xo']:g} (off-diagonal) "
                     f"or {RESOLUTION['rms']:g} % (RMS) below before in "
                     f"{int(np.sum(miss & shared))}")
    return "\n".join(lines)


def _fill_in(folders, name: str, add) -> None:
    """``add(case)`` for every case run under ``folders`` (its ``diagnose.json`` written) that
    lacks the file ``name``."""
    for folder in folders or ():
        for found in sorted(Path(folder).glob("*/*/*/diagnose.json")):
            if not (found.parent / name).is_file():
                add(found.parent)
                print(f"{name}: {found.parent}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--structures", nargs="+", default=list(STRUCTURES), choices=STRUCTURES)
    parser.add_argument("--kinds", nargs="+", default=list(TRUTH_KINDS), choices=TRUTH_KINDS)
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0 .. N-1")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--noise", type=float, nargs=2, metavar=("FREQUENCY", "SHAPE"),
                        default=[FREQUENCY_NOISE, SHAPE_NOISE],
                        help="the test data's noise: standard deviations of each frequency and of "
                             "each shape DOF (fractions of the frequency, of the shape's RMS)")
    parser.add_argument("--frequency-only", action="store_true",
                        help="give the workflow the test frequencies alone (no shapes)")
    parser.add_argument("--suspension", action="store_true",
                        help="hang every truth on three bungees and list its suspension modes "
                             "in the GVT (free structures)")
    parser.add_argument("--out", type=Path, default=Path("runs/diagnose_blind_study"))
    parser.add_argument("--score", type=Path, nargs="+", metavar="DIR",
                        help="score the cases already run under these folders (a later folder's "
                             "case replaces an earlier one's) instead of running any")
    parser.add_argument("--oracle", type=Path, nargs="+", metavar="DIR",
                        help="write oracle_gap.json (the truth's effect on the nominal model) "
                             "for the cases under these folders that lack it, then score them")
    parser.add_argument("--truth-gap", type=Path, nargs="+", metavar="DIR",
                        help="write truth_gap.json for the cases under these folders that lack "
                             "it, then score them")
    args = parser.parse_args(argv)
    _fill_in(args.truth_gap, TRUTH_GAP, add_truth_gap)
    _fill_in(args.oracle, ORACLE_GAP, add_oracle_gap)
    if args.truth_gap or args.oracle:
        args.score = list(args.score or ()) + list(args.truth_gap or ()) + list(args.oracle or ())
    if args.score:
        ds = rescore(args.score)
    else:
        ds = run_study(args.structures, args.kinds,
                       range(args.first_seed, args.first_seed + args.seeds), args.out,
                       noise=tuple(args.noise), frequency_only=args.frequency_only,
                       suspension=args.suspension)
    print(confusion_text(ds))
    print(gap_text(ds))


if __name__ == "__main__":
    main()
