"""The TOML case file: what to run, on which decks, with which settings.

Example (``data/bah_wing/case.toml``)::

    name = "bah_wing"
    units = "si"

    [[configurations]]
    name = "baseline"
    deck = "bah_plane.bdf"   # relative to the case file
    nmodes = 10
    gvt = "gvt.unv"          # optional: the configuration's GVT (UFF 15/55 or netCDF)
    measured_mass = { weight = 18950.0, x_cg = 0.10 }   # optional: measured mass properties

    [flutter]                # optional: run the decks' FLUTTER cards
    kernel = "quartic"       # doublet-lattice kernel integration: quartic or parabolic
    flutter_ids = [502]      # FLUTTER cards to run (default: the case control's FMETHOD)

Unknown keys raise with the list of valid ones, so a typo never passes silently.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

from structures.assembly import MASS_OPTIONS
from structures.errors import InputError
from structures.massprops import check_measured_mass

UNIT_SYSTEMS = ("si", "english_in", "english_ft")


def _check_keys(table: dict, cls, where: str) -> None:
    valid = {f.name for f in fields(cls)} - {"path"}
    unknown = sorted(set(table) - valid)
    if unknown:
        raise InputError(f"{where}: unknown keys {unknown}; valid: {sorted(valid)}.")


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
            raise InputError(f"configuration name {self.name!r} must be letters, digits, '_' or '-'.")
        if not Path(self.deck).exists():
            raise InputError(f"configuration {self.name}: deck {self.deck} does not exist. Fix: give a "
                             "path relative to the case file.")
        if self.mass not in MASS_OPTIONS:
            raise InputError(f"configuration {self.name}: mass = {self.mass!r}; valid: "
                             f"{', '.join(MASS_OPTIONS)}.")
        if self.nmodes is not None and self.nmodes < 1:
            raise InputError(f"configuration {self.name}: nmodes = {self.nmodes} must be >= 1.")


KERNELS = ("quartic", "parabolic")


@dataclass(frozen=True)
class FlutterSettings:
    """``[flutter]``: run each configuration's FLUTTER cards (modes -> GAFs -> p-k / k)."""

    kernel: str = "quartic"
    flutter_ids: tuple = ()

    def __post_init__(self):
        if self.kernel not in KERNELS:
            raise InputError(f"[flutter] kernel = {self.kernel!r}; valid: {', '.join(KERNELS)}.")
        object.__setattr__(self, "flutter_ids", tuple(int(i) for i in self.flutter_ids))


@dataclass(frozen=True)
class Case:
    """A whole case: name, unit system, configurations and optional stage settings."""

    name: str
    configurations: tuple
    units: str = "si"
    flutter: FlutterSettings | None = None
    tuning: Mapping | None = None  # the raw [tuning] table, validated by pipeline.cmd_tune
    path: Path | None = None

    def __post_init__(self):
        if self.units not in UNIT_SYSTEMS:
            raise InputError(f"case {self.name}: units = {self.units!r}; valid: "
                             f"{', '.join(UNIT_SYSTEMS)}.")
        if not self.configurations:
            raise InputError(f"case {self.name}: no [[configurations]]. Fix: add at least one with "
                             "name and deck.")
        names = [c.name for c in self.configurations]
        if len(set(names)) != len(names):
            raise InputError(f"case {self.name}: duplicate configuration names {names}.")


def read_case(path) -> Case:
    """Read and validate a TOML case file (paths resolved relative to it)."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"file {path}: no such case file. Fix: check the path.")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"file {path}: not valid TOML ({exc}).") from None
    _check_keys(data, Case, f"file {path}")
    base = path.parent
    configs = []
    for i, table in enumerate(data.get("configurations", [])):
        _check_keys(table, Configuration, f"file {path}, [[configurations]] #{i + 1}")
        if "name" not in table or "deck" not in table:
            raise InputError(f"file {path}, [[configurations]] #{i + 1}: 'name' and 'deck' are required.")
        table = dict(table)
        table["deck"] = (base / table["deck"]).resolve()
        if table.get("gvt"):
            table["gvt"] = (base / table["gvt"]).resolve()
        configs.append(Configuration(**table))
    flutter = None
    if "flutter" in data:
        _check_keys(data["flutter"], FlutterSettings, f"file {path}, [flutter]")
        flutter = FlutterSettings(**data["flutter"])
    tuning = data.get("tuning")
    if tuning is not None and not isinstance(tuning, dict):
        raise InputError(f"file {path}: 'tuning' must be a table ([tuning]).")
    return Case(name=data.get("name", path.stem), configurations=tuple(configs),
                units=data.get("units", "si"), flutter=flutter,
                tuning=None if tuning is None else MappingProxyType(tuning), path=path.resolve())
