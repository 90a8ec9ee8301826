"""The TOML case file: what to run, on which decks, with which settings.

Example (``data/bah_wing/case.toml``)::

    name = "bah_wing"
    units = "si"

    [[configurations]]
    name = "baseline"
    deck = "bah_plane.bdf"   # relative to the case file
    nmodes = 10
    gvt = "gvt.unv"          # optional: the configuration's GVT (UFF 15/55 or netCDF), or
                             # its frequencies alone as a CSV table (pipeline diagnose only;
                             # structures.gvt.read_frequency_table)
    measured_mass = { weight = 18950.0, x_cg = 0.10 }   # optional: measured mass properties, or
                             # a JSON file: measured_mass = "mass.json" (structures.massprops.
                             # read_measured_mass: {"weight", "cg", "inertia_cg"})

    [flutter]                # optional: run the decks' FLUTTER cards
    kernel = "quartic"       # doublet-lattice kernel integration: quartic or parabolic
    flutter_ids = [502]      # FLUTTER cards to run (default: the case control's FMETHOD)
    structural_damping = 0.01   # optional: g on every mode, replaces the decks' SDAMP table
    solver = "pk"            # how PK/PKNL flight points are solved: "pk" (p-k), "g" (g-method),
                             # "p" (p-method on a rational fit); solvers = { 502 = "g" } per FLUTTER id
    envelope = { mach = [0.2, 0.6], velocity = [300.0, 320.0] }  # optional: V_D per Mach, model units

    [flutter.matched]        # optional: matched-point flutter instead of the decks' FLUTTER cards
    mach = [0.130, 0.160]    # one p-k line per Mach number (0 < M < 1)
    altitude = [-1000.0, 20000.0]   # range, swept from high to low (US76 -5 km .. 86 km)
    altitude_units = "ft"    # "ft" or "m"
    points = 60              # flight points per Mach line: US76 density, V = M a(h)
    method = "pknl"          # p-k at each matched point (the only method for now)

    [selection]              # optional: participation-based mode selection (defaults shown)
    primary = 0.90           # primary modes: with the rigid modes, >= 90 % of every critical root
    secondary = 0.98         # secondary modes: the next ones up to 98 %
    rigid_hz = 0.05          # in-vacuo modes below this frequency are rigid-body modes
    flutter_modes = 2        # critical roots: the first N flutter crossings of every sweep

    [loop]                   # optional: the tuning <-> flutter loop of pipeline run
    stages = 3               # at most this many tuning stages after the baseline (stage 0)
    standard = "MIL-STD-1540C"  # or "NASA-STD-5002": the primary-mode targets that stop the loop

    [tuning]                 # optional: pipeline tune, and the loop's design variables (schema in
                             # pipeline.cmd_tune's docstring; the loop keeps its constraints and
                             # design-change prior and takes the rest of its objective from the
                             # selection, pipeline.loop)

    [diagnose]               # optional: pipeline diagnose's settings (schema in
                             # pipeline.diagnose.inputs; every configuration needs a gvt)

:func:`read_case` checks the whole file before anything is computed: unknown keys raise with the
list of valid ones, every value has the type its key needs (an integer is never a bool or a float,
a list of FLUTTER ids is never a bare number or a string), and every deck, GVT file and restart
history named exists. Each message names the file, the table, the key, the value given and the
expected type.
"""
from __future__ import annotations

import fnmatch
import tomllib  # Python >= 3.11 (pyproject requires-python)
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

from flutter.solve import SOLVERS
from flutter.summary import Envelope
from structures.acceptance import MIL_STD_1540C, NASA_STD_5002, AcceptanceCriteria
from structures.assembly import MASS_OPTIONS
from structures.common.errors import InputError
from structures.massprops import check_measured_mass, read_measured_mass
from structures.units import UNIT_SYSTEMS, unit_labels

KERNELS = ("quartic", "parabolic")
STANDARDS = {c.name: c for c in (MIL_STD_1540C, NASA_STD_5002)}

