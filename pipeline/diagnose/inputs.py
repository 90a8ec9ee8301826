"""What ``pipeline diagnose`` reads from a case: its ``[diagnose]`` table and its configurations.

The optional ``[diagnose]`` table of a case file (every key optional; defaults shown)::

    [diagnose]
    kinds = ["lumped_mass", "joint_flexibility", "member_taper", "member_curvature",
             "boundary_stiffness"]   # the candidate effects screened (pipeline.diagnose.effects)
    max_effects = 3          # look-again rounds: at most this many effects named in turn
    frequency_noise = 0.01   # standard deviation of a test frequency (fraction, 0.01 = 1 %)
    shape_noise = 0.05       # of a mode-shape coefficient (fraction); left out: estimated from data
    holdout = 3              # every holdout-th paired mode of each configuration is held out
                             # (2 up to a configuration's elastic test modes)
    margin = 10.0            # BIC margin by which the named effect beats the other kinds
    refit = 6                # candidates refitted after the linear screening
    nmodes = 30              # analysis modes; left out: 2 x elastic test modes + 6 rigid
    model_scatter = 0.03     # scatter of every section quantity and CONM2 (fraction)
    before_tuning = false    # pipeline run: diagnose after stage 0 and before the tuning stages
                             # (false: after the last stage, before the report)
    flutter = true           # flutter speed before / after (default: true when [flutter] is given)

:func:`diagnose_case_settings` checks the table (unknown keys raise with the valid list, every
value has its type; the ranges are checked by :class:`pipeline.diagnose.DiagnoseSettings`) and
that every configuration has a GVT file, when the case is read (:func:`pipeline.case.read_case`)
and so before any computation; :func:`settings_from_case` gives
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
                 "nmodes": "int", "model_scatter": "float", "before_tuning": "bool",
                 "flutter": "bool"}
#: The keys that are not the workflow's settings.
STAGE_KEYS = ("before_tuning", "flutter")


@dataclass(frozen=True)
class DiagnoseCaseSettings:
    """The validated ``[diagnose]`` table (module docstring): the workflow's settings
    (``workflow``, a :class:`pipeline.diagnose.DiagnoseSettings`, which checks the ranges) plus
    where ``pipeline run`` runs the stage (``before_tuning``) and whether the flutter speed is
    computed before and after (``flutter``)."""

    workflow: object
    before_tuning: bool = False
    flutter: bool = False

    def record(self) -> dict:
        """The settings as JSON-able values (a stage's fingerprint)."""
        return {**asdict(self.workflow), "before_tuning": self.before_tuning,
                "flutter": self.flutter}


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
    from pipeline.case import built, checked
    from pipeline.diagnose import DiagnoseSettings

    where = f"file {path}, [diagnose]"
    checked(table, DIAGNOSE_KEYS, where)
    if table.get("flutter") and not has_flutter:
        raise InputError(f"{where}: flutter = true needs the case's [flutter] table (the flight "
                         "points and the kernel). Fix: add [flutter], or flutter = false.")
    missing = [c.name for c in configurations if c.gvt is None]
    if missing:
        raise InputError(f"{where}: configuration(s) {missing} have no GVT file; diagnose "
                         "compares every configuration with its test. Fix: add gvt = "
                         "\"gvt.unv\" to each, or remove the configurations without a test.")
    values = {k: float(v) if DIAGNOSE_KEYS[k] == "float" else tuple(v) if k == "kinds" else v
              for k, v in table.items() if k not in STAGE_KEYS}
    return DiagnoseCaseSettings(workflow=built(DiagnoseSettings, where, **values),
                                before_tuning=table.get("before_tuning", False),
                                flutter=table.get("flutter", has_flutter))


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
    return case_diagnose_settings(case).workflow


def configurations_from_case(case) -> tuple:
    """Every configuration's model, GVT and measured mass, read from what the case names.

    Parameters
    ----------
    case : pipeline.case.Case

    Returns
    -------
    tuple of pipeline.diagnose.ConfigurationData
        In the case's order; ``measured_mass`` None when the configuration states none.

    Raises
    ------
    InputError
        A configuration without ``gvt`` (naming it and the fix); a deck or GVT file the readers
        reject (structures.bdf.read_model, structures.gvt.load_gvt; a table of test frequencies
        alone is accepted).
    """
    from pipeline.diagnose import ConfigurationData
    from structures.bdf import read_model
    from structures.gvt import load_gvt

    out = []
    for c in case.configurations:
        if c.gvt is None:
            raise InputError(f"case {case.path}, configuration {c.name}: no GVT file; diagnose "
                             "compares the model with the test. Fix: add gvt = \"gvt.unv\" to "
                             "the configuration.")
        out.append(ConfigurationData(name=c.name, model=read_model(c.deck),
                                     gvt=load_gvt(c.gvt, shapes=False),
                                     measured_mass=dict(c.measured_mass) or None,
                                     deck=Path(c.deck)))
    return tuple(out)


def check_case_data(case) -> None:
    """Every data check of the diagnosis (:func:`pipeline.diagnose.preflight`: the settings
    against the test, analysis modes, pairing, sensor DOFs, the shape-noise estimate, the
    measured mass) on what ``case`` names, before any stage of ``pipeline diagnose`` or of a
    ``pipeline run`` with a ``[diagnose]`` table computes.

    Parameters
    ----------
    case : pipeline.case.Case

    Raises
    ------
    InputError
        As :func:`configurations_from_case`, and the preflight's errors prefixed with the case
        file.
    """
    from pipeline.diagnose import preflight

    settings = settings_from_case(case)
    configurations = configurations_from_case(case)
    try:
        preflight(configurations, settings)
    except InputError as exc:
        raise InputError(f"case {case.path}: {exc}") from None
