"""What ``pipeline diagnose`` reads from a case: its ``[diagnose]`` table and its configurations.

The optional ``[diagnose]`` table of a case file (every key optional; defaults shown)::

    [diagnose]
    kinds = ["lumped_mass", "joint_flexibility", "member_taper", "member_curvature",
             "boundary_stiffness"]   # the candidate effects screened (pipeline.diagnose.effects)
    max_effects = 3          # look-again rounds: at most this many effects named in turn
    frequency_noise = 0.01   # standard deviation of a test frequency (fraction, 0.01 = 1 %)
    shape_noise = 0.05       # of a mode-shape coefficient (fraction); left out: estimated from data
    holdout = 3              # every holdout-th paired mode of each configuration is held out
    margin = 10.0            # BIC margin by which the named candidate beats the runner-up
    refit = 6                # candidates refitted after the linear screening
    nmodes = 30              # analysis modes; left out: 2 x test modes + 6 rigid
    before_tuning = false    # pipeline run: diagnose after stage 0 and before the tuning stages
                             # (false: after the last stage, before the report)
    flutter = true           # flutter speed before / after (default: true when [flutter] is given)

:func:`diagnose_case_settings` checks the table (unknown keys raise with the valid list, every
value has its type and range) and that every configuration has a GVT file, when the case is read
(:func:`pipeline.case.read_case`) and so before any computation; :func:`settings_from_case` gives
the :class:`pipeline.diagnose.DiagnoseSettings` of a case and :func:`configurations_from_case` its
:class:`pipeline.diagnose.ConfigurationData` (decks, GVT files, measured mass: only what the case
names).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

from structures.common.errors import InputError

#: The keys of ``[diagnose]`` and the type of each (pipeline.case's type names).
DIAGNOSE_KEYS = {"kinds": "str list", "max_effects": "int", "frequency_noise": "float",
                 "shape_noise": "float", "holdout": "int", "margin": "float", "refit": "int",
                 "nmodes": "int", "before_tuning": "bool", "flutter": "bool"}


def _kinds():
    from pipeline.diagnose.effects import KINDS

    return KINDS


@dataclass(frozen=True)
class DiagnoseCaseSettings:
    """The validated ``[diagnose]`` table (module docstring): the workflow's settings
    (:class:`pipeline.diagnose.DiagnoseSettings`) plus where ``pipeline run`` runs the stage
    (``before_tuning``) and whether the flutter speed is computed before and after (``flutter``)."""

    kinds: tuple = ()
    max_effects: int = 3
    frequency_noise: float = 0.01
    shape_noise: float | None = None
    holdout: int = 3
    margin: float = 10.0
    refit: int = 6
    nmodes: int | None = None
    before_tuning: bool = False
    flutter: bool = False

    def __post_init__(self):
        valid = _kinds()
        kinds = tuple(self.kinds) or valid
        unknown = [k for k in kinds if k not in valid]
        if unknown:
            raise InputError(f"kinds = {list(kinds)}: unknown effect kinds {unknown}; valid: "
                             f"{list(valid)}. Fix: list some of these, or leave kinds out for all.")
        if len(set(kinds)) != len(kinds):
            raise InputError(f"kinds = {list(kinds)} repeats a kind. Fix: list each once.")
        object.__setattr__(self, "kinds", kinds)
        checks = (("max_effects", self.max_effects >= 1, "max_effects = 3"),
                  ("frequency_noise", 0.0 < self.frequency_noise < 1.0, "frequency_noise = 0.01"),
                  ("shape_noise", self.shape_noise is None or 0.0 < self.shape_noise < 1.0,
                   "shape_noise = 0.05, or leave it out to estimate it from the data"),
                  ("holdout", self.holdout >= 2, "holdout = 3 (every third mode held out)"),
                  ("margin", self.margin > 0.0, "margin = 10.0"),
                  ("refit", self.refit >= 1, "refit = 6"),
                  ("nmodes", self.nmodes is None or self.nmodes >= 1,
                   "nmodes = 30, or leave it out for 2 x test modes + 6"))
        for key, ok, example in checks:
            if not ok:
                raise InputError(f"{key} = {getattr(self, key)!r} is out of range. Fix: e.g. "
                                 f"{example}.")

    def record(self) -> dict:
        """The settings as JSON-able values (a stage's fingerprint)."""
        return {**asdict(self), "kinds": list(self.kinds)}


def diagnose_case_settings(table: dict, path, configurations, has_flutter: bool
                           ) -> DiagnoseCaseSettings:
    """Validate a case's ``[diagnose]`` table before any computation.

    Parameters
    ----------
    table : dict
        The table as TOML gives it (``{}`` for a case without one: every default).
    path : path
        The case file (for messages).
    configurations : sequence of pipeline.case.Configuration
        Every one needs a ``gvt`` file.
    has_flutter : bool
        Whether the case has ``[flutter]`` (``flutter`` defaults to it; true without it raises).

    Returns
    -------
    DiagnoseCaseSettings

    Raises
    ------
    InputError
        Unknown keys (with the valid list), values of the wrong type or out of range, unknown
        effect kinds, ``flutter = true`` without ``[flutter]``, a configuration without ``gvt``;
        the message names the file, the table, the key and the fix.
    """
    from pipeline.case import _built, _checked

    where = f"file {path}, [diagnose]"
    _checked(table, DIAGNOSE_KEYS, where)
    kinds = table.get("kinds", [])
    if "kinds" in table and not kinds:
        raise InputError(f"{where}: kinds = [] names no effect kind. Fix: list some of "
                         f"{list(_kinds())}, or leave kinds out for all.")
    if table.get("flutter") and not has_flutter:
        raise InputError(f"{where}: flutter = true needs the case's [flutter] table (the flight "
                         "points and the kernel). Fix: add [flutter], or flutter = false.")
    missing = [c.name for c in configurations if c.gvt is None]
    if missing:
        raise InputError(f"{where}: configuration(s) {missing} have no GVT file; diagnose "
                         "compares every configuration with its test. Fix: add gvt = "
                         "\"gvt.unv\" to each, or remove the configurations without a test.")
    values = {k: float(v) if DIAGNOSE_KEYS[k] == "float" else v for k, v in table.items()}
    return _built(DiagnoseCaseSettings, where, **{**values, "kinds": tuple(kinds),
                                                  "flutter": table.get("flutter", has_flutter)})


def case_diagnose_settings(case) -> DiagnoseCaseSettings:
    """The case's ``[diagnose]`` settings, or the defaults (checked the same way) without one."""
    if case.diagnose is not None:
        return case.diagnose
    return diagnose_case_settings({}, case.path, case.configurations, case.flutter is not None)


def settings_from_case(case):
    """The workflow settings of a case (its ``[diagnose]`` table or the defaults).

    Parameters
    ----------
    case : pipeline.case.Case

    Returns
    -------
    pipeline.diagnose.DiagnoseSettings
    """
    from pipeline.diagnose import DiagnoseSettings

    s = case_diagnose_settings(case)
    return DiagnoseSettings(kinds=s.kinds, max_effects=s.max_effects,
                            frequency_noise=s.frequency_noise, shape_noise=s.shape_noise,
                            holdout=s.holdout, margin=s.margin, refit=s.refit, nmodes=s.nmodes)


def configurations_from_case(case, decks=None) -> tuple:
    """Every configuration's model, GVT and measured mass, read from what the case names.

    Parameters
    ----------
    case : pipeline.case.Case
    decks : mapping, optional
        configuration name -> deck replacing the case's (e.g. a tuned deck).

    Returns
    -------
    tuple of pipeline.diagnose.ConfigurationData
        In the case's order; ``measured_mass`` None when the configuration states none.

    Raises
    ------
    InputError
        A configuration without ``gvt`` (naming it and the fix); a deck or GVT file the readers
        reject (structures.bdf.read_model, structures.gvt.load_gvt).
    """
    from pipeline.diagnose import ConfigurationData
    from structures.bdf import read_model
    from structures.gvt import load_gvt

    decks = dict(decks or {})
    out = []
    for c in case.configurations:
        if c.gvt is None:
            raise InputError(f"case {case.path}, configuration {c.name}: no GVT file; diagnose "
                             "compares the model with the test. Fix: add gvt = \"gvt.unv\" to "
                             "the configuration.")
        deck = Path(decks.get(c.name, c.deck))
        out.append(ConfigurationData(name=c.name, model=read_model(deck), gvt=load_gvt(c.gvt),
                                     measured_mass=dict(c.measured_mass) or None, deck=deck))
    return tuple(out)
