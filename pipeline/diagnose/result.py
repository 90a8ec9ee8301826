"""The result of :func:`pipeline.diagnose.diagnose`: verdict, named effects, ranking, gap.

``to_json()`` gives the issue's schema (plus ``effects`` for every look-again round, ``nominal``,
``calibrated``, ``gap_models`` and ``rounds``); ``to_dataset()`` a netCDF-able Dataset: the
first round's candidate table on dim ``rank`` and the gap metrics on (``metric``, ``when``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, NamedTuple

import numpy as np
import xarray as xr

from pipeline.diagnose.mirror import site_values
from pipeline.diagnose.quantities import quantities
from structures.common.errors import InputError

VERDICTS = ("effect", "none", "ambiguous", "unexplained")
#: Scalar gap metrics (keys of ``gap_before`` / ``gap_after``) put in the Dataset.
GAP_METRICS = ("frequency_rms_held_out", "frequency_rms", "frequency_rms_held_out_expected",
               "max_cross_orthogonality_offdiag",
               "max_cross_orthogonality_offdiag_held_out",
               "max_cross_orthogonality_offdiag_unfiltered", "mac_min", "mac_min_held_out",
               "mac_mean", "frequency_rms_cross_validated",
               "frequency_rms_cross_validated_expected",
               "max_cross_orthogonality_offdiag_cross_validated", "mac_min_cross_validated")

#: Which model each gap is of (JSON ``gap_models``). The pipeline stage writes both decks.
GAP_MODELS = {
    "before": "the nominal model with its nominal parameters calibrated (E of each material, "
              "CONM2 mass scale: 'calibrated') and no effect; deck <config>_calibrated.bdf",
    "after": "the nominal model with the named effects and the nominal parameters refitted with "
             "them ('nominal'); deck <config>_diagnosed.bdf (the calibrated deck when no effect "
             "was named); with a suspension identified from the test's suspension modes, the "
             "modal and mass metrics are of that model on the suspension, deck "
             "<config>_as_tested.bdf, and the flutter speed of the free one, <config>_diagnosed.bdf"}


class EffectRecord(NamedTuple):
    """A named effect: the candidate, its fitted parameter values (npar,) and its score: the
    lead of :func:`pipeline.diagnose.verdict.decide` in its round, the lower of the runner-up's
    and "none"'s scores minus the effect's, each score chi^2 / c + p ln n (c the round's
    dispersion; "none"'s less 2 ln of the candidates screened, its prior odds). ``elsewhere``
    lists the candidates of its kind at other sites that score within the margin of it
    (:func:`pipeline.diagnose.rounds.sites_elsewhere`): its site is then uncertain. ``errors``
    (npar,) are the standard errors of ``values`` (:mod:`pipeline.diagnose.linearised`; inf:
    not determined by the data), None when not estimated (a suspension)."""

    candidate: object
    values: np.ndarray
    score: float
    elsewhere: tuple = ()
    errors: np.ndarray | None = None


class CandidateScore(NamedTuple):
    """A ranked candidate of the first round.

    ``score`` is its score minus the best's (0 for the best), the scores the verdict compared
    (:func:`pipeline.diagnose.verdict.round_scores`: chi2_modal / c + chi2_stated + p ln n with
    the round's modal dispersion c, "none"'s less 2 ln of the candidates screened);
    ``refitted`` says whether the chi^2 comes from the nonlinear refit (else from the linearised
    fit); ``kind`` "none" is the model with its nominal parameters only.
    """

    kind: str
    location: Mapping
    score: float
    label: str
    refitted: bool


def location_dict(location) -> dict:
    if location is None:
        return {"grids": [], "elements": [], "properties": []}
    return location.as_dict() if hasattr(location, "as_dict") else dict(location)


def suspension_effects(suspension: Mapping | None) -> int:
    """How many of the effects are the suspension's (its sites, added first), 0 without one."""
    return len(suspension["sites"]) if suspension else 0


def effect_json(record: EffectRecord) -> dict:
    """{"kind", "location", "parameters", "standard_errors", "quantities", "label", "score",
    "sites", "elsewhere"} of a named effect.

    ``parameters`` are relative to scales of the model of the effect's round
    (:mod:`pipeline.diagnose.effects`); ``quantities`` is what they add to the model in deck units
    (:mod:`pipeline.diagnose.quantities`: masses, spring stiffnesses, section factors, rises).
    ``sites`` lists the places it acts on, each with its ``location``, ``parameters`` and
    ``quantities``: one for a one-sided effect, two for a mirror pair
    (:mod:`pipeline.diagnose.mirror`; ``location`` is then the union of both and ``parameters``
    and ``quantities`` the first site's: a pair of masses adds ``parameters["mass"]`` at each,
    twice in all). ``elsewhere`` lists the candidates of its kind at other sites that the data
    do not tell from it (each ``kind``, ``label``, ``location``, ``score`` above the effect's,
    below the margin, and ``refitted``: False when scored by its linearised fit): empty when its
    site is as certain as its kind. ``standard_errors`` holds each parameter's (null: not
    determined by the data; the whole entry null when not estimated).
    """
    cand = record.candidate
    errors = (None if record.errors is None else
              {name: float(e) if np.isfinite(e) else None
               for name, e in zip(cand.parameters, record.errors)})
    per_site = quantities(cand, record.values)
    return {"kind": cand.kind, "location": location_dict(cand.location),
            "parameters": {name: float(v) for name, v in zip(cand.parameters, record.values)},
            "standard_errors": errors, "quantities": per_site[0], "label": cand.label,
            "score": float(record.score),
            "sites": [{"location": location_dict(site.location),
                       "parameters": {name: float(v) for name, v in zip(site.parameters, x)},
                       "quantities": q}
                      for (site, x), q in zip(site_values(cand, record.values), per_site)],
            "elsewhere": [dict(e) for e in record.elsewhere]}


def _clean(value):
    """JSON-safe copy: numpy scalars and arrays to Python, NaN to None."""
    if isinstance(value, Mapping):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_clean(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return None if not np.isfinite(value) else float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


@dataclass(frozen=True)
class DiagnoseResult:
    """What diagnose found.

    Attributes
    ----------
    verdict : {"effect", "none", "ambiguous", "unexplained"}
    effects : tuple of EffectRecord, the named effects in the order they were found.
    candidates : tuple of CandidateScore, the first round's ranking (best first).
    gap_before, gap_after : mapping
        ``frequency_rms_held_out``, ``frequency_rms`` [%], ``max_cross_orthogonality_offdiag``
        (``_held_out``: rows of the held-out modes; on the significant SEREP coordinates,
        ``_unfiltered`` on all, :mod:`pipeline.diagnose.gap`), ``mac_min``, ``mac_min_held_out``,
        ``mac_mean`` (None without shapes), ``mass`` {quantity: % error of the
        configuration with the largest |error|}, ``mass_by_configuration``, ``flutter_speed``
        (None: filled by the pipeline stage); when an effect was added, the cross-validated
        ``frequency_rms_cross_validated`` [%], ``frequency_rms_cross_validated_expected`` [%],
        ``n_cross_validated``, ``max_cross_orthogonality_offdiag_cross_validated`` and
        ``mac_min_cross_validated`` (:mod:`pipeline.diagnose.crossval`). :data:`GAP_MODELS`
        says which model each is.
    notes : tuple of str
    separating_measurement : str or None, for an ambiguous verdict.
    nominal : mapping {parameter: relative change} of the final model (``gap_after``'s).
    calibrated : mapping {parameter: relative change} of the nominal calibration without
        effects (``gap_before``'s model).
    rounds : tuple of mapping, per look-again round: its ``verdict`` and the ``reason``
        (:func:`pipeline.diagnose.verdict.decide`: ``gain``, ``no_gain``, ``runner_up``,
        ``held_out``, ``past_veto``, ``held_out_reversal``, the last two when the held-out
        modes took part in naming (past a veto of the best, or reversing the training
        ranking), or ``unconfirmed`` (a later round's best that the held-out modes do not
        support by the margin: not named); before the load path and bound checks, which can
        still turn an ``effect`` into ``unexplained``, and the stability check, which makes it
        ``unexplained`` with the reason ``unstable``), ``vetoed`` (the labels of the fits
        the held-out modes contradict by more than the margin), ``n_data`` (training
        residuals), ``n_modal`` (the modal ones among them: frequencies and shapes),
        ``dispersion`` (the modal dispersion c of the round's scores and held-out evidence,
        :func:`pipeline.diagnose.verdict.round_scores`), ``n_held_out`` (held-out residual
        entries) and ``held_out_modes_entries`` (per held-out mode), "none"'s ``none_chi2``,
        ``none_chi2_modal``, ``none_bic``, ``none_n_params``, ``none_held_out_chi2`` and
        ``none_held_out_modes_chi2`` (per mode), and the refitted candidates (``fits``, the
        ``best`` and the ``runner_up``: kind, label, chi2, chi2_modal, bic, n_params,
        held_out_chi2, held_out_modes_chi2, held_out_modes_kept (the modes either model
        reproduces), held_out_evidence, parameters), ``alike`` (the labels of the fits that
        predict the same data as the best, :func:`pipeline.diagnose.gap.indistinguishable`:
        one explanation with it, not its rival); the held-out chi^2 is over the held-out
        modes' residual entries (:func:`pipeline.diagnose.predictive.held_out_modes`,
        :func:`pipeline.diagnose.predictive.held_out_evidence`); ``load_path`` (when the
        round's verdict named an effect, or would have: the best spring between two grids,
        :mod:`pipeline.diagnose.loadpath`: its ``grids``, ``stiffness``, ``chi2``, ``n_pairs``,
        ``score`` and the named effect's ``named_score``), else null; ``gap`` (when the round
        named an effect: the gap of the model with it and every earlier one, keys as
        ``gap_after``; the last such round's is ``gap_after``) and ``nominal`` (its model's nominal
        parameters, as the top-level ``nominal``), else null; ``detailed`` (when the named
        effect was added in its detailed form, :mod:`pipeline.diagnose.detail`, a joint with
        one compliance per CBUSH component, a support spring in every free direction or a mass
        with one share per grid of its neighbourhood: its
        ``parameters``, ``chi2`` and ``bic`` and the named form's ``named_chi2`` and
        ``named_bic``; the effect's parameters are then the detailed ones); ``neighbours``
        (when a named joint was compared with its neighbouring joints,
        :func:`pipeline.diagnose.detail.located`: per joint tried, the named one first, its
        ``label``, two-parameter ``chi2`` and ``bic``, and its detailed form's
        ``detailed_chi2`` and ``detailed_bic``, null when that form does not lower its BIC;
        the joint added is the form of least BIC), else null; ``splits`` (when the round named
        an effect: the effect refitted on each other split of the paired modes,
        :func:`pipeline.diagnose.crossval.extend`: its ``shift``, the split's ``gain`` in score
        for it, > 0 where the split supports it, and the refitted ``parameters``), else absent.
    suspension : mapping or None, the suspension identified from the test's suspension modes
        before the rounds (:mod:`pipeline.diagnose.suspension`; its sites are the first
        ``effects``): ``sites`` (grids per site), ``stiffness`` (per site k_x, k_y, k_z, force /
        length), ``chi2``, ``bic``, ``n_data``, ``frequencies`` (per configuration the paired
        ``test`` and ``model`` suspension frequencies, Hz), ``alternatives`` (the other refitted
        hypotheses: label and BIC), ``gap`` (the gap with the suspension added, keys as
        ``gap_after``); None when the test lists no suspension modes.
    """

    verdict: str
    effects: tuple
    candidates: tuple
    gap_before: Mapping
    gap_after: Mapping
    notes: tuple = ()
    separating_measurement: str | None = None
    nominal: Mapping = field(default_factory=dict)
    rounds: tuple = ()
    calibrated: Mapping = field(default_factory=dict)
    suspension: Mapping | None = None

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise InputError(f"diagnose result: verdict {self.verdict!r} is not one of "
                             f"{list(VERDICTS)}.")

    def to_json(self) -> dict:
        """The issue's JSON schema (see the module docstring)."""
        effects = [effect_json(r) for r in self.effects]
        n_hung = suspension_effects(self.suspension)
        return _clean({
            "verdict": self.verdict,
            "effect": (effects[n_hung] if len(effects) > n_hung and self.verdict == "effect"
                       else None),
            "effects": effects,
            "candidates": [{"kind": c.kind, "location": location_dict(c.location),
                            "score": c.score, "label": c.label, "refitted": c.refitted}
                           for c in self.candidates],
            "gap_before": dict(self.gap_before), "gap_after": dict(self.gap_after),
            "notes": list(self.notes), "separating_measurement": self.separating_measurement,
            "nominal": dict(self.nominal), "calibrated": dict(self.calibrated),
            "gap_models": dict(GAP_MODELS), "rounds": list(self.rounds),
            "suspension": None if self.suspension is None else dict(self.suspension)})

    def to_dataset(self) -> xr.Dataset:
        """Candidate table on ``rank`` (1 = best) and the gap metrics on (metric, when)."""
        rank = np.arange(1, len(self.candidates) + 1)
        gap = np.array([[np.nan if (self.gap_before.get(m) is None) else self.gap_before[m],
                         np.nan if (self.gap_after.get(m) is None) else self.gap_after[m]]
                        for m in GAP_METRICS], float)
        ds = xr.Dataset(
            {"kind": ("rank", np.array([c.kind for c in self.candidates], dtype=str)),
             "label": ("rank", np.array([c.label for c in self.candidates], dtype=str)),
             "score": ("rank", np.array([c.score for c in self.candidates], float),
                       {"long_name": "verdict score (chi^2 / c + p ln n, none with its prior "
                                     "odds) minus the best's", "units": "1"}),
             "refitted": ("rank", np.array([c.refitted for c in self.candidates], bool)),
             "gap": (("metric", "when"), gap,
                     {"long_name": "gap between model and test", "units":
                      "% for frequency_rms*, 1 for cross-orthogonality and MAC"})},
            coords={"rank": rank, "metric": list(GAP_METRICS), "when": ["before", "after"]},
            attrs={"verdict": self.verdict,
                   "effects": "; ".join(f"{r.candidate.kind}: {r.candidate.label}"
                                        for r in self.effects) or "none",
                   "separating_measurement": self.separating_measurement or ""})
        return ds