# expected type -> (test, words for the message, example value)
_KINDS = {
    "str": (lambda v: isinstance(v, str), "a string", '"text"'),
    "int": (lambda v: isinstance(v, int) and not isinstance(v, bool), "an integer", "10"),
    "float": (lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and v == v
              and abs(v) != float("inf"), "a finite number", "1.0"),
    "int list": (lambda v: isinstance(v, list) and all(
        isinstance(i, int) and not isinstance(i, bool) for i in v), "a list of integers", "[502]"),
    "list": (lambda v: isinstance(v, list), "a list", "[...]"),
    "str list": (lambda v: isinstance(v, list) and all(isinstance(i, str) for i in v),
                 "a list of strings", '["lumped_mass"]'),
    "bool": (lambda v: isinstance(v, bool), "a boolean", "true"),
    "float list": (lambda v: isinstance(v, list) and len(v) > 0 and all(
        _KINDS["float"][0](i) for i in v), "a non-empty list of finite numbers", "[0.2, 0.6]"),
    "table": (lambda v: isinstance(v, dict), "a table", "{ ... }"),
    "table or str": (lambda v: isinstance(v, (dict, str)), "a table or a file name", "{ ... }"),
    "table list": (lambda v: isinstance(v, list) and all(isinstance(i, dict) for i in v),
                   "a list of tables ([[...]])", "[{ ... }]"),
}
#: Examples shown in the fix of a wrongly typed key (default: the type's example).
_EXAMPLES = {"measured_mass": "{ weight = 18950.0, x_cg = 0.1 }", "mass": '"lumped"',
             "deck": '"wing.bdf"', "gvt": '"gvt.unv"', "kernel": '"quartic"', "units": '"si"',
             "mass_targets": "{ weight = 1500.0 }", "test_modes": "[7, 8, 9]",
             "fields": '[["PBAR", 11, "I1"]]', "method": '"slsqp"', "index": '"*:frequency:*"',
             "envelope": "{ mach = [0.2, 0.6], velocity = [300.0, 320.0] }",
             "standard": '"MIL-STD-1540C"', "structural_damping": "0.01", "primary": "0.9",
             "secondary": "0.98", "stages": "3", "flutter_modes": "2",
             "altitude": "[-1000.0, 20000.0]", "altitude_units": '"ft"', "points": "60"}
_TOML_TYPES = {str: "a string", bool: "a boolean", int: "an integer", float: "a number",
               list: "a list", dict: "a table"}

#: The keys of every table and the type of each.
CASE_KEYS = {"name": "str", "units": "str", "configurations": "table list", "flutter": "table",
             "selection": "table", "loop": "table", "tuning": "table", "diagnose": "table"}
CONFIGURATION_KEYS = {"name": "str", "deck": "str", "nmodes": "int", "mass": "str", "gvt": "str",
                      "measured_mass": "table or str"}
FLUTTER_KEYS = {"kernel": "str", "flutter_ids": "int list", "structural_damping": "float",
                "envelope": "table", "matched": "table", "solver": "str", "solvers": "table"}
ENVELOPE_KEYS = {"mach": "float list", "velocity": "float list"}
MATCHED_KEYS = {"mach": "float list", "altitude": "float list", "altitude_units": "str",
                "points": "int", "method": "str"}
#: metres per unit of ``[flutter.matched] altitude``
ALTITUDE_UNITS = {"ft": 0.3048, "m": 1.0}
MATCHED_METHODS = ("pknl",)
SELECTION_KEYS = {"primary": "float", "secondary": "float", "rigid_hz": "float",
                  "flutter_modes": "int"}
LOOP_KEYS = {"stages": "int", "standard": "str"}
TUNING_KEYS = {"method": "str", "maxiter": "int", "shape_method": "str", "restart": "str",
               "allowed_violation": "float", "out": "str", "variables": "table list",
               "objective": "table list", "constraints": "table list",
               "configurations": "table"}
