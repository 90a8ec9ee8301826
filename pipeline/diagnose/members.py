"""Members of a beam model (chains of CBAR/CBEAM elements with one property, end to end) and
neighbourhoods of grids and elements.

A member is what an engineer idealises as one uniform, straight beam (a spar between two ribs, a
fuselage segment, a pylon): the taper and curvature candidates of :mod:`pipeline.diagnose.effects`
act on whole members. Elements of one PID are linked through a shared grid; a grid shared by two
such elements links them; where three or more meet (a branch), the two most nearly collinear ones
are linked and the others end there. The linked elements form paths (or closed loops), each a
member; an element linked to none is a member of its own.

A member runs from the end grid with the smaller id (a loop from its smallest grid), and ``xi``
is the arc length from there over the member's length (grid positions, offsets ignored).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from structures.model import FEModel

#: The line-element families members are made of.
MEMBER_CARDS = ("CBAR", "CBEAM")


@dataclass(frozen=True)
class Member:
    """One chain of line elements with one property.

    Attributes
    ----------
    card : str, ``CBAR`` or ``CBEAM``.
    pid : int
    eids : (ne,) element ids in chain order.
    grids : (ne + 1,) grid ids in chain order (a loop repeats its first grid at the end).
    xi_a, xi_b : (ne,) arc-length position (0..1) of each element's end A and end B (the grids
        GA and GB of its card, whichever way the element points along the chain).
    length : float, the member's length.
    """

    card: str
    pid: int
    eids: tuple
    grids: tuple
    xi_a: tuple
    xi_b: tuple
    length: float

    @property
    def xi_mid(self) -> np.ndarray:
        """(ne,) mid-length position of each element."""
        return 0.5 * (np.asarray(self.xi_a) + np.asarray(self.xi_b))


def _links(nodes, xyz_index, xyz):
    """For each element, the elements it is linked to at its end A and B (-1: none)."""
    ne = len(nodes)
    link = -np.ones((ne, 2), dtype=np.int64)
    at = {}
    for e in range(ne):
        for end in (0, 1):
            at.setdefault(int(nodes[e, end]), []).append((e, end))
    for grid, ends in at.items():
        if len(ends) < 2:
            continue
        if len(ends) == 2:
            pair = ends
        else:
            here = xyz[xyz_index[grid]]
            out = []
            for e, end in ends:
                d = xyz[xyz_index[int(nodes[e, 1 - end])]] - here
                out.append(d / np.linalg.norm(d))
            cos = np.array(out) @ np.array(out).T
            np.fill_diagonal(cos, np.inf)
            i, j = np.unravel_index(np.argmin(cos), cos.shape)
            pair = [ends[i], ends[j]]
        (e1, end1), (e2, end2) = pair
        link[e1, end1], link[e2, end2] = e2, e1
    return link


def _walk(start, link, nodes):
    """Elements and grids of the chain that starts at element ``start`` (an end or a loop)."""
    order, grids = [start], []
    free_end = 0 if link[start, 0] < 0 else 1 if link[start, 1] < 0 else 0
    grids.append(int(nodes[start, free_end]))
    grids.append(int(nodes[start, 1 - free_end]))
    cur = start
    while True:
        nxt = int(link[cur, 1 if nodes[cur, 1] == grids[-1] else 0])
        if nxt < 0 or nxt == start:
            break
        order.append(nxt)
        grids.append(int(nodes[nxt, 1] if nodes[nxt, 0] == grids[-1] else nodes[nxt, 0]))
        cur = nxt
    return order, grids


def find_members(model: FEModel) -> tuple[Member, ...]:
    """All members of the model's CBAR and CBEAM elements.

    Parameters
    ----------
    model : FEModel

    Returns
    -------
    tuple of Member, ordered by card, PID and first element id.
    """
    xyz = model.grids.xyz
    index = {int(g): i for i, g in enumerate(model.grids.ids)}
    members = []
    for card in MEMBER_CARDS:
        es = model.elements.get(card)
        if es is None:
            continue
        for pid in np.unique(es.pids):
            rows = np.flatnonzero(es.pids == pid)
            nodes = es.nodes[rows]
            link = _links(nodes, index, xyz)
            seen = np.zeros(len(rows), dtype=bool)
            ends = [e for e in range(len(rows)) if np.any(link[e] < 0)]
            loops = [e for e in np.argsort(es.eids[rows]) if not np.any(link[e] < 0)]
            for start in ends + [int(e) for e in loops]:
                if seen[start]:
                    continue
                order, grids = _walk(start, link, nodes)
                seen[order] = True
                if grids[-1] < grids[0] and grids[-1] != grids[0]:
                    order, grids = order[::-1], grids[::-1]
                seg = np.linalg.norm(np.diff(xyz[[index[g] for g in grids]], axis=0), axis=1)
                s = np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum()
                forward = nodes[order, 0] == np.array(grids[:-1])
                xi_a = np.where(forward, s[:-1], s[1:])
                xi_b = np.where(forward, s[1:], s[:-1])
                members.append(Member(card, int(pid), tuple(int(e) for e in es.eids[rows][order]),
                                      tuple(grids), tuple(xi_a.tolist()), tuple(xi_b.tolist()),
                                      float(seg.sum())))
    return tuple(sorted(members, key=lambda m: (m.card, m.pid, min(m.eids))))


def connectivity(model: FEModel) -> list:
    """(eids, nodes (ne, nn), 0-padded, pids) of every element family and the rigid elements."""
    conn = [(es.eids, es.nodes, es.pids) for es in model.elements.values()]
    if model.rigid:
        rigid_grids = [[gid for gid, _ in r.independent + r.dependent] for r in model.rigid]
        nodes = np.zeros((len(rigid_grids), max(map(len, rigid_grids))), np.int64)
        for i, g in enumerate(rigid_grids):
            nodes[i, :len(g)] = g
        conn.append((np.array([r.eid for r in model.rigid]), nodes,
                     np.zeros(len(rigid_grids), np.int64)))
    return conn


def grow(model: FEModel, grids, elements, properties) -> tuple[set, set, set]:
    """Grids, elements and properties grown by one element layer.

    The seed grids are ``grids`` and those of ``elements``; every element (rigid elements
    included) touching a seed grid joins, with its grids and property.

    Parameters
    ----------
    model : FEModel
    grids, elements, properties : iterables of ids.

    Returns
    -------
    (grids, elements, properties) : sets of ids.
    """
    conn = connectivity(model)
    elements = set(elements)
    seeds = set(grids)
    for eids, nodes, _ in conn:
        seeds.update(nodes[np.isin(eids, list(elements))].ravel().tolist())
    out_grids, props = set(seeds), set(properties)
    for eids, nodes, pids in conn:
        touch = np.isin(nodes, list(seeds)).any(axis=1)
        out_grids.update(nodes[touch].ravel().tolist())
        elements.update(eids[touch].tolist())
        props.update(pids[touch & (pids > 0)].tolist())
    out_grids.discard(0)
    return out_grids, elements, props
