"""Adding a candidate effect (:mod:`pipeline.diagnose.effects`, whose docstring defines what each
kind changes) to a model, to its assembled matrices, or as bulk data to its deck.

Every function takes the model the candidate was built on (or one with other effects already
added) and parameter values inside the candidate's bounds; all-zero values add nothing.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from pipeline.diagnose.edits import append_elements, next_eid, next_pid
from pipeline.diagnose.effect_deck import (change_matrices, model_changes, small_field_text,
                                           write_patched_deck)
from pipeline.diagnose.effects import (DIRECTIONS, JOINT_DIRECTIONS, TAPER_EXPONENTS, Candidate,
                                       check_values, component_compliances)
from pipeline.diagnose.joints import flexible_joint
from pipeline.diagnose.members import remesh
from pipeline.diagnose.mirror import site_values
from structures.common.errors import InputError
from structures.massprops import mass_properties
from structures.model import FEModel, Property


def _lumped_mass(model, candidate, x):
    total = candidate.get("total_mass")
    if total is None:
        total = mass_properties(model).weight
    cm = model.masses
    grids = np.asarray(candidate.location.grids, np.int64)
    if candidate.get("per_grid"):                       # one share per grid, the empty left out
        share = x[:-1] * total
        grids, share = grids[share > 0.0], share[share > 0.0]
    else:                                               # 1, or a spread mass's equal shares
        share = np.full(grids.size, x[0] * total / grids.size)
    n = grids.size
    inertia = (share * x[-1] * candidate.get("length") ** 2)[:, None, None] * np.eye(3)  # m r^2
    masses = replace(cm, eids=np.append(cm.eids, next_eid(model) + np.arange(n)),
                     grid=np.append(cm.grid, grids), mass=np.append(cm.mass, share),
                     offset=np.concatenate([cm.offset, np.zeros((n, 3))]),
                     inertia=np.concatenate([cm.inertia, inertia]))
    return replace(model, masses=masses)


def _boundary(model, candidate, x):
    direction = [DIRECTIONS.index(name[2:]) + 1 for name in candidate.parameters]
    keep = np.flatnonzero(x > 0.0)
    n = keep.size
    elements = append_elements(
        model, "CELAS", next_eid(model) + np.arange(n), np.zeros(n, np.int64),
        np.column_stack([np.full(n, candidate.location.grids[0]), np.zeros(n, np.int64)]),
        {"c1": np.array(direction)[keep], "c2": np.zeros(n, np.int64),
         "k": x[keep] * candidate.get("k_ref")})
    return replace(model, elements=elements)


def _joint(model, candidate, x):
    if x.size == len(JOINT_DIRECTIONS):                  # c_1..c_6, one per CBUSH component
        if not np.all(x > 0.0):
            raise InputError(f"candidate {candidate.label!r}: directional compliances {x.tolist()}"
                             " mix zero (a rigid CBUSH component) with nonzero ones. Fix: give "
                             "every component a compliance > 0, or all 0 for the rigid joint.")
        c = x
    else:
        c = component_compliances(x)
    k_ref = np.repeat([candidate.get("k_translation"), candidate.get("k_rotation")], 3)
    return flexible_joint(model, candidate.location.elements[0], k_ref / c,
                          candidate.get("dependent"))


def _taper(model, candidate, x):
    member = candidate.get("member")
    model, rows, xi_mid = remesh(model, member)
    es = model.elements[member.card]
    s = 1.0 + x[1] * (xi_mid - 0.5)
    pids = np.array(es.pids)
    props = dict(model.properties)
    new_pid = next_pid(model)
    for i, row in enumerate(rows):
        base = model.property(es.pids[row], card=es.card, eid=es.eids[row])
        if np.count_nonzero(es.pids == base.pid) > 1:
            pids[row], new_pid = new_pid, new_pid + 1
        fields = {k: (None if base.fields.get(k) is None else
                      base.fields[k] * ((1.0 + x[0]) * s[i]) ** n)
                  for k, n in TAPER_EXPONENTS.items()}
        props[int(pids[row])] = Property(int(pids[row]), base.card, {**base.fields, **fields})
    elements = dict(model.elements)
    elements[member.card] = replace(es, pids=pids)
    return replace(model, properties=props, elements=elements)


def _curvature(model, candidate, x):
    return remesh(model, candidate.get("member"), x)[0]


#: The :attr:`Candidate.detail` keys each kind needs (set by :func:`candidates`).
_DETAIL = {"lumped_mass": (), "boundary_stiffness": ("direction", "k_ref"),
           "joint_flexibility": ("k_translation", "k_rotation"), "member_taper": ("member",),
           "member_curvature": ("member",)}
_APPLY = {"lumped_mass": _lumped_mass, "boundary_stiffness": _boundary, "joint_flexibility": _joint,
          "member_taper": _taper, "member_curvature": _curvature}


def apply_effect(model: FEModel, candidate: Candidate, values) -> FEModel:
    """The model with the candidate effect of the given size added.

    Parameters
    ----------
    model : FEModel
        The model the candidate was built on (or one with other effects already added).
    candidate : Candidate
    values : (npar,) parameter values inside the candidate's bounds; all zero returns ``model``.

    Returns
    -------
    FEModel
    """
    x = check_values(candidate, values)
    missing = [key for key in _DETAIL[candidate.kind] if candidate.get(key) is None]
    if missing:
        raise InputError(f"candidate {candidate.label!r} lacks the detail {missing} of a "
                         f"{candidate.kind}. Fix: build candidates with candidates(model).")
    if not np.any(x):
        return model
    for site, x_site in site_values(candidate, x):             # a mirror pair: both sites
        model = _APPLY[candidate.kind](model, site, x_site)
    return model


def effect_matrices(model: FEModel, candidate: Candidate, values, *, mass: str = "deck"):
    """Change of the g-set stiffness and mass (basic axes) made by an effect.

    Only the changed and added elements and CONM2s are assembled
    (:func:`pipeline.diagnose.effect_deck.change_matrices`).

    Parameters
    ----------
    model : FEModel
    candidate : Candidate, not ``joint_flexibility`` (it changes the constraint equations) nor
        a taper or curvature of a member it splits (new grids): those raise InputError.
    values : (npar,)
    mass : {'deck', 'consistent', 'lumped'}, as in :func:`structures.assembly.assemble_g`.

    Returns
    -------
    dK, dM : scipy.sparse.csr_matrix (6 n_grids, 6 n_grids),
        ``assemble_g(new) - assemble_g(model)``.
    """
    if candidate.kind == "joint_flexibility":
        raise InputError(f"candidate {candidate.label!r}: a joint flexibility changes the rigid "
                         "elements, not only element matrices. Fix: assemble the changed model.")
    return change_matrices(model, apply_effect(model, candidate, values), mass)


def effect_cards(model: FEModel, candidate: Candidate, values) -> str:
    """Small-field bulk-data text of the effect: cards added or replacing ones of the deck.

    Removed rigid elements and replaced cards are named in ``$`` comment lines.

    Parameters
    ----------
    model : FEModel
    candidate : Candidate
    values : (npar,)

    Returns
    -------
    str
    """
    x = check_values(candidate, values)
    removed, cards = model_changes(model, apply_effect(model, candidate, x))
    header = (f"diagnose effect {candidate.kind}: {candidate.label}; " +
              ", ".join(f"{n} = {v:.6g}" for n, v in zip(candidate.parameters, x)))
    return small_field_text(removed, cards, header)


def write_effect_deck(deck_in, deck_out, model: FEModel, effects) -> Path:
    """Write ``deck_in`` with effects added (large field, INCLUDEs merged into one file).

    Parameters
    ----------
    deck_in, deck_out : path-like
        ``model`` must be ``read_model(deck_in)``.
    model : FEModel
    effects : sequence of (Candidate, values), applied in order.

    Returns
    -------
    Path of the written deck; :func:`structures.bdf.read_model` reads it back to the K and M of
    the model with the effects applied.
    """
    changes = []
    for candidate, values in effects:
        new = apply_effect(model, candidate, values)
        changes.append(model_changes(model, new))
        model = new
    return write_patched_deck(deck_in, deck_out, changes)