VARIABLE_KEYS = {"name": "str", "fields": "list", "lower": "float", "upper": "float",
                 "scale": "float"}
OBJECTIVE_KEYS = {"index": "str", "weight": "float"}
CONSTRAINT_KEYS = {"index": "str", "limit": "float"}
TUNING_CONFIGURATION_KEYS = {"test_modes": "int list", "mass_targets": "table",
                             "mass_references": "table"}


def checked(table: dict, schema: dict, where: str, required=()) -> dict:
    """``table`` after checking its keys against ``schema`` (key -> kind) and the values' types."""
    unknown = sorted(set(table) - set(schema))
    if unknown:
        raise InputError(f"{where}: unknown keys {unknown}; valid: {sorted(schema)}.")
    missing = [k for k in required if k not in table]
    if missing:
        raise InputError(f"{where}: {', '.join(repr(k) for k in missing)} "
                         f"{'is' if len(missing) == 1 else 'are'} required. Fix: add "
                         + ", ".join(f"{k} = ..." for k in missing) + ".")
    for key, value in table.items():
        test, words, example = _KINDS[schema[key]]
        if not test(value):
            given = _TOML_TYPES.get(type(value), type(value).__name__)
            raise InputError(f"{where}: {key} = {value!r} is {given}; expected {words}. "
                             f"Fix: write e.g. {key} = {_EXAMPLES.get(key, example)}.")
    return table


def built(cls, where: str, **values):
    """``cls(**values)``, with the file and table put in front of a range error's message."""
    try:
        return cls(**values)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None


def _existing(base: Path, name: str, where: str, what: str) -> Path:
    path = (base / name).resolve()
    if not path.is_file():
        raise InputError(f"{where}: {what} {name!r} -> {path} does not exist. Fix: give a path "
                         "relative to the case file.")
    return path


@dataclass(frozen=True)
class Configuration:
    """One structural configuration (e.g. empty / full fuel): a deck and its settings."""

    name: str
    deck: Path
    nmodes: int | None = None
    mass: str = "deck"
    gvt: Path | None = None
    measured_mass: Mapping = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "measured_mass", MappingProxyType(check_measured_mass(
            dict(self.measured_mass), f"configuration {self.name}, measured_mass")))
        if not self.name or not self.name.replace("_", "").replace("-", "").isalnum():
            raise InputError(f"configuration name {self.name!r} must be letters, digits, '_' or "
                             "'-'. Fix: rename it, e.g. name = \"full_fuel\".")
        if not Path(self.deck).is_file():
            raise InputError(f"configuration {self.name}: deck {self.deck} does not exist. Fix: give a "
                             "path relative to the case file.")
        if self.gvt is not None and not Path(self.gvt).is_file():
            raise InputError(f"configuration {self.name}: gvt {self.gvt} does not exist. Fix: give a "
                             "path relative to the case file.")
        if self.mass not in MASS_OPTIONS:
            raise InputError(f"configuration {self.name}: mass = {self.mass!r}; valid: "
                             f"{', '.join(MASS_OPTIONS)}.")
        if self.nmodes is not None and self.nmodes < 1:
            raise InputError(f"configuration {self.name}: nmodes = {self.nmodes} must be >= 1. "
                             "Fix: give a positive number of modes or leave it out.")


