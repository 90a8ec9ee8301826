"""Unit labels of the case's unit system (structures.units)."""
from __future__ import annotations

import pytest

from structures.common.errors import InputError
from structures.units import MODEL_UNITS, UnitLabels, system_of, unit_labels


def test_labels_of_each_system():
    si, ips, fps = (unit_labels(s) for s in ("si", "english_in", "english_ft"))
    assert (si.length, si.velocity, si.density, si.mass, si.inertia, si.force) == \
        ("m", "m/s", "kg/m^3", "kg", "kg m^2", "N")
    assert (ips.length, ips.velocity, ips.mass, ips.force) == ("in", "in/s", "lbf s^2/in (slinch)",
                                                                "lbf")
    assert ips.density.startswith("lbf s^2/in^4")
    assert (fps.length, fps.velocity, fps.density, fps.mass, fps.inertia) == \
        ("ft", "ft/s", "slug/ft^3", "slug", "slug ft^2")
    assert {si.frequency, ips.frequency, fps.frequency} == {"Hz"}
    assert si.as_dict()["velocity"] == "m/s" and si.as_dict()["system"] == "si"


def test_model_units_without_a_case():
    labels = unit_labels(None)
    assert labels.velocity == labels.density == labels.mass == MODEL_UNITS
    assert labels.frequency == "Hz"
    assert unit_labels(MODEL_UNITS) == labels


def test_unknown_system_lists_the_valid_ones():
    with pytest.raises(InputError, match="'imperial'.*si, english_in, english_ft"):
        unit_labels("imperial")
    with pytest.raises(InputError, match="empty labels"):
        UnitLabels("x", "m", "", "kg/m^3", "kg", "kg m^2", "N")


def test_system_named_by_a_result_and_the_case_file_agree():
    assert system_of({"units": "english_ft"}) == "english_ft"
    assert system_of({"units": "deck"}) is None and system_of({}) is None


def test_mass_property_units():
    si, ips = unit_labels("si"), unit_labels("english_in")
    assert [si.of_mass_property(q) for q in ("mass", "x_cg", "Izx", "weight")] == \
        ["kg", "m", "kg m^2", "kg"]                   # WTMASS = 1: weight is the mass itself
    assert ips.of_mass_property("weight", wtmass=1 / 386.089) == "lbf"
    with pytest.raises(InputError, match="'Jxx'"):
        si.of_mass_property("Jxx")
