"""The gap between model and test (before / after), and the measurement that separates two fits.

Gap metrics (issue 14 step 6, the contract's JSON keys), over all configurations, of the modes
paired as a correlation report pairs them (:func:`pipeline.diagnose.evidence.report_pairing`):

- ``frequency_rms_held_out`` / ``frequency_rms``: RMS of 100 (f_FE - f_GVT) / f_GVT (paper eq. 18)
  over the held-out paired modes / all paired modes [%];
- ``max_cross_orthogonality_offdiag``: largest |S_ij|, i != j, of the cross-orthogonality of the
  test modes with their paired analysis modes (paper eq. 20; SEREP on the rigid and paired modes,
  eqs. 11-14, :mod:`structures.correlation`);
- ``max_cross_orthogonality_offdiag_held_out``: the same over the rows of the held-out test
  modes only (the modes no fit saw; their columns still span every paired mode);
- ``mac_min``, ``mac_mean``: of the paired modes (paper eq. 23); ``mac_min_held_out`` of the
  held-out ones (None when no mode is held out);
- ``mass``: error [%] of every measured quantity relative to its reference size
  (:func:`pipeline.diagnose.weighing.mass_references`: weight and moments themselves, CG the
  radius of gyration, products the largest moment), from the configuration with the largest
  |error|; ``mass_by_configuration`` all of them;
- ``flutter_speed``: None (the pipeline stage fills it).
Without shapes the cross-orthogonality and MAC entries are None.
"""
from __future__ import annotations

import numpy as np

from pipeline.diagnose.evidence import report_pairing
from pipeline.diagnose.weighing import mass_references
from structures.correlation import cross_orthogonality, mac, serep_coordinates
from structures.modes import rigid_index



def _cross_offdiag(ref, modes, paired) -> tuple[float, float]:
    """Largest |S_ij|, i != j, over all test modes and over the held-out ones (rows i)."""
    phi_m = modes["shape"].values[:, ref.sensor_index]
    rigid = rigid_index(modes)
    keep = np.concatenate([rigid, paired])
    q = serep_coordinates(phi_m[keep].T, ref.shapes.T)                     # eq. 14
    s = np.abs(cross_orthogonality(q, np.eye(keep.size)))[:, rigid.size:]   # eq. 20, paired block
    off = s - np.diag(np.diag(s))
    return float(np.max(off, initial=0.0)), float(np.max(off[~ref.train], initial=0.0))


def gap_metrics(problem, evaluations) -> dict:
    """The gap of a model (its evaluations, one per configuration) against the tests."""
    errors, held = [], []
    cross, cross_held, macs, macs_held = [], [], [], []
    mass_by = {}
    for ref, ev in zip(problem.refs, evaluations):
        paired = report_pairing(ref, ev.modes)
        f_fe = ev.modes["frequency"].values[paired]
        err = 100.0 * (f_fe - ref.test_frequency) / ref.test_frequency       # eq. 18 in %
        errors.append(err)
        held.append(err[~ref.train])
        if ref.has_shapes:
            both, held_only = _cross_offdiag(ref, ev.modes, paired)
            cross.append(both)
            cross_held.append(held_only)
            phi = ev.modes["shape"].values[paired][:, ref.sensor_index]
            macs.append(np.diag(mac(ref.shapes.T, phi.T)))                 # eq. 23
            macs_held.append(macs[-1][~ref.train])
        if ref.measured_mass:
            values = ev.props.as_dict()
            size = mass_references(ref.measured_mass, ev.props)
            mass_by[ref.name] = {q: 100.0 * (values[q] - m) / size[q]
                                 for q, m in ref.measured_mass.items()}
    allerr, held = np.concatenate(errors), np.concatenate(held)
    worst = {}
    for values in mass_by.values():
        for q, v in values.items():
            if q not in worst or (np.isfinite(v) and abs(v) > abs(worst[q])):
                worst[q] = v
    macs = np.concatenate(macs) if macs else None
    macs_held = np.concatenate(macs_held) if macs_held else np.zeros(0)
    return {"frequency_rms_held_out": float(np.sqrt(np.mean(held ** 2))) if held.size else None,
            "frequency_rms": float(np.sqrt(np.mean(allerr ** 2))),
            "max_cross_orthogonality_offdiag": max(cross) if cross else None,
            "max_cross_orthogonality_offdiag_held_out": max(cross_held) if cross_held and
            macs_held.size else None,
            "mac_min": float(macs.min()) if macs is not None else None,
            "mac_mean": float(macs.mean()) if macs is not None else None,
            "mac_min_held_out": float(macs_held.min()) if macs_held.size else None,
            "mass": worst, "mass_by_configuration": mass_by, "flutter_speed": None}


