"""Diagnose on a structure from elsewhere: the University of Bristol WINDY wing with its folding
wingtip (tests/data/windy_fwt, a public deck none of this project's generators made), whose hinge
the deck locks with RBE2 300 (grids 208 and 209, coincident, both in the hinge frame CD 3).

The hidden truth: the hinge is six CELAS2 springs in the hinge frame, stiff (1e6 N/m, 1e4 N m /
rad) but for the rotation about the frame's x axis (100 N m / rad: the fold, 7.5 % down in the
second mode, 6.97 against 7.54 Hz). A GVT of the 10 lowest modes at 120 translational DOFs (40
grids evenly over the ids), 1 % frequency and 5 % shape noise. A hinge is the joint the
two-parameter library joint cannot be (one rotation soft, the rest stiff): it is named only in
its six-compliance form, against a load path that matches the two-parameter fit within the margin
(:mod:`pipeline.diagnose.workflow`). Without the springs (the deck as it is, the same noise) the
verdict names nothing. About 3 minutes: ``slow``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from structures.bdf import read_model
from structures.common.files import write_json, write_text
from structures.common.nastran import read_pynastran
from structures.gvt import make_gvt_dataset, write_uff
from structures.massprops import mass_properties
from structures.modal import compute_modes
from tests.pipeline.diagnose.truth.generate import _case_toml, measured
from tests.pipeline.diagnose.truth.study import diagnose_case
from tests.pipeline.diagnose.truth.x56 import measured_mass

DECK = Path(__file__).resolve().parents[2] / "data" / "windy_fwt" / "sol103.bdf"
HINGE, N_TEST, N_GRIDS = 300, 10, 40
#: Spring stiffness per component of the hinge frame: translations, rotations, the fold (4).
K_TRANSLATION, K_ROTATION, K_FOLD, FOLD = 1.0e6, 1.0e4, 100.0, 4


def _case(folder: Path, hinge: bool, seed: int = 0) -> Path:
    """The analysis deck (the public deck written back), the truth's GVT and weighing, case.toml."""
    folder.mkdir(parents=True)
    bdf = read_pynastran(DECK)
    analysis = folder / "fwt.bdf"
    bdf.write_bdf(str(analysis), enddata=True)
    if hinge:
        rbe = bdf.rigid_elements.pop(HINGE)
        eid = max([*bdf.elements, *bdf.masses, *bdf.rigid_elements, HINGE]) + 1
        for c in range(1, 7):
            k = K_FOLD if c == FOLD else (K_TRANSLATION if c <= 3 else K_ROTATION)
            bdf.add_celas2(eid + c, k, [int(rbe.gn), int(rbe.Gmi[0])], c1=c, c2=c)
    truth = folder / "truth" / "truth.bdf"
    truth.parent.mkdir()
    bdf.write_bdf(str(truth), enddata=True)
    model = read_model(truth)
    modes = compute_modes(model, N_TEST).isel(mode=slice(0, N_TEST))     # clamped: no rigid
    key = {(int(g), int(c)): j for j, (g, c) in
           enumerate(zip(modes["grid"].values, modes["component"].values))}
    ids = np.unique(modes["grid"].values)
    grids = ids[np.linspace(0, ids.size - 1, N_GRIDS).round().astype(int)]
    sensors = [(int(g), c) for g in grids for c in (1, 2, 3) if (int(g), c) in key]
    f, shape, damping = measured(modes, sensors, np.random.default_rng(seed), (0.01, 0.05))
    xyz = dict(zip(model.grids.ids.tolist(), model.grids.xyz.tolist()))
    gvt = make_gvt_dataset(f, shape, [g for g, _ in sensors], [c for _, c in sensors],
                           mode=np.arange(1, N_TEST + 1), damping=damping,
                           xyz=[xyz[g] for g, _ in sensors], source="windy_fwt truth",
                           units="si")
    write_uff(gvt, folder / "gvt_fwt.unv", title="WINDY FWT GVT")
    write_json(measured_mass(mass_properties(model)), folder / "mass_fwt.json")
    return write_text(_case_toml("windy_fwt", "si", [("fwt", analysis)], {}),
                      folder / "case.toml")


@pytest.mark.slow
def test_flexible_hinge_is_named_and_the_locked_one_is_not(tmp_path):
    result = diagnose_case(_case(tmp_path / "hinge", True))
    assert result["verdict"] == "effect", result["notes"]
    effect = result["effect"]
    assert effect["kind"] == "joint_flexibility" and HINGE in effect["location"]["elements"]
    assert len(effect["parameters"]) == 6                  # the six-compliance form
    before, after = result["gap_before"], result["gap_after"]
    assert after["frequency_rms_held_out"] < before["frequency_rms_held_out"]
    assert (after["max_cross_orthogonality_offdiag"]
            < before["max_cross_orthogonality_offdiag"])
    assert diagnose_case(_case(tmp_path / "locked", False))["verdict"] != "effect"
