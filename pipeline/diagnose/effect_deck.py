"""Bulk-data cards of a model change, and a deck patched with them.

An effect of :mod:`pipeline.diagnose.effects` is defined by the model it makes; its cards are read
off the difference between the model before and after (new CONM2s, CBUSH/PBUSH and CELAS2
springs, new or changed CBAR/CBEAM and PBAR/PBEAM cards, new or moved grids, removed rigid
elements), so that the
written deck and :func:`pipeline.diagnose.apply.apply_effect` cannot disagree. Cards are field
lists: rendered as small-field text with :mod:`structures.bulk_text` (MYSTRAN-readable), or added
to a pyNastran deck and written in large field (the precision of the model's numbers).
"""
from __future__ import annotations

import io
from dataclasses import replace
from pathlib import Path

import numpy as np

from structures.assembly import assemble_g
from structures.bulk_text import card as card_text
from structures.common.errors import InputError, card_message
from structures.common.files import write_text
from structures.common.nastran import read_pynastran
from structures.model import ElementSet, FEModel

#: Element families an effect may add or change (others are never touched).
CHANGED_FAMILIES = ("CBAR", "CBEAM", "CBUSH", "CELAS")


def _components(mask: int):
    """Nastran component string of a bit mask as an integer field (None when no component)."""
    text = "".join(str(c + 1) for c in range(6) if int(mask) >> c & 1)
    return int(text) if text else None


def _line_card(es, i: int) -> list:
    data = es.data
    if data["g0"][i]:
        orient = [int(data["g0"][i]), None, None]
    else:
        orient = [float(x) + 0.0 for x in data["v"][i]]
    fields = [es.card, int(es.eids[i]), int(es.pids[i]), int(es.nodes[i, 0]), int(es.nodes[i, 1]),
              *orient, str(data["offt"][i]), _components(data["pa"][i]),
              _components(data["pb"][i]), *[float(x) + 0.0 for x in data["wa"][i]],
              *[float(x) + 0.0 for x in data["wb"][i]]]
    return fields


def _spring_card(es, i: int) -> list:
    k = float(es.data["k"][i])
    if np.isnan(k):
        raise InputError(card_message("a changed CELAS1 cannot be written by diagnose.",
                                      card="CELAS1", card_id=int(es.eids[i]),
                                      fix="report this: effects add CELAS2 springs only."))
    return ["CELAS2", int(es.eids[i]), k, int(es.nodes[i, 0]), int(es.data["c1"][i]) or None,
            int(es.nodes[i, 1]) or None, int(es.data["c2"][i]) or None]


def _bush_card(es, i: int) -> list:
    if int(es.data["cid"][i]) != 0:
        raise InputError(card_message("only CBUSHes in the basic frame (CID = 0) are written.",
                                      card="CBUSH", card_id=int(es.eids[i]),
                                      fix="report this: diagnose effects use CID = 0."))
    return ["CBUSH", int(es.eids[i]), int(es.pids[i]), int(es.nodes[i, 0]), int(es.nodes[i, 1]),
            None, None, None, 0, float(es.data["s"][i])]


def _property_card(prop) -> list:
    f = prop.fields

    def val(name):
        value = f.get(name)
        return None if value is None else float(value)

    tail = [val("K1"), val("K2")] + ([val("I12") or None] if prop.card == "PBAR" else [])
    stress = [0.0] * 8 if any(v is not None for v in tail) else []
    if prop.card == "PBAR":
        fields = ["PBAR", prop.pid, int(f["MID"]), val("A"), val("I1"), val("I2"), val("J"),
                  val("NSM"), None, *stress, *tail]
    elif prop.card == "PBEAM":
        fields = ["PBEAM", prop.pid, int(f["MID"]), val("A"), val("I1"), val("I2"), val("I12"),
                  val("J"), val("NSM"), *stress, *tail]
    else:
        fields = []
    while fields and fields[-1] is None:
        fields.pop()
    if fields:
        return fields
    if prop.card == "PBUSH":
        return ["PBUSH", prop.pid, "K", *[float(f.get(f"K{i}", 0.0) or 0.0) for i in range(1, 7)]]
    raise InputError(card_message(f"a changed {prop.card} cannot be written by diagnose.",
                                  card=prop.card, card_id=prop.pid,
                                  fix="report this: effects change PBAR, PBEAM and PBUSH only."))