@dataclass(frozen=True)
class MatchedSettings:
    """``[flutter.matched]``: matched-point flutter in place of the decks' FLUTTER cards.

    One p-k line per Mach number: ``points`` altitudes from the top of the ``altitude`` range
    down to its bottom (in ``altitude_units``), each at the US76 density and V = M a(h)
    (pipeline.flight_points).
    """

    mach: tuple
    altitude: tuple
    altitude_units: str
    points: int = 60
    method: str = "pknl"

    def __post_init__(self):
        object.__setattr__(self, "mach", tuple(float(m) for m in self.mach))
        object.__setattr__(self, "altitude", tuple(float(h) for h in self.altitude))
        if self.altitude_units not in ALTITUDE_UNITS:
            raise InputError(f"altitude_units = {self.altitude_units!r}; valid: "
                             f"{', '.join(ALTITUDE_UNITS)}.")
        if not all(0.0 < m < 1.0 for m in self.mach):
            raise InputError(f"mach = {list(self.mach)}: every Mach number must be in (0, 1) (the "
                             "doublet lattice is subsonic). Fix: e.g. mach = [0.13, 0.16].")
        if len(set(self.mach)) != len(self.mach):
            raise InputError(f"mach = {list(self.mach)} repeats a Mach number. Fix: list each "
                             "once.")
        low, high = self.altitude_range_m if len(self.altitude) == 2 else (0.0, 0.0)
        if len(self.altitude) != 2 or low == high:
            raise InputError(f"altitude = {list(self.altitude)} must be a range of two different "
                             "altitudes. Fix: e.g. altitude = [-1000.0, 20000.0].")
        if low < -5000.0 or high > 86000.0:
            raise InputError(f"altitude = {list(self.altitude)} {self.altitude_units} is outside "
                             "the US76 atmosphere (-5 km .. 86 km). Fix: check the range and "
                             "altitude_units.")
        if self.points < 2:
            raise InputError(f"points = {self.points} must be >= 2. Fix: e.g. points = 60.")
        if self.method not in MATCHED_METHODS:
            raise InputError(f"method = {self.method!r}; valid: {', '.join(MATCHED_METHODS)}.")

    @property
    def altitude_range_m(self) -> tuple[float, float]:
        """(lowest, highest) altitude of the range, m."""
        metres = ALTITUDE_UNITS.get(self.altitude_units, 1.0)
        return min(self.altitude) * metres, max(self.altitude) * metres


@dataclass(frozen=True)
class FlutterSettings:
    """``[flutter]``: run each configuration's FLUTTER cards (modes -> GAFs -> p-k / k), or the
    matched points of ``matched`` (:class:`MatchedSettings`) instead.

    ``structural_damping`` (g, e.g. 0.01) replaces the decks' SDAMP tables when given;
    ``envelope`` is the flight envelope whose 1.15 x speed the flutter boundary is held against;
    ``solver`` solves every PK / PKNL request and the matched points (flutter.solve.SOLVERS), and
    ``solvers`` (FLUTTER id -> solver, stored as sorted pairs) overrides it per FLUTTER card.
    """

    kernel: str = "quartic"
    flutter_ids: tuple = ()
    structural_damping: float | None = None
    envelope: Envelope | None = None
    matched: MatchedSettings | None = None
    solver: str = "pk"
    solvers: tuple = ()

    def __post_init__(self):
        if self.kernel not in KERNELS:
            raise InputError(f"kernel = {self.kernel!r}; valid: {', '.join(KERNELS)}.")
        object.__setattr__(self, "flutter_ids", tuple(int(i) for i in self.flutter_ids))
        pairs = self.solvers.items() if isinstance(self.solvers, dict) else self.solvers
        try:
            pairs = tuple(sorted((int(k), str(v)) for k, v in pairs))
        except (TypeError, ValueError):
            raise InputError(f"solvers = {self.solvers!r}: give FLUTTER ids and solver names, e.g. "
                             "solvers = { 502 = \"g\" }.") from None
        object.__setattr__(self, "solvers", pairs)
        for name in (self.solver,) + tuple(v for _, v in pairs):
            if name not in SOLVERS:
                raise InputError(f"solver = {name!r}; valid: {', '.join(sorted(SOLVERS))}. Fix: "
                                 "e.g. solver = \"pk\" (p-k), \"g\" (g-method) or \"p\" "
                                 "(p-method on a rational fit).")
        if self.matched is not None and self.solvers:
            raise InputError("solvers (per FLUTTER id) and [flutter.matched] were both given. Fix: "
                             "the matched points are solved by solver = ...; remove solvers.")
        if self.matched is not None and self.flutter_ids:
            raise InputError(f"flutter_ids = {list(self.flutter_ids)} and [flutter.matched] both "
                             "choose the flight points. Fix: remove flutter_ids to run the matched "
                             "points, or [flutter.matched] to run the decks' FLUTTER cards.")
        if self.structural_damping is not None and not 0.0 <= self.structural_damping < 1.0:
            raise InputError(f"structural_damping = {self.structural_damping} must be a g value in "
                             "[0, 1). Fix: e.g. structural_damping = 0.01 (1 %).")