#: Two fitted models whose predictions differ by less than this many noise standard deviations
#: at every paired frequency and at every translational DOF of the model (measured or not) are
#: one explanation: no measurement of the test's accuracy tells them apart (a spring anywhere
#: along a member that is rigid in its direction, :func:`indistinguishable`).
EQUIVALENT_SIGMAS = 0.1


def prediction_difference(problem, fit_a, fit_b) -> tuple:
    """Where two fitted models' predictions differ most relative to the noise.

    Compares the paired frequencies of every configuration (relative to the frequency scale) and,
    for a configuration with shapes, the paired mode shapes at every translational DOF of the
    model (each shape at unit RMS over the sensors, signs aligned, relative to the shape noise):
    a DOF that is not measured yet is a sensor to add.

    Returns
    -------
    frequency : (float, str), the largest difference in standard deviations and the test mode.
    shape : (float, str), the same for the shapes and the DOF ((0.0, "") without shapes).
    """
    best_f = (0.0, "")
    best_s = (0.0, "")
    for i, ref in enumerate(problem.refs):
        ea, eb = fit_a.evaluations[i], fit_b.evaluations[i]
        df = np.abs(ea.frequency - eb.frequency)
        j = int(np.argmax(df))
        if df[j] > best_f[0]:
            best_f = (float(df[j]), f"the frequency of test mode {ref.test_mode[j]} in "
                                    f"configuration {ref.name}")
        if not ref.has_shapes:
            continue
        modes_a, modes_b = ea.modes, eb.modes
        # the DOFs of both models: an effect's added grids come after the model's own
        n_dof = min(modes_a.sizes["dof"], modes_b.sizes["dof"])
        trans = np.flatnonzero(modes_a["component"].values[:n_dof] <= 3)
        sa = modes_a["shape"].values[ea.paired, :n_dof]
        sb = modes_b["shape"].values[eb.paired, :n_dof]
        scale_a = np.sqrt(np.mean(sa[:, ref.sensor_index] ** 2, axis=1, keepdims=True))
        scale_b = np.sqrt(np.mean(sb[:, ref.sensor_index] ** 2, axis=1, keepdims=True))
        sa, sb = sa / scale_a, sb / scale_b
        sign = np.sign(np.sum(sa[:, ref.sensor_index] * sb[:, ref.sensor_index], axis=1))
        diff = np.abs(sa - sign[:, None] * sb)[:, trans] / ref.shape_sigma[:, None]
        j, d = np.unravel_index(int(np.argmax(diff)), diff.shape)
        if diff[j, d] > best_s[0]:
            dof = trans[d]
            grid = int(modes_a["grid"].values[dof])
            comp = int(modes_a["component"].values[dof])
            best_s = (float(diff[j, d]), f"a sensor at grid {grid} component {comp} in test mode "
                                         f"{ref.test_mode[j]} of configuration {ref.name}")
    return best_f, best_s


def indistinguishable(problem, fit_a, fit_b) -> bool:
    """True when two fitted models predict the same data: every paired frequency and every
    translational DOF of the model's shapes within :data:`EQUIVALENT_SIGMAS` noise standard
    deviations (:func:`prediction_difference`). Judged only when every configuration has shapes
    (without them, sites that differ only in the shapes, e.g. the two sides of a symmetric
    structure, would look the same): False otherwise."""
    if not all(ref.has_shapes for ref in problem.refs):
        return False
    (df, _), (ds, _) = prediction_difference(problem, fit_a, fit_b)
    return max(df, ds) < EQUIVALENT_SIGMAS


def separating_measurement(problem, fit_a, fit_b) -> str:
    """The measurement that separates two fits (:func:`prediction_difference`), as a sentence."""
    best_f, best_s = prediction_difference(problem, fit_a, fit_b)
    label_a = fit_a.candidate.label if fit_a.candidate else "nothing missing"
    label_b = fit_b.candidate.label if fit_b.candidate else "nothing missing"
    text = (f"to separate {fit_a.candidate.kind} {label_a} from {fit_b.candidate.kind} {label_b}: "
            f"{best_f[1]} (predictions {best_f[0]:.1f} sigma apart)")
    if best_s[1]:
        text += f"; {best_s[1]} ({best_s[0]:.1f} sigma apart)"
    return text + "."