#: CONM2 I11, I21, I22, I31, I32, I33 as (row, column, sign) of the basic inertia tensor.
_CONM2_INERTIA = ((0, 0, 1.0), (1, 0, -1.0), (1, 1, 1.0), (2, 0, -1.0), (2, 1, -1.0), (2, 2, 1.0))


def _conm2_card(masses, i: int) -> list:
    t = masses.inertia[i]
    return ["CONM2", int(masses.eids[i]), int(masses.grid[i]), 0, float(masses.mass[i]),
            *[float(x) for x in masses.offset[i]], None,
            *[float(sign * t[r, c]) + 0.0 for r, c, sign in _CONM2_INERTIA]]


def _differs(a, b) -> np.ndarray:
    """Row-wise inequality of two arrays (NaN equal to NaN): (n,) bool."""
    a, b = (np.asarray(x).reshape(len(x), int(np.prod(np.shape(x)[1:]))) for x in (a, b))
    out = a != b
    if a.dtype.kind == "f":
        out &= ~(np.isnan(a) & np.isnan(b))
    return out.any(axis=1)


def _match(old_ids, new_ids) -> np.ndarray:
    """Row of each new id among the old ids, -1 where absent."""
    if len(old_ids) == 0:
        return -np.ones(len(new_ids), np.int64)
    order = np.argsort(old_ids)
    j = order[np.clip(np.searchsorted(old_ids, new_ids, sorter=order), 0, len(order) - 1)]
    return np.where(old_ids[j] == new_ids, j, -1)


def _row_diff(before, es, changed_pids=(), moved_grids=()):
    """Rows of ``es`` that are new, rows of ``es`` that differ from ``before`` (same element id,
    a property in ``changed_pids`` or a grid in ``moved_grids``), their rows in ``before``, and
    rows of ``before`` gone."""
    if before is None:
        return np.arange(len(es)), *(np.zeros(0, np.int64),) * 3
    j = _match(before.eids, es.eids)
    rows, j = np.flatnonzero(j >= 0), j[j >= 0]
    diff = (_differs(before.pids[j], es.pids[rows]) | _differs(before.nodes[j], es.nodes[rows])
            | np.isin(es.pids[rows], list(changed_pids))
            | np.isin(es.nodes[rows], list(moved_grids)).any(axis=1))
    for key, arr in es.data.items():
        diff |= _differs(np.asarray(before.data[key])[j], np.asarray(arr)[rows])
    gone = np.flatnonzero(~np.isin(before.eids, es.eids))
    return np.setdiff1d(np.arange(len(es)), rows), rows[diff], j[diff], gone


def _mass_diff(om, cm):
    """Rows of the old and of the new CONM2s that are gone / new or whose values differ."""
    j = _match(om.eids, cm.eids)
    rows, j = np.flatnonzero(j >= 0), j[j >= 0]
    diff = np.zeros(len(rows), bool)
    for name in ("grid", "mass", "offset", "inertia"):
        diff |= _differs(getattr(om, name)[j], getattr(cm, name)[rows])
    new_rows = np.concatenate([np.setdiff1d(np.arange(len(cm)), rows), rows[diff]])
    old_rows = np.concatenate([j[diff], np.flatnonzero(~np.isin(om.eids, cm.eids))])
    return old_rows, new_rows


def _mass_rows(masses, rows):
    return replace(masses, eids=masses.eids[rows], grid=masses.grid[rows], mass=masses.mass[rows],
                   offset=masses.offset[rows], inertia=masses.inertia[rows])


