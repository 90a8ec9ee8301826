"""An effect written as bulk data (pipeline.diagnose.apply.write_effect_deck, effect_cards):
the written deck read back to the same model, and the effect cards against MYSTRAN."""
import re
import subprocess
from dataclasses import replace

import numpy as np
import pytest

from pipeline.diagnose.apply import apply_effect, effect_cards, write_effect_deck
from pipeline.diagnose.effects import candidates
from pipeline.diagnose.effect_deck import model_changes, write_patched_deck
from structures.assembly import assemble_g
from structures.bdf import read_model
from structures.bulk_text import card
from structures.modal import compute_modes
from structures.mystran import mystran_executable
from tests.pipeline.diagnose.small_decks import X56, elastic, pick, small_deck


# ----------------------------------------------------------------------------- written decks
def test_written_deck_reads_back_to_the_same_model(x56, x56_candidates, tmp_path):
    """Every kind alone and all together: the same assembled K and M, and the same modes."""
    picks = [("lumped_mass", "grid 5021"), ("lumped_mass", "grid 3005 spread over"),
             ("joint_flexibility", "RBE2 7501"),
             ("member_taper", "PID 101 (CBAR 1003"), ("member_curvature", "PID 101 (CBAR 1003"),
             ("member_curvature", "PID 132"), ("boundary_stiffness", "grid 1004 z")]
    effects = []
    for kind, label in picks:
        cand = pick(x56_candidates, kind, label)
        values = np.array(cand.reference) * 1.7
        effects.append((cand, values))
        expected = assemble_g(apply_effect(x56, cand, values))
        path = write_effect_deck(X56, tmp_path / f"{kind}.bdf", x56, [(cand, values)])
        for got, want in zip(assemble_g(read_model(path)), expected):
            assert abs(got - want).max() <= 1e-10 * abs(want).max()
    combined = x56
    for cand, values in effects:
        combined = apply_effect(combined, cand, values)
    back = read_model(write_effect_deck(X56, tmp_path / "all.bdf", x56, effects))
    for got, want in zip(assemble_g(back), assemble_g(combined)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()
    # K and M agree to 3e-15; the eigen-solver reproduces the grounded spring's 1.42 Hz bounce
    # mode of these equal matrices to 3e-8 only, hence 1e-7 on the modes.
    np.testing.assert_allclose(elastic(back, 20), elastic(combined, 20), rtol=1e-7)


def test_cbeam_members_round_trip(tmp_path):
    """CBEAM/PBEAM (shear factors K1, K2) through taper and curvature, both written forms."""
    cards = [("GRID", i + 1, None, 2.0 * i, 0.3 * i, 0.0, None, 123456 if i == 0 else None)
             for i in range(5)]
    cards += [("CBEAM", 20 + i, 8, i + 1, i + 2, 0.0, 0.0, 1.0) for i in range(4)]
    cards += [("PBEAM", 8, 1, 2.0, 0.4, 0.9, 0.05, 0.6, 0.1, *[0.0] * 8, 0.85, 0.8),
              ("MAT1", 1, 7.0e4, None, 0.33, 2.7e-3)]
    deck = small_deck(tmp_path, "beams.bdf", cards)
    model = read_model(deck)
    cands = candidates(model, ["member_taper", "member_curvature"])
    assert [c.location.elements for c in cands] == [(20, 21, 22, 23)] * 5
    effects = [(cands[0], [-0.1, 0.4]), (cands[2], [0.08, -0.05])]
    combined = apply_effect(apply_effect(model, *effects[0]), *effects[1])
    back = read_model(write_effect_deck(deck, tmp_path / "beams_out.bdf", model, effects))
    for got, want in zip(assemble_g(back), assemble_g(combined)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()
    text = effect_cards(model, *effects[0])
    assert "replaces or removes element 20 21 22 23" in text
    path = small_deck(tmp_path, "beams_small.bdf", [c for c in cards if c[0] != "CBEAM"])
    path.write_text(path.read_text().replace("ENDDATA", text + "ENDDATA"))
    np.testing.assert_allclose(compute_modes(read_model(path), 6)["frequency"].values,
                               compute_modes(apply_effect(model, *effects[0]), 6)
                               ["frequency"].values, rtol=1e-5)


def test_a_moved_grid_keeps_its_cd_and_ps(tmp_path):
    """Grid 2 given in CP 5 with CD 5 (a frame turned 30 deg about z, origin (1, 2, 0)) and PS 4,
    moved by (0.1, -0.2, 0.3): its card is written at the basic position with CD 5 and PS 4, and
    the patched deck reads back to the moved model's grids and K, M (CD sets the g-set axes)."""
    turn = np.radians(30.0)
    deck = small_deck(tmp_path, "turned.bdf", [
        ("CORD2R", 5, None, 1.0, 2.0, 0.0, 1.0, 2.0, 1.0, 1.0 + np.cos(turn), 2.0 + np.sin(turn),
         0.0),
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 123456), ("GRID", 2, 5, 2.0, 0.0, 0.0, 5, 4),
        ("CBAR", 10, 7, 1, 2, 0.0, 0.0, 1.0), ("PBAR", 7, 1, 3.0, 0.7, 1.3, 1.0),
        ("MAT1", 1, 2.0e5, None, 0.3, 7.8e-9)])
    model = read_model(deck)
    assert model.grids.cd.tolist() == [0, 5] and model.grids.ps.tolist() == [63, 8]
    xyz = model.grids.xyz.copy()
    xyz[1] += [0.1, -0.2, 0.3]
    moved = replace(model, grids=replace(model.grids, xyz=xyz))
    removed, cards = model_changes(model, moved)
    assert removed["grids"] == [2]
    assert cards == [["GRID", 2, None, *xyz[1].tolist(), 5, 4]]
    back = read_model(write_patched_deck(deck, tmp_path / "turned_out.bdf", [(removed, cards)]))
    np.testing.assert_allclose(back.grids.xyz, xyz, atol=1e-14)
    assert back.grids.cd.tolist() == [0, 5] and back.grids.ps.tolist() == [63, 8]
    np.testing.assert_allclose(back.grids.cd_axes, model.grids.cd_axes, atol=1e-15)
    for got, want in zip(assemble_g(back), assemble_g(moved)):
        assert abs(got - want).max() <= 1e-12 * abs(want).max()


def test_effect_cards_are_readable_small_field_bulk_data(x56, x56_candidates, tmp_path):
    """Additive effects: the original deck plus the small-field cards gives the effect's modes
    (to the 8-character precision of the fields)."""
    for kind, label in (("lumped_mass", "grid 5021"), ("boundary_stiffness", "grid 1004 z")):
        cand = pick(x56_candidates, kind, label)
        text = effect_cards(x56, cand, cand.reference)
        assert text.startswith("$ diagnose effect")
        assert all(len(line) <= 72 for line in text.splitlines() if not line.startswith("$"))
        deck = X56.read_text().replace("ENDDATA", text + "ENDDATA")
        (tmp_path / "structure_x56.inc").write_text((X56.parent / "structure_x56.inc").read_text())
        for inc in ("masses_efew.inc", "aero_x56.inc"):
            (tmp_path / inc).write_text((X56.parent / inc).read_text())
        path = tmp_path / f"{kind}_cards.bdf"
        path.write_text(deck)
        np.testing.assert_allclose(elastic(read_model(path), 20),
                                   elastic(apply_effect(x56, cand, cand.reference), 20),
                                   rtol=1e-5)


def _deck_with_cards(folder, texts, nmodes):
    """The X-56 structure and EFEW masses as one SOL 103 deck with effect cards: cards the
    effects' ``$ replaces or removes`` comments name are dropped first."""
    drop = {"rigid element": "RBE2", "element": "CBAR", "property": "PBAR"}
    removed = set()
    for text in texts:
        for line in text.splitlines():
            hit = re.match(r"\$ replaces or removes (rigid element|element|property) (.*)", line)
            if hit:
                removed |= {(drop[hit.group(1)], int(i)) for i in hit.group(2).split()}
    lines = ((X56.parent / "structure_x56.inc").read_text().splitlines()
             + (X56.parent / "masses_efew.inc").read_text().splitlines())
    bulk, keep = [], True
    for line in lines:
        if line[:1] not in (" ", "+", "*"):
            keep = (line[:8].strip(), int(line[8:16]) if line[8:16].strip().isdigit() else None) \
                not in removed
        if keep:
            bulk.append(line)
    path = folder / "effects.bdf"
    path.write_text("SOL 103\nCEND\nMETHOD = 1\nDISP(PLOT) = ALL\nBEGIN BULK\n" + "\n".join(bulk)
                    + "\n" + "".join(texts) + card("EIGRL", 1, None, None, nmodes) + "\nENDDATA\n")
    return path


@pytest.mark.skipif(mystran_executable() is None, reason="mystran is not installed")
def test_effect_cards_against_mystran(x56, x56_candidates, tmp_path):
    """MYSTRAN on the deck with the small-field cards of four effects (CONM2, CBUSH/PBUSH for
    a removed RBE2, re-PIDed tapered CBARs, bowed CBAR offsets) against apply_effect. (MYSTRAN
    18 rejects grounded springs, so boundary_stiffness is left out.)"""
    from pyNastran.op2.op2 import read_op2

    picks = [("lumped_mass", "grid 5021", [0.03, 2e-4]),
             ("joint_flexibility", "RBE2 7501", [4.0, 0.6]),
             ("member_taper", "PID 101 (CBAR 1003", [0.1, 0.5]),
             ("member_curvature", "PID 132 (CBAR 5002, grids 5001-5011) bow +y -z", [0.05, -0.05])]
    model, texts = x56, []
    for kind, label, values in picks:
        cand = pick(x56_candidates, kind, label)
        texts.append(effect_cards(model, cand, values))
        model = apply_effect(model, cand, values)
    deck = _deck_with_cards(tmp_path, texts, 20)
    subprocess.run([mystran_executable(), deck.name], cwd=tmp_path, capture_output=True,
                   timeout=300)
    errors = [line for line in deck.with_suffix(".F06").read_text(errors="replace").splitlines()
              if "*ERROR" in line or "FATAL" in line]
    assert not errors
    table = next(iter(read_op2(str(deck.with_suffix(".OP2")), debug=None).eigenvectors.values()))
    theirs = np.sqrt(np.clip(np.asarray(table.eigns, float), 0, None)) / (2 * np.pi)
    ours = compute_modes(model, 20)["frequency"].values
    np.testing.assert_allclose(theirs[6:], ours[6:len(theirs)], rtol=1e-6)
    assert np.max(np.abs(ours[6:] / elastic(x56, 20)[:14] - 1)) > 0.01   # the effects show
