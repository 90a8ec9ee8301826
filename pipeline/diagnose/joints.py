"""The ``joint_flexibility`` kind of :mod:`pipeline.diagnose.effects`: which rigid elements are
joints, their stiffness scales k_ref,t and k_ref,r, and the model with a joint on springs (the
parametrisation is stated in :mod:`pipeline.diagnose.effects`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from pipeline.diagnose.edits import add_bushes, add_grids
from structures.common.errors import InputError, card_message
from structures.model import FEModel


def _beam_stiffness(model: FEModel):
    """Per CBAR/CBEAM element: (eids, nodes, 12 E I / L^3, E I / L) with I = (I1 + I2) / 2."""
    out = []
    for card in ("CBAR", "CBEAM"):
        es = model.elements.get(card)
        if es is None:
            continue
        gi = model.grids.index(es.nodes, card=card, filename=model.filename)
        length = np.linalg.norm(model.grids.xyz[gi[:, 1]] - model.grids.xyz[gi[:, 0]], axis=1)
        ei = np.zeros(len(es))
        for pid in np.unique(es.pids):
            sel = es.pids == pid
            prop = model.property(pid, card=card, eid=int(es.eids[sel][0]))
            e_mod = model.material(prop.get("MID"), card=prop.card, pid=pid).isotropic()[0]
            ei[sel] = e_mod * 0.5 * (prop.get("I1") + prop.get("I2"))
        out.append((es.eids, es.nodes, 12.0 * ei / length ** 3, ei / length))
    if not out:
        return None
    return tuple(np.concatenate(parts) for parts in zip(*out))


def joint_grids(rigid) -> tuple | None:
    """(independent grid, ((dependent grid, components), ...)) of a rigid joint, else None."""
    if rigid.card not in ("RBE2", "RBAR") or len(rigid.independent) != 1:
        return None
    grid, comps = rigid.independent[0]
    if sorted(str(comps)) != list("123456"):
        return None
    return int(grid), tuple((int(g), str(c)) for g, c in rigid.dependent)


def joint_sites(model: FEModel) -> list:
    """The rigid joints a ``joint_flexibility`` candidate can soften.

    Parameters
    ----------
    model : FEModel

    Returns
    -------
    list of (grids, eid, label, detail): the joint's grids (independent first), the rigid
    element's id, a label and the candidate detail (``k_translation``, ``k_rotation`` and, for a
    one-sided joint, ``dependent``); a multi-dependent RBE2 gives its whole joint and then one
    entry per dependent grid.
    """
    beams = _beam_stiffness(model)
    if beams is None:
        return []
    eids, nodes, k_t, k_r = beams
    out = []
    for rigid in model.rigid:
        joint = joint_grids(rigid)
        if joint is None:
            continue
        indep, deps = joint
        partial = [g for g, c in deps if sorted(c) != list("123456")]
        if partial and np.any(model.grids.cd[model.grids.index(partial)] != 0):
            continue
        mine = [indep] + [g for g, _ in deps]
        near = np.isin(nodes, mine).any(axis=1)
        if not near.any():
            near[:] = True
        kt, kr = float(np.median(k_t[near])), float(np.median(k_r[near]))
        dep_ids = [g for g, _ in deps]
        label = f"{rigid.card} {rigid.eid} ({indep}-{'/'.join(str(g) for g, _ in deps)})"
        out.append((tuple(mine), rigid.eid, label,
                    (("k_translation", kt), ("k_rotation", _k_rotation(model, indep, dep_ids,
                                                                       kt, kr)))))
        if rigid.card == "RBE2" and len(deps) > 1:
            out += [((indep, g), rigid.eid, f"RBE2 {rigid.eid} ({indep}-{g} only)",
                     (("k_translation", kt),
                      ("k_rotation", _k_rotation(model, indep, [g], kt, kr)), ("dependent", g)))
                    for g in dep_ids]
    return out


def hangs_nothing(model: FEModel, eid: int, only=None) -> bool:
    """True when the grids a joint candidate hangs on its springs carry nothing.

    The hung grids (the rigid joint's dependent grids, or ``only``) then have no CONM2, no
    element, no other rigid element and no SPC or PS: the springs carry no force in any mode
    (nothing loads the hung grids), so every compliance gives the rigid joint's modes, the hung
    grids following the independent grid as before.

    Parameters
    ----------
    model : FEModel
    eid : int, the RBE2 / RBAR.
    only : int, optional, the one dependent grid of a one-sided candidate.
    """
    rigid = next((r for r in model.rigid if r.eid == eid), None)
    joint = None if rigid is None else joint_grids(rigid)
    if joint is None:
        return False
    hung = [only] if only is not None else [g for g, _ in joint[1]]
    if np.isin(model.masses.grid, hung).any():
        return False
    if any(np.isin(es.nodes, hung).any() for es in model.elements.values()):
        return False
    if any(int(g) in hung for r in model.rigid if r.eid != eid
           for g, _ in tuple(r.independent) + tuple(r.dependent)):
        return False
    if any(int(g) in hung for g, _ in model.spc):
        return False
    return not np.any(model.grids.ps[model.grids.index(hung)] != 0)


def _k_rotation(model: FEModel, indep: int, hung, kt: float, kr: float) -> float:
    """k_ref,r of a joint: k_ref,t I / m for the CONM2s at the hung grids (m their mass, I
    their largest moment of inertia about the independent grid), so that one compliance puts the
    hung part's local translation and rotation modes at one frequency; without hung mass,
    E I / L + k_ref,t d^2 (d the largest distance of a hung grid)."""
    xyz0 = model.grids.xyz[model.grids.index([indep])[0]]
    cm = model.masses
    sel = np.isin(cm.grid, hung)
    mass = float(cm.mass[sel].sum())
    if mass > 0:
        r = model.grids.xyz[model.grids.index(cm.grid[sel])] + cm.offset[sel] - xyz0   # (k, 3)
        parallel = np.einsum("k,kij->ij", cm.mass[sel],
                             np.einsum("ki,ki->k", r, r)[:, None, None] * np.eye(3)
                             - r[:, :, None] * r[:, None, :])
        inertia = float(np.linalg.eigvalsh(cm.inertia[sel].sum(axis=0) + parallel)[-1])
        return kt * inertia / mass
    d2 = np.sum((model.grids.xyz[model.grids.index(hung)] - xyz0) ** 2, axis=1)
    return kr + kt * float(d2.max())


def flexible_joint(model: FEModel, eid: int, stiffness, only=None) -> FEModel:
    """The model with rigid joint ``eid`` on springs.

    Parameters
    ----------
    model : FEModel
    eid : int, the RBE2 / RBAR.
    stiffness : (6,) CBUSH stiffness K1..K6 (basic axes: three translations, three rotations).
    only : int, optional, the one dependent grid put on its spring (the others stay rigid).

    Returns
    -------
    FEModel
        The whole joint (``only`` None): the rigid element stays rigid on a new grid at its
        independent grid, hung there by one zero-length CBUSH (all six components); one-sided:
        the hung dependent grid gets a CBUSH to the independent grid on its dependent
        components and leaves the rigid element.
    """
    rigid = next((r for r in model.rigid if r.eid == eid), None)
    joint = None if rigid is None else joint_grids(rigid)
    if joint is None:
        raise InputError(card_message("no rigid joint (RBE2, or RBAR independent on one grid) with "
                                      "this id in the model.", card="RBE2/RBAR", card_id=eid,
                                      filename=model.filename,
                                      fix="build the candidate with candidates() on this model."))
    indep, deps = joint
    k = np.asarray(stiffness, float)
    kept = tuple(d for d in deps if d[0] != only) if only is not None else ()
    if only is not None and len(kept) == len(deps):
        raise InputError(card_message(f"grid {only} is not a dependent grid of this RBE2.",
                                      card=rigid.card, card_id=eid, filename=model.filename,
                                      fix="build the candidate with candidates() on this model."))
    if only is None:
        return _hang_whole(model, rigid, indep, k)
    hung = [d for d in deps if d not in kept]
    stiffness = [[k[c] if str(c + 1) in comps else 0.0 for c in range(6)] for _, comps in hung]
    rigid_new = tuple(replace(r, dependent=kept) if r.eid == eid else r for r in model.rigid
                      if r.eid != eid or kept)
    model = replace(model, rigid=rigid_new)
    return add_bushes(model, [(indep, g) for g, _ in hung], stiffness)


def _hang_whole(model: FEModel, rigid, indep: int, k) -> FEModel:
    """The rigid element kept rigid but moved onto a new grid at its independent grid, which
    hangs on a zero-length CBUSH (all six components) to the independent grid (written back as
    an RBE2: an RBAR independent on one grid is one)."""
    model, (new,) = add_grids(model, model.grids.xyz[model.grids.index([indep])])
    moved = tuple(replace(r, independent=((int(new), "123456"),)) if r.eid == rigid.eid else r
                  for r in model.rigid)
    return add_bushes(replace(model, rigid=moved), [(indep, int(new))], [list(k)])