@dataclass(frozen=True)
class SelectionSettings:
    """``[selection]``: thresholds of the participation-based mode selection (fractions)."""

    primary: float = 0.90
    secondary: float = 0.98
    rigid_hz: float = 0.05
    flutter_modes: int = 2

    def __post_init__(self):
        if not 0.0 < self.primary <= self.secondary <= 1.0:
            raise InputError(f"primary = {self.primary}, secondary = {self.secondary}: need "
                             "0 < primary <= secondary <= 1. Fix: e.g. primary = 0.9, "
                             "secondary = 0.98.")
        if not self.rigid_hz >= 0.0:
            raise InputError(f"rigid_hz = {self.rigid_hz} must be >= 0. Fix: e.g. rigid_hz = 0.05.")
        if self.flutter_modes < 1:
            raise InputError(f"flutter_modes = {self.flutter_modes} must be >= 1. Fix: e.g. "
                             "flutter_modes = 2.")


@dataclass(frozen=True)
class LoopSettings:
    """``[loop]``: at most ``stages`` tuning stages; stop when ``standard``'s primary-mode targets
    hold (structures.acceptance)."""

    stages: int = 3
    standard: str = "MIL-STD-1540C"

    def __post_init__(self):
        if self.stages < 0:
            raise InputError(f"stages = {self.stages} must be >= 0. Fix: e.g. stages = 3.")
        if self.standard not in STANDARDS:
            raise InputError(f"standard = {self.standard!r}; valid: {', '.join(STANDARDS)}.")

    @property
    def criteria(self) -> AcceptanceCriteria:
        """The standard's acceptance limits."""
        return STANDARDS[self.standard]


@dataclass(frozen=True)
class TuningSettings:
    """The validated ``[tuning]`` section of a case file (see :mod:`pipeline.cmd_tune`).

    ``variables`` holds :class:`structures.design.DesignVariable`; ``objective`` and
    ``constraints`` hold (index pattern, weight or limit); ``per_configuration`` holds
    (configuration name, {test_modes, mass_targets, mass_references}).
    """

    variables: tuple
    objective: tuple
    constraints: tuple = ()
    method: str = "slsqp"
    maxiter: int = 50
    shape_method: str = "nelson"
    restart: Path | None = None
    allowed_violation: float = 0.05
    out: Path | None = None
    per_configuration: tuple = ()

    def __post_init__(self):
        from structures.sensitivity import SHAPE_METHODS
        from structures.tuning import METHODS

        if self.method not in METHODS:
            raise InputError(f"method = {self.method!r}; valid: {', '.join(METHODS)}.")
        if self.shape_method not in SHAPE_METHODS:
            raise InputError(f"shape_method = {self.shape_method!r}; valid: "
                             f"{', '.join(SHAPE_METHODS)}.")
        if self.maxiter < 1:
            raise InputError(f"maxiter = {self.maxiter} must be >= 1. Fix: e.g. "
                             "maxiter = 50.")


