"""Ids and cards the candidate effects add to a model (:mod:`pipeline.diagnose.effects`,
:mod:`pipeline.diagnose.joints`): new element and property ids, appended element rows, CBUSHes,
new grids.

New elements take ids from the model's largest element, CONM2 or rigid-element id + 1; new
properties from its largest PID + 1; new grids from its largest grid id + 1.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from structures.model import ElementSet, FEModel, Property


def next_eid(model: FEModel) -> int:
    """The model's largest element, CONM2 or rigid-element id + 1."""
    ids = [0, *model.masses.eids.tolist(), *(r.eid for r in model.rigid)]
    ids += [int(es.eids.max()) for es in model.elements.values() if len(es)]
    return max(ids) + 1


def next_pid(model: FEModel) -> int:
    """The model's largest property id + 1."""
    return max([0, *model.properties]) + 1


def append_elements(model: FEModel, card: str, eids, pids, nodes, data) -> dict:
    """The model's element families with rows appended to ``card``'s (n,) eids, pids,
    (n, nn) nodes and per-element ``data`` arrays (the family's keys)."""
    elements = dict(model.elements)
    old = elements.get(card)
    if old is not None:
        eids = np.concatenate([old.eids, eids])
        pids = np.concatenate([old.pids, pids])
        nodes = np.concatenate([old.nodes, nodes])
        data = {k: np.concatenate([np.asarray(old.data[k]), np.asarray(v)])
                for k, v in data.items()}
    elements[card] = ElementSet(card, eids, pids, nodes, data)
    return elements


def add_bushes(model: FEModel, pairs, stiffness) -> FEModel:
    """CBUSHes (CID 0, S 0.5) on (GA, GB) grid pairs, one PBUSH each."""
    n = len(pairs)
    eid0, pid0 = next_eid(model), next_pid(model)
    props = dict(model.properties)
    for i, k in enumerate(stiffness):
        props[pid0 + i] = Property(pid0 + i, "PBUSH", {f"K{c + 1}": float(k[c]) for c in range(6)})
    elements = append_elements(
        model, "CBUSH", np.arange(eid0, eid0 + n), np.arange(pid0, pid0 + n), np.array(pairs),
        {"v": np.zeros((n, 3)), "g0": np.zeros(n, np.int64), "cid": np.zeros(n, np.int64),
         "s": np.full(n, 0.5)})
    return replace(model, elements=elements, properties=props)


def add_grids(model: FEModel, xyz) -> tuple[FEModel, np.ndarray]:
    """The model with grids added at the (n, 3) basic positions ``xyz`` (basic displacement
    frame, no permanent constraints), ids from the largest grid id + 1; and their (n,) ids."""
    g = model.grids
    xyz = np.asarray(xyz, float).reshape(-1, 3)
    ids = int(g.ids.max()) + 1 + np.arange(len(xyz))
    grids = replace(g, ids=np.append(g.ids, ids), xyz=np.vstack([g.xyz, xyz]),
                    cd_axes=np.concatenate([g.cd_axes, np.tile(np.eye(3), (len(xyz), 1, 1))]),
                    cd=np.append(g.cd, np.zeros(len(xyz), np.int64)),
                    ps=np.append(g.ps, np.zeros(len(xyz), np.int64)))
    return replace(model, grids=grids), ids