def _moved_grids(old: FEModel, new: FEModel) -> np.ndarray:
    """Sorted ids of the grids of both models whose basic position differs."""
    j = _match(old.grids.ids, new.grids.ids)
    both = np.flatnonzero(j >= 0)
    moved = _differs(old.grids.xyz[j[both]], new.grids.xyz[both])
    return np.sort(new.grids.ids[both[moved]])


def model_changes(old: FEModel, new: FEModel) -> tuple[dict, list]:
    """The cards that turn ``old`` into ``new``.

    Parameters
    ----------
    old, new : FEModel
        ``new`` made from ``old`` by diagnose effects (elements and properties added or changed in
        the families of :data:`CHANGED_FAMILIES`, CONM2s added, grids added (basic frame),
        rigid elements removed, RBE2s with fewer dependent grids of one component set or a new
        independent grid: removed and written again; grids moved).

    Returns
    -------
    removed : dict with ``rigid``, ``elements``, ``properties``, ``grids``: sorted ids of cards
        to delete (changed cards are deleted and written again).
    cards : list of field lists (card name first), in the order grids, properties, elements,
        masses. A new or moved GRID is written at its basic position (CP blank) with its CD and
        PS.
    """
    new_rigid = {r.eid: r for r in new.rigid}
    removed = {"rigid": sorted(r.eid for r in old.rigid if new_rigid.get(r.eid) != r),
               "elements": [], "properties": []}
    prop_cards, elem_cards, mass_cards = [], [], []
    moved = _moved_grids(old, new)
    removed["grids"] = moved.tolist()
    added = ~np.isin(new.grids.ids, old.grids.ids) | np.isin(new.grids.ids, moved)
    grids = new.grids
    grid_cards = [["GRID", int(gid), None, *map(float, xyz), int(cd) or None, _components(ps)]
                  for gid, xyz, cd, ps in zip(grids.ids[added], grids.xyz[added],
                                              grids.cd[added], grids.ps[added])]
    for eid in removed["rigid"]:
        rigid = new_rigid.get(eid)
        if rigid is not None:                                  # an RBE2 with fewer dependents
            (grid, _), = rigid.independent
            elem_cards.append(["RBE2", eid, grid, int(rigid.dependent[0][1]),
                               *[g for g, _ in rigid.dependent]])
    for pid in sorted(new.properties):
        prop = new.properties[pid]
        if pid in old.properties and old.properties[pid] == prop:
            continue
        if pid in old.properties:
            removed["properties"].append(pid)
        prop_cards.append(_property_card(prop))
    for kind in CHANGED_FAMILIES:
        es = new.elements.get(kind)
        if es is None:
            continue
        added, changed, _, _ = _row_diff(old.elements.get(kind), es)
        write = {"CBUSH": _bush_card, "CELAS": _spring_card}.get(kind, _line_card)
        removed["elements"].extend(es.eids[changed].tolist())
        elem_cards.extend(write(es, i) for i in np.sort(np.concatenate([added, changed])))
    known = set(old.masses.eids.tolist())
    mass_cards = [_conm2_card(new.masses, i) for i, eid in enumerate(new.masses.eids.tolist())
                  if eid not in known]
    return removed, grid_cards + prop_cards + elem_cards + mass_cards