@dataclass(frozen=True)
class Case:
    """A whole case: name, unit system, configurations and optional stage settings."""

    name: str
    configurations: tuple
    units: str = "si"
    flutter: FlutterSettings | None = None
    tuning: TuningSettings | None = None
    path: Path | None = None
    selection: SelectionSettings = SelectionSettings()
    loop: LoopSettings | None = None
    diagnose: object = None   # pipeline.diagnose.inputs.DiagnoseCaseSettings ([diagnose])

    def __post_init__(self):
        if self.units not in UNIT_SYSTEMS:
            raise InputError(f"case {self.name}: units = {self.units!r}; valid: "
                             f"{', '.join(UNIT_SYSTEMS)}.")
        if not self.configurations:
            raise InputError(f"case {self.name}: no [[configurations]]. Fix: add at least one with "
                             "name and deck.")
        names = [c.name for c in self.configurations]
        if len(set(names)) != len(names):
            raise InputError(f"case {self.name}: duplicate configuration names {names}. Fix: give "
                             "each configuration its own name.")
        if self.loop is not None and self.loop.stages > 0:
            missing = [c.name for c in self.configurations if c.gvt is None]
            if self.tuning is None or self.flutter is None or missing:
                raise InputError(
                    f"case {self.name}: [loop] with stages = {self.loop.stages} tunes to the GVT "
                    "and selects modes from flutter: it needs [tuning] (design variables), "
                    "[flutter] and a gvt file for every configuration"
                    + (f" (missing for {missing})" if missing else "") + ". Fix: add them, or "
                    "stages = 0.")


def _index_pattern(pattern: str, configurations: set, where: str) -> str:
    """A tuning index name or glob, checked before anything runs: CONFIG:KIND:MODES with a
    configuration of the case (or ``design:change:VARIABLE``) and a kind of structures.indices."""
    from structures.indices import KINDS

    parts = pattern.split(":")
    kinds = (*KINDS, "change")
    if len(parts) != 3 or not (
            any(fnmatch.fnmatchcase(c, parts[0]) for c in (*configurations, "design"))
            and any(fnmatch.fnmatchcase(k, parts[1]) for k in kinds)):
        raise InputError(f"{where}: index = {pattern!r} names no index of this case: an index is "
                         f"CONFIGURATION:KIND:MODES with a configuration of {sorted(configurations)} "
                         f"and a kind of {list(KINDS)} (or design:change:VARIABLE); globs allowed. "
                         f"Fix: e.g. index = \"{sorted(configurations)[0]}:frequency:*\".")
    return pattern


def _tuning(table: dict, path: Path, case_name: str, configs: tuple) -> TuningSettings:
    from structures.design import DesignVariable

    where = f"file {path}, [tuning]"
    checked(table, TUNING_KEYS, where)
    base = path.parent
    variables = []
    for i, v in enumerate(table.get("variables", [])):
        at = f"file {path}, [[tuning.variables]] #{i + 1}"
        checked(v, VARIABLE_KEYS, at, required=("name", "fields"))
        for f in v["fields"]:
            if not (isinstance(f, list) and len(f) == 3 and isinstance(f[0], str)
                    and _KINDS["int"][0](f[1]) and isinstance(f[2], str)):
                raise InputError(f"{at}: fields entry {f!r} is not [card, id, field]. Fix: write "
                                 'e.g. fields = [["PBAR", 11, "I1"]].')
        variables.append(built(DesignVariable, at, name=v["name"],
                                fields=tuple(tuple(f) for f in v["fields"]), lower=v.get("lower"),
                                upper=v.get("upper"), scale=v.get("scale")))
    objective, constraints = [], []
    names = {c.name for c in configs}
    for i, term in enumerate(table.get("objective", [])):
        at = f"file {path}, [[tuning.objective]] #{i + 1}"
        checked(term, OBJECTIVE_KEYS, at, ("index",))
        objective.append((_index_pattern(term["index"], names, at), float(term.get("weight", 1.0))))
    for i, term in enumerate(table.get("constraints", [])):
        at = f"file {path}, [[tuning.constraints]] #{i + 1}"
        checked(term, CONSTRAINT_KEYS, at, ("index", "limit"))
        constraints.append((_index_pattern(term["index"], names, at), float(term["limit"])))
    per = []
    for name, sub in table.get("configurations", {}).items():
        at = f"file {path}, [tuning.configurations.{name}]"
        if name not in names:
            raise InputError(f"{at}: names no configuration; valid: {sorted(names)}.")
        if not isinstance(sub, dict):
            raise InputError(f"{at}: {sub!r} is not a table. Fix: write "
                             f"[tuning.configurations.{name}] with test_modes = [...].")
        checked(sub, TUNING_CONFIGURATION_KEYS, at)
        for key in ("mass_targets", "mass_references"):
            if key in sub:
                check_measured_mass(sub[key], f"{at}, {key}")
        per.append((name, MappingProxyType(dict(sub))))
    restart = table.get("restart")
    return built(
        TuningSettings, where, variables=tuple(variables), objective=tuple(objective),
        constraints=tuple(constraints),
        method=table.get("method", "slsqp"), maxiter=table.get("maxiter", 50),
        shape_method=table.get("shape_method", "nelson"),
        restart=None if not restart else _existing(base, restart, where, "restart history"),
        allowed_violation=float(table.get("allowed_violation", 0.05)),
        out=(base / table.get("out", f"{case_name}_tuning")).resolve(),
        per_configuration=tuple(per))


