"""The weighing as evidence: the measured mass properties' reference sizes, stated accuracies
and residual (issue 14 step 2; the paper's J1..J10, eqs. 1-10).

A missing mass shows in weight, CG and inertia; a stiffness error does not. Each measured
quantity enters the residual vector of :mod:`pipeline.diagnose.evidence` as
(model - measured) / (accuracy x reference size): weight and moments relative to their measured
value, CG relative to the radius of gyration, products of inertia relative to the largest moment.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from structures.massprops import MassProperties

#: Weighing accuracy of the total weight (load cells, 0.5 %).
WEIGHT_ACCURACY = 0.005
#: CG accuracy as a fraction of the radius of gyration (0.5 %: a few mm on a 1 m radius).
CG_ACCURACY = 0.005
#: Accuracy of measured moments and products of inertia (pendulum / swing tests, 2 % of the
#: principal moments).
INERTIA_ACCURACY = 0.02
_INERTIA_NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Iyz", "Izx")
_DIAGONAL = {"Ixx": 0, "Iyy": 1, "Izz": 2}
_PRODUCTS = {"Ixy": (0, 1), "Iyz": (1, 2), "Izx": (2, 0)}

_ACCURACY = {"weight": WEIGHT_ACCURACY, "x_cg": CG_ACCURACY, "y_cg": CG_ACCURACY,
             "z_cg": CG_ACCURACY, **{k: INERTIA_ACCURACY for k in _INERTIA_NAMES}}


def mass_references(measured: Mapping, model_props: MassProperties) -> dict:
    """Reference size of every measured mass quantity (errors are stated relative to it).

    Weight and moments of inertia: their measured value; CG: the radius of gyration
    sqrt(I_max / m); products of inertia: the largest moment I_max. I_max and m are the measured
    ones, or the model's (``model_props``) when the file does not give them.
    """
    values = model_props.as_dict()
    moments = [abs(measured[k]) for k in _DIAGONAL if k in measured]
    i_max = max(moments) if moments else max(abs(values[k]) for k in _DIAGONAL)
    mass = measured["weight"] * model_props.wtmass if "weight" in measured else model_props.mass
    out = {}
    for key in measured:
        if key == "weight" or key in _DIAGONAL:
            out[key] = abs(measured[key])
        elif key in _PRODUCTS:
            out[key] = i_max
        else:
            out[key] = float(np.sqrt(i_max / mass))
    return out


def mass_scales(measured: Mapping, model_props: MassProperties) -> dict:
    """Stated standard deviation of every measured quantity: its accuracy (``WEIGHT_ACCURACY``,
    ``CG_ACCURACY``, ``INERTIA_ACCURACY``) times its reference (:func:`mass_references`)."""
    refs = mass_references(measured, model_props)
    return {k: _ACCURACY[k] * refs[k] for k in measured}


def mass_residual(props: MassProperties, measured: Mapping, scales: Mapping) -> np.ndarray:
    """(model - measured) / scale for every measured quantity, in ``scales`` order."""
    values = props.as_dict()
    return np.array([(values[k] - measured[k]) / scales[k] for k in scales])