def changed_parts(old: FEModel, new: FEModel) -> tuple[FEModel, FEModel]:
    """The elements and CONM2s in which two models with the same grids (ids; positions may
    differ) and rigid elements differ.

    Parameters
    ----------
    old, new : FEModel

    Returns
    -------
    old_part, new_part : FEModel
        ``old`` restricted to its changed and removed elements and CONM2s, ``new`` to its changed
        and added ones; elements whose property changed or with a moved grid count as changed.
        ``K(new) - K(old) = K(new_part) - K(old_part)`` for every assembled matrix.
    """
    if [r.eid for r in old.rigid] != [r.eid for r in new.rigid] or \
            not np.array_equal(old.grids.ids, new.grids.ids):
        raise InputError("the two models differ in their grids or rigid elements, so their "
                         "difference is not a sum of element matrices. Fix: reassemble both.")
    changed_pids = [pid for pid, prop in new.properties.items()
                    if pid in old.properties and old.properties[pid] != prop]
    moved = _moved_grids(old, new)
    parts = ({}, {})
    for kind in sorted(set(old.elements) | set(new.elements)):
        es, before = new.elements.get(kind), old.elements.get(kind)
        if es is None:
            rows_new, rows_old = np.zeros(0, np.int64), np.arange(len(before))
        elif es is before and not changed_pids and not moved.size:
            continue
        else:
            added, changed, was, gone = _row_diff(before, es, changed_pids, moved)
            rows_new, rows_old = np.concatenate([added, changed]), np.concatenate([was, gone])
        for side, source, rows in ((0, before, rows_old), (1, es, rows_new)):
            if len(rows):
                data = {k: np.asarray(v)[rows] for k, v in source.data.items()}
                parts[side][kind] = ElementSet(kind, source.eids[rows], source.pids[rows],
                                               source.nodes[rows], data)
    old_rows, new_rows = _mass_diff(old.masses, new.masses)
    return (replace(old, elements=parts[0], masses=_mass_rows(old.masses, old_rows)),
            replace(new, elements=parts[1], masses=_mass_rows(new.masses, new_rows)))


def change_matrices(old: FEModel, new: FEModel, mass: str = "deck"):
    """Change of the g-set stiffness and mass (basic axes) from ``old`` to ``new``, assembled
    from the elements and CONM2s that differ only (:func:`changed_parts`).

    Parameters
    ----------
    old, new : FEModel with the same grids and rigid elements.
    mass : {'deck', 'consistent', 'lumped'}, as in :func:`structures.assembly.assemble_g`.

    Returns
    -------
    dK, dM : scipy.sparse.csr_matrix (6 n_grids, 6 n_grids),
        ``assemble_g(new) - assemble_g(old)``.
    """
    old_part, new_part = changed_parts(old, new)
    k1, m1 = assemble_g(new_part, mass)
    k0, m0 = assemble_g(old_part, mass)
    return (k1 - k0).tocsr(), (m1 - m0).tocsr()


def small_field_text(removed: dict, cards: list, header: str = "") -> str:
    """Small-field bulk-data text of the cards, removals stated as comments."""
    lines = [f"$ {line}" for line in header.splitlines()]
    for key, name in (("rigid", "rigid element"), ("elements", "element"),
                      ("properties", "property"), ("grids", "grid")):
        if removed.get(key):
            lines.append(f"$ replaces or removes {name} " + " ".join(map(str, removed[key])))
    lines.extend(card_text(*fields) for fields in cards)
    return "\n".join(lines) + "\n"


def write_patched_deck(deck_in, deck_out, changes) -> Path:
    """Write ``deck_in`` with the changes applied, large field, INCLUDEs merged (CELAS2 excepted:
    pyNastran 1.4.1 writes it in small field, its stiffness to 7 significant digits).

    Parameters
    ----------
    deck_in, deck_out : path-like
    changes : sequence of (removed, cards) from :func:`model_changes`, applied in order.
    """
    bdf = read_pynastran(deck_in)
    for removed, cards in changes:
        for eid in removed["rigid"]:
            bdf.rigid_elements.pop(eid, None)
        for eid in removed["elements"]:
            bdf.elements.pop(eid, None)
        for pid in removed["properties"]:
            bdf.properties.pop(pid, None)
        for gid in removed.get("grids", ()):
            bdf.nodes.pop(gid, None)
        for fields in cards:
            bdf.add_card(list(fields), fields[0], is_list=True)
    text = io.StringIO()
    bdf.write_bdf(text, size=16, is_double=False, close=False)
    return write_text(text.getvalue(), Path(deck_out))
