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

:func:`remesh` represents a member by at least :data:`MIN_SEGMENTS` straight elements on a
parabolic arc (a bow of a few per cent of the length; no bow: on the member's line). A shallow
arch's axial stiffness with clamped ends is limited by bending through the part of its rise y(xi)
that is not linear in xi: the axial compliance gains int (y - y_lin)^2 ds / E I (unit-load
method, Timoshenko & Gere, *Theory of Elastic Stability*, 2nd ed., sec. 7.1; y_lin the best
linear fit). One straight element (offset or not) has y - y_lin = 0 and cannot show it; chords of
a parabola of rise h give int (y - mean y)^2 dxi = 0.0833 h^2 with 2 chords, 0.0885 h^2 with 4
and 0.0889 h^2 with 8, as the arc itself (4/45 h^2). A taper needs more: a cantilever whose
section size varies by 0.6 of its mean (I ~ s^4, a factor 5 in I along it) has its tip
compliance 6.5 % off with 4 uniform pieces and 1.6 % with 8 (midpoint rule, error ~ 1/n^2),
hence 8, for both.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from pipeline.diagnose.edits import add_grids, append_elements, next_eid
from structures.assembly import line_offsets
from structures.common.errors import InputError, card_message
from structures.elements.beam import beam_axes
from structures.model import ElementSet, FEModel

#: The line-element families members are made of.
MEMBER_CARDS = ("CBAR", "CBEAM")
#: Fewest straight elements :func:`remesh` represents a member by (see the module docstring).
MIN_SEGMENTS = 8


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


def fixed_masks(model: FEModel) -> np.ndarray:
    """(ng,) constrained-component bit masks (SPC and GRID PS) per grid row (bit c - 1 for
    component c: ``mask & 7 == 7`` holds all three translations)."""
    masks = np.array(model.grids.ps, np.int64)
    if model.spc:
        gids, bits = zip(*model.spc)
        np.bitwise_or.at(masks, model.grids.index(list(gids), card="SPC",
                                                   filename=model.filename), list(bits))
    return masks


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


def member_pieces(model: FEModel, member: Member):
    """The member's element family and, for each of its elements in chain order, the rows of
    the pieces it is now made of from its end A to its end B (the element alone, or the pieces
    :func:`remesh` split it in, joined at grids that are not the member's).

    Returns
    -------
    es : ElementSet of the member's card.
    pieces : list of (n_pieces,) int arrays, one per element of the member.
    """
    es = model.elements.get(member.card)
    pos = {} if es is None else {int(e): i for i, e in enumerate(es.eids)}
    missing = [e for e in member.eids if e not in pos]
    if missing:
        raise InputError(card_message(f"the member's elements {missing} are not in the model.",
                                      card=member.card, card_id=missing[0],
                                      filename=model.filename,
                                      fix="build the candidate with candidates() on this model."))
    at = {}
    for r, (g1, g2) in enumerate(es.nodes[:, :2].tolist()):
        at.setdefault(g1, []).append(r)
        at.setdefault(g2, []).append(r)
    ends, pieces = set(member.grids), []
    for k, eid in enumerate(member.eids):
        chain = [pos[eid]]
        grid = int(es.nodes[chain[0], 1])
        while grid not in ends:
            nxt = [q for q in at[grid] if q != chain[-1]]
            if len(nxt) != 1:
                break
            chain.append(nxt[0])
            a, b = es.nodes[nxt[0], :2].tolist()
            grid = b if a == grid else a
        if {int(es.nodes[chain[0], 0]), grid} != {member.grids[k], member.grids[k + 1]}:
            raise InputError(card_message(f"the element no longer runs from grid "
                                          f"{member.grids[k]} to {member.grids[k + 1]}.",
                                          card=member.card, card_id=eid, filename=model.filename,
                                          fix="build the candidate with candidates() on this "
                                          "model."))
        pieces.append(np.array(chain, np.int64))
    return es, pieces


def remesh(model: FEModel, member: Member, bow=(0.0, 0.0)):
    """The member on a parabolic arc, in at least :data:`MIN_SEGMENTS` straight elements.

    The arc runs through P(xi) = chord point + 4 xi (1 - xi) L (bow_1 y + bow_2 z), y, z the
    axes of each element's chord, L the member's length: the member's interior grids move onto
    it (a grid joining two elements by the mean of their two arcs, the same point on a straight
    member), and with them what they carry (CONM2s, the independent grids of rigid elements,
    sensors), as the points of a real curved member and what hangs on them lie on its curve;
    its end grids (xi = 0, 1) stay. Element offsets are kept as they are. An element of a member
    with ne < MIN_SEGMENTS elements is split in ceil(MIN_SEGMENTS / ne) elements at equal steps
    of xi, joined at new grids on the arc (basic frame), with the element's property, its basic
    orientation vector and no offsets or pin flags at the new grids. The first piece keeps the
    element's id, the others get new ids. A member split before keeps its pieces and its grids
    move by the arc (bows add). Without bow, a split member of straight uniform elements has the
    original stiffness between its grids (static condensation of the new grids is exact for
    cubic beam elements) and its structural mass spread over the new grids.

    Parameters
    ----------
    model : FEModel
    member : Member of ``model``.
    bow : (2,) rise of the arc's middle over L, along each element's y and z axis.

    Returns
    -------
    model : FEModel
    rows : (n_pieces,) rows of the member's elements in the new family, in chain order.
    xi_mid : (n_pieces,) their mid-length positions.
    """
    es, pieces = member_pieces(model, member)
    ne, done = len(pieces), len(pieces[0]) > 1
    per = len(pieces[0]) if done else int(np.ceil(MIN_SEGMENTS / ne))
    xi_a, xi_b = np.asarray(member.xi_a), np.asarray(member.xi_b)
    t = np.arange(per + 1) / per
    xi = xi_a[:, None] + t[None, :] * (xi_b - xi_a)[:, None]               # (ne, per + 1)
    mids = ((xi[:, :-1] + xi[:, 1:]) / 2.0).ravel()
    if not np.any(bow) and (done or per == 1):
        return model, np.concatenate(pieces), mids
    first, last = np.array([p[0] for p in pieces]), np.array([p[-1] for p in pieces])
    data = {k: np.array(v_) for k, v_ in es.data.items()}
    chord = {k: v_[first] for k, v_ in data.items()}
    chord["wb"] = data["wb"][last]
    chord["offt"] = np.array([f[:2] + g[2] for f, g in zip(data["offt"][first],
                                                           data["offt"][last])])
    ends = np.column_stack([es.nodes[first, 0], es.nodes[last, 1]])
    gi = model.grids.index(ends, card=es.card, filename=model.filename)
    v, wa, wb = line_offsets(model, ElementSet(es.card, es.eids[first], es.pids[first], ends,
                                               chord), gi, model.filename)
    xyz = model.grids.xyz
    a, b = xyz[gi[:, 0]] + wa, xyz[gi[:, 1]] + wb                           # (ne, 3)
    axes, _ = beam_axes(a, b, v)
    lateral = bow[0] * axes[:, 1] + bow[1] * axes[:, 2]                    # (ne, 3)
    shift = 4.0 * member.length * (xi * (1.0 - xi))[:, :, None] * lateral[:, None, :]
    rows, at = np.unique(gi.ravel(), return_inverse=True)      # the member's grids, each end
    step = np.zeros((rows.size, 3))
    np.add.at(step, at, shift[:, [0, -1]].reshape(-1, 3))
    moved = model.grids.xyz.copy()
    moved[rows] += step / np.bincount(at)[:, None]              # the end grids: shift 0
    if done:
        inner = np.array([es.nodes[p[1:], 0] for p in pieces])             # (ne, per - 1)
        moved[model.grids.index(inner.ravel())] += shift[:, 1:-1].reshape(-1, 3)
    model = replace(model, grids=replace(model.grids, xyz=moved))
    if done or per == 1:
        return model, np.concatenate(pieces), mids
    data["v"][first], data["g0"][first] = v, 0
    data["offt"][first] = ["B" + f[1:] for f in data["offt"][first]]
    inner = a[:, None] + t[None, 1:-1, None] * (b - a)[:, None] + shift[:, 1:-1]   # (ne, per-1, 3)
    model, new = add_grids(model, inner.reshape(-1, 3))
    chain = np.column_stack([es.nodes[first, 0], new.reshape(ne, per - 1), es.nodes[first, 1]])
    parent = np.repeat(np.arange(ne), per - 1)                     # the element of each new piece
    j = np.tile(np.arange(1, per), ne)                             # its place in the element
    piece = {k: np.array(v_)[first][parent] for k, v_ in data.items()}
    end_b = j == per - 1
    piece["wa"][:], piece["pa"][:] = 0.0, 0
    piece["wb"][~end_b], piece["pb"][~end_b] = 0.0, 0
    piece["offt"] = np.array([f[:1] + "G" + (f[2] if e else "G")
                              for f, e in zip(piece["offt"], end_b)])
    nodes = es.nodes.copy()
    nodes[first, 1] = chain[:, 1]
    data["wb"][first], data["pb"][first] = 0.0, 0
    data["offt"][first] = [f[:2] + "G" for f in data["offt"][first]]
    model = replace(model, elements={**model.elements,
                                     es.card: replace(es, nodes=nodes, data=data)})
    elements = append_elements(model, es.card, next_eid(model) + np.arange(len(parent)),
                               es.pids[first][parent],
                               np.stack([chain[parent, j], chain[parent, j + 1]], axis=1), piece)
    order = np.concatenate([[row, *(len(es) + np.flatnonzero(parent == i))]
                            for i, row in enumerate(first)]).astype(np.int64)
    return replace(model, elements=elements), order, mids