def read_case(path) -> Case:
    """Read and validate a whole TOML case file (paths resolved relative to it).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    Case

    Raises
    ------
    InputError
        Missing or non-TOML file, unknown keys, values of the wrong type or out of range, decks,
        GVT files or restart histories that do not exist; the message names file, table and key.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"file {path}: no such case file. Fix: check the path.")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"file {path}: not valid TOML ({exc}). Fix: correct the line named.") from None
    checked(data, CASE_KEYS, f"file {path}")
    base = path.parent
    configs = []
    for i, table in enumerate(data.get("configurations", [])):
        where = f"file {path}, [[configurations]] #{i + 1}"
        table = dict(checked(table, CONFIGURATION_KEYS, where, required=("name", "deck")))
        table["deck"] = _existing(base, table["deck"], where, "deck")
        if "gvt" in table:
            table["gvt"] = _existing(base, table["gvt"], where, "gvt")
        if isinstance(table.get("measured_mass"), str):
            table["measured_mass"] = read_measured_mass(
                _existing(base, table["measured_mass"], where, "measured_mass"))
        configs.append(built(Configuration, where, **table))
    flutter = None
    units = data.get("units", "si")
    if units not in UNIT_SYSTEMS:  # Case names the valid systems
        units = None
    if "flutter" in data:
        where = f"file {path}, [flutter]"
        table = dict(checked(data["flutter"], FLUTTER_KEYS, where))
        if "envelope" in table:
            at = f"{where}, envelope"
            checked(table["envelope"], ENVELOPE_KEYS, at, required=("mach", "velocity"))
            table["envelope"] = built(Envelope, at, mach=table["envelope"]["mach"],
                                       velocity=table["envelope"]["velocity"],
                                       units=unit_labels(units).velocity)
        if "matched" in table:
            at = f"file {path}, [flutter.matched]"
            checked(table["matched"], MATCHED_KEYS, at,
                     required=("mach", "altitude", "altitude_units"))
            table["matched"] = built(MatchedSettings, at, **table["matched"])
        flutter = built(FlutterSettings, where, **table)
    sections = {}
    for key, cls, schema in (("selection", SelectionSettings, SELECTION_KEYS),
                             ("loop", LoopSettings, LOOP_KEYS)):
        if key in data:
            where = f"file {path}, [{key}]"
            sections[key] = built(cls, where, **checked(data[key], schema, where))
    name = data.get("name", path.stem)
    tuning = None if "tuning" not in data else _tuning(data["tuning"], path, name, tuple(configs))
    if "diagnose" in data:   # the table's schema and checks: pipeline.diagnose.inputs
        from pipeline.diagnose.inputs import diagnose_case_settings
        sections["diagnose"] = diagnose_case_settings(data["diagnose"], path, tuple(configs),
                                                      flutter is not None)
    return built(Case, f"file {path}", name=name, configurations=tuple(configs),
                  units=data.get("units", "si"), flutter=flutter, tuning=tuning,
                  path=path.resolve(), **sections)
