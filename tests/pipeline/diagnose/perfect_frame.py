"""A perfect test of the blind study's frame: a model against the modes of a truth at the frame's
120 sensors and its weighing, without noise (shared by the screening, refit, pairing, detail,
load-path, grounded-spring and linearised-error tests)."""
from dataclasses import replace

import numpy as np

from pipeline.diagnose.evidence import build_reference
from structures.gvt import make_gvt_dataset
from structures.massprops import mass_properties
from structures.modal import compute_modes
from structures.model import ConcentratedMass
from tests.pipeline.diagnose.truth import frame


def perfect_reference(truth, model, nmodes: int = 46):
    """``model`` against the modes 7..26 of ``truth`` at the frame's 120 sensors and its weighing
    (no noise); returns (model's modes, reference)."""
    truth_modes = compute_modes(truth, nmodes)
    modes = truth_modes if truth is model else compute_modes(model, nmodes)
    grid, comp = np.array(frame.sensors()).T
    dof = np.array([np.flatnonzero((truth_modes["grid"].values == g)
                                   & (truth_modes["component"].values == c))[0]
                    for g, c in zip(grid, comp)])
    gvt = make_gvt_dataset(truth_modes["frequency"].values[6:26],
                           truth_modes["shape"].values[6:26][:, dof], grid, comp,
                           mode=np.arange(7, 27))
    props = mass_properties(truth).as_dict()
    measured = {k: props[k] for k in ("weight", "x_cg", "y_cg", "z_cg", "Ixx", "Iyy", "Izz")}
    ref, _ = build_reference("frame", model, gvt, measured, modes, frequency_noise=0.01,
                             shape_noise_value=0.05, model_scatter=0.03, holdout=3, nmodes=nmodes)
    return modes, ref


def with_mass(model, grid: int, mass: float):
    """The model with a point mass (a CONM2 without inertia) at ``grid``."""
    cm = model.masses
    return replace(model, masses=ConcentratedMass(
        np.append(cm.eids, cm.eids.max() + 1), np.append(cm.grid, grid), np.append(cm.mass, mass),
        np.vstack([cm.offset, np.zeros((1, 3))]),
        np.concatenate([cm.inertia, np.zeros((1, 3, 3))])))
