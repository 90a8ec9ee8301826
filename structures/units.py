"""Unit labels of the case's unit system, for every printed and written number (DESIGN.md section 3).

The numbers stay in the model's own consistent units; the case file only states which system they
are (``units = "si" | "english_in" | "english_ft"``), and this table turns that name into the labels
of tables, figures, ``summary.json`` entries and netCDF ``units`` attributes. Without a case (a bare
deck) the labels say "model units" explicitly. Conversion factors to SI live in
:class:`flutter.atmosphere.Units`.
"""
from __future__ import annotations

from dataclasses import dataclass, fields

from structures.common.errors import InputError

MODEL_UNITS = "model units"


@dataclass(frozen=True)
class UnitLabels:
    """Labels of the quantities a report prints, in one consistent unit system."""

    system: str
    length: str
    velocity: str
    density: str
    mass: str
    inertia: str
    force: str
    frequency: str = "Hz"

    def __post_init__(self):
        empty = [f.name for f in fields(self) if not getattr(self, f.name)]
        if empty:
            raise InputError(f"UnitLabels: empty labels {empty}. Fix: give every quantity a label.")

    def of_mass_property(self, quantity: str, wtmass: float = 1.0) -> str:
        """Unit of a mass-properties quantity as structures.massprops names it: ``mass``,
        ``x_cg``.. (length), ``Ixx``.. ``Izx`` (inertia) and ``weight`` = mass / WTMASS, a force
        when PARAM WTMASS converts the deck's weights to mass, else the mass unit itself."""
        if quantity in ("mass", "weight"):
            return self.force if quantity == "weight" and wtmass != 1.0 else self.mass
        if quantity in ("x_cg", "y_cg", "z_cg"):
            return self.length
        if len(quantity) == 3 and quantity[0] == "I" and set(quantity[1:]) <= set("xyz"):
            return self.inertia
        raise InputError(f"unit of mass property {quantity!r} is not known. Fix: use mass, weight, "
                         "x_cg, y_cg, z_cg or Ixx .. Izx.")

    def as_dict(self) -> dict:
        """The labels as a plain dict (for ``summary.json`` entries and netCDF attrs)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


UNIT_LABELS = {
    "si": UnitLabels("si", "m", "m/s", "kg/m^3", "kg", "kg m^2", "N"),
    # slinch = lbf s^2/in: the mass unit consistent with in, s, lbf
    "english_in": UnitLabels("english_in", "in", "in/s", "lbf s^2/in^4 (slinch/in^3)",
                             "lbf s^2/in (slinch)", "lbf s^2 in (slinch in^2)", "lbf"),
    "english_ft": UnitLabels("english_ft", "ft", "ft/s", "slug/ft^3", "slug", "slug ft^2", "lbf"),
}
UNIT_SYSTEMS = tuple(UNIT_LABELS)
_MODEL = UnitLabels(MODEL_UNITS, *(MODEL_UNITS,) * 6)


def unit_labels(system: str | None = None) -> UnitLabels:
    """The labels of a named unit system; ``None`` (no case file) labels everything "model units".

    Parameters
    ----------
    system : {"si", "english_in", "english_ft"} or None

    Returns
    -------
    UnitLabels

    Raises
    ------
    InputError
        For an unknown name, listing the valid ones.
    """
    if system is None or system == MODEL_UNITS:
        return _MODEL
    if system not in UNIT_LABELS:
        raise InputError(f"unit system {system!r} is not known. Fix: use one of "
                         f"{', '.join(UNIT_SYSTEMS)} (the case file's units = ...).")
    return UNIT_LABELS[system]


def system_of(attrs: dict) -> str | None:
    """The unit system a result states in its attrs (``units`` = a known system name), else None.

    A modes Dataset read from a bare deck carries ``units = "deck"``: that says nothing about the
    system, so the labels stay "model units".
    """
    name = attrs.get("units")
    return name if name in UNIT_LABELS else None
