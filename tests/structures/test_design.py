"""Tests of structures.design: fields, linking, bounds, scaling, application, bad input, write-back."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from tuning_decks import PROPS, PSHELL_T, write_aircraft_deck  # noqa: E402

from structures.assembly import assemble  # noqa: E402
from structures.bdf import read_model  # noqa: E402
from structures.design import (DesignVariable, FieldRef, affected_submodel, apply_design, bind,  # noqa: E402
                               element_groups, get_field, write_tuned_bdf)
from structures.common.errors import InputError, MissingReferenceError  # noqa: E402


@pytest.fixture(scope="module")
def decks(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("design")
    empty = write_aircraft_deck(tmp / "empty.bdf")["path"]
    full = write_aircraft_deck(tmp / "full.bdf", fuel=300.0)["path"]
    return empty, full, read_model(empty), read_model(full)


ALL_KINDS = [
    DesignVariable("spar_I1", [("PBAR", 11, "I1"), ("PBAR", 12, "I1")]),
    DesignVariable("fus_A", [("PBAR", 1, "A")], lower=5e-3, upper=7e-3, scale=1e-3),
    DesignVariable("fus_J", [("PBAR", 1, "J")]),
    DesignVariable("skin_T", [("PSHELL", 21, "T"), ("PSHELL", 22, "T")]),
    DesignVariable("skin_E", [("MAT1", 2, "E")]),
    DesignVariable("pylon", [("PELAS", 41, "K")]),
    DesignVariable("pylon_rot", [("CELAS2", 804, "K"), ("CELAS2", 807, "K")]),
    DesignVariable("engine", [("CONM2", 900, "M"), ("CONM2", 901, "M")]),
    DesignVariable("engine_I", [("CONM2", 900, "I22"), ("CONM2", 901, "I22")]),
]


def test_bind_defaults_linking_and_scaling(decks):
    _, _, empty, full = decks
    space = bind(ALL_KINDS, [empty, full])
    i = space.names.index("spar_I1")
    assert space.x0[i] == pytest.approx(PROPS[11][1], rel=1e-9)
    assert space.lower[i] == pytest.approx(0.8 * PROPS[11][1], rel=1e-12)   # default -20 %
    assert space.upper[i] == pytest.approx(1.2 * PROPS[11][1], rel=1e-12)   # default +20 %
    j = space.names.index("fus_A")
    assert (space.lower[j], space.upper[j], space.scale[j]) == (5e-3, 7e-3, 1e-3)
    assert space.scale[i] == pytest.approx(PROPS[11][1])                    # default |x0|
    np.testing.assert_allclose(space.from_scaled(space.to_scaled(space.x0)), space.x0, rtol=1e-15)


def test_apply_design_changes_every_linked_field_and_nothing_else(decks):
    _, _, empty, _ = decks
    space = bind(ALL_KINDS, [empty])
    x = space.x0 * 1.1
    tuned = apply_design(empty, space, x)
    for var in ALL_KINDS:
        for ref in var.fields:
            assert get_field(tuned, ref) == pytest.approx(1.1 * get_field(empty, ref), rel=1e-12), ref
    assert tuned.properties[13].fields["I1"] == empty.properties[13].fields["I1"]   # untouched
    assert tuned.properties[11].fields["I2"] == empty.properties[11].fields["I2"]
    with pytest.raises(InputError, match="is 0"):   # CONM2 900 has I21 = 0: no linked scaling
        bind([DesignVariable("i21", [("CONM2", 900, "I21")])], [empty])


def test_linked_fields_of_different_size_move_in_proportion(decks):
    _, _, empty, _ = decks
    var = DesignVariable("tail_fin", [("PBAR", 31, "I1"), ("PBAR", 32, "I1")])
    space = bind([var], [empty])
    tuned = apply_design(empty, space, [space.x0[0] * 0.9])
    assert tuned.properties[31].fields["I1"] == pytest.approx(0.9 * PROPS[31][1], rel=1e-12)
    assert tuned.properties[32].fields["I1"] == pytest.approx(0.9 * PROPS[32][1], rel=1e-12)


def test_field_present_in_one_configuration_only(decks):
    _, _, empty, full = decks
    fuel = DesignVariable("fuel", [("CONM2", 950, "M")])
    space = bind([fuel], [empty, full])
    assert space.x0[0] == pytest.approx(300.0 / 16)
    assert apply_design(empty, space, [20.0]).masses.mass.sum() == pytest.approx(empty.masses.mass.sum())
    with pytest.raises(MissingReferenceError, match="CONM2 950"):
        bind([fuel], [empty])


def test_submodel_assembly_equals_full_assembly_difference(decks):
    _, _, empty, _ = decks
    space = bind(ALL_KINDS, [empty])
    x = space.x0 * 1.07
    sub0 = affected_submodel(empty, space)
    full0, full1 = assemble(empty), assemble(apply_design(empty, space, x))
    from structures.assembly import assemble_g
    k0, _ = assemble_g(sub0)
    k1, _ = assemble_g(apply_design(sub0, space, x))
    tr = full0.rotation @ full0.T
    diff_sub = tr.T @ (k1 - k0) @ tr
    diff_full = full1.K - full0.K
    assert abs(diff_sub - diff_full).max() <= 1e-12 * abs(full0.K).max()


@pytest.mark.parametrize("var, match", [
    (DesignVariable("x", [("PBAR", 999, "I1")]), "no PBAR with id 999"),
    (DesignVariable("x", [("PSHELL", 1, "T")]), "no PSHELL with id 1"),
    (DesignVariable("x", [("MAT8", 2, "E1")]), "no MAT8 with id 2"),
    (DesignVariable("x", [("CONM2", 12345, "M")]), "CONM2 12345"),
    (DesignVariable("x", [("CELAS2", 20, "K")]), "CELAS2 20"),
    (DesignVariable("x", [("PBAR", 1, "I1")], lower=7e-5, upper=9e-5), "exclude the start value"),
])
def test_bad_design_variables_fail_before_any_solve(decks, var, match):
    _, _, empty, _ = decks
    with pytest.raises(InputError, match=match):
        bind([var], [empty])


def test_unknown_card_or_field_names_the_valid_ones():
    with pytest.raises(InputError, match="not a tunable field of PBAR"):
        FieldRef("PBAR", 1, "I3")
    with pytest.raises(InputError, match="cannot be a design variable"):
        FieldRef("CQUAD4", 1, "T")


def test_shared_field_with_different_start_values_raises(decks, tmp_path):
    _, _, empty, _ = decks
    other = read_model(write_aircraft_deck(tmp_path / "o.bdf", changes={("PBAR", 1, "I1"): 1.1})["path"])
    with pytest.raises(InputError, match="different values"):
        bind([DesignVariable("f", [("PBAR", 1, "I1")])], [empty, other])


def test_write_tuned_bdf_round_trip(decks, tmp_path):
    empty_path, _, empty, _ = decks
    space = bind(ALL_KINDS, [empty])
    x = space.x0 * np.linspace(0.85, 1.15, len(space))
    x[space.names.index("fus_A")] = 6.5e-3
    out = write_tuned_bdf(empty_path, tmp_path / "tuned.bdf", space, x)
    reread = read_model(out)
    expected = apply_design(empty, space, x)
    for var in ALL_KINDS:
        for ref in var.fields:
            assert get_field(reread, ref) == pytest.approx(get_field(expected, ref), rel=1e-7), ref
    assert reread.properties[21].fields["T"] == pytest.approx(
        PSHELL_T[21] * x[space.names.index("skin_T")] / space.x0[space.names.index("skin_T")], rel=1e-7)
    with pytest.raises(InputError, match="outside its bounds"):
        write_tuned_bdf(empty_path, tmp_path / "bad.bdf", space, space.upper * 2)


def test_element_groups_partition_the_affected_elements_by_their_variables(decks):
    """Every affected element and CONM2 is in exactly one group, and a group's elements are
    changed by exactly its variables (checked against affected_submodel per variable)."""
    _, _, empty, _ = decks
    space = bind(ALL_KINDS, [empty])
    groups = element_groups(empty, space)
    seen = {}
    for variables, sub in groups:
        for kind, es in sub.elements.items():
            for eid in es.eids.tolist():
                assert (kind, eid) not in seen
                seen[(kind, eid)] = variables
        for eid in sub.masses.eids.tolist():
            assert ("CONM2", eid) not in seen
            seen[("CONM2", eid)] = variables
    everything = affected_submodel(empty, space)
    expected = {(k, e) for k, es in everything.elements.items() for e in es.eids.tolist()}
    expected |= {("CONM2", e) for e in everything.masses.eids.tolist()}
    assert set(seen) == expected
    for key, variables in seen.items():
        owners = []
        for i in range(len(space)):
            sub = affected_submodel(empty, space, only=[i])
            ids = (sub.masses.eids.tolist() if key[0] == "CONM2" else
                   sub.elements[key[0]].eids.tolist() if key[0] in sub.elements else [])
            if key[1] in ids:
                owners.append(i)
        assert tuple(owners) == variables, key
    skin = space.names.index("skin_T"), space.names.index("skin_E")
    assert tuple(sorted(skin)) in [v for v, _ in groups]
