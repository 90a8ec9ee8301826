"""Reference and value checks of an FE model, run when it is read (before any solve).

Each check raises the project's error naming the card, the id and the fix, so that a bad deck fails
early and nothing is half-written.
"""
from __future__ import annotations

from structures.errors import InputError, card_message
from structures.model import FEModel

_PROPERTY_OF = {"CBAR": ("PBAR", "PBEAM"), "CBEAM": ("PBAR", "PBEAM"), "CROD": ("PROD",),
                "CELAS": ("PELAS",), "CBUSH": ("PBUSH",), "CQUAD4": ("PSHELL",),
                "CTRIA3": ("PSHELL",)}
_SECTION_FIELDS = {"PBAR": ("A",), "PBEAM": ("A",), "PROD": ("A",), "PSHELL": ("T",)}


def _check_property(model: FEModel, card: str, eid: int, pid: int) -> None:
    prop = model.property(pid, card=card, eid=eid)
    if prop.card not in _PROPERTY_OF[card]:
        raise InputError(card_message(
            f"references {prop.card} {pid}; {card} needs {' or '.join(_PROPERTY_OF[card])}.",
            card=card, card_id=eid, filename=model.filename, fix="correct the PID field."))
    for name in _SECTION_FIELDS.get(prop.card, ()):
        value = prop.fields.get(name)
        if value is None or not value > 0:
            raise InputError(card_message(f"{name} = {value} must be positive.", card=prop.card,
                                          card_id=pid, filename=model.filename,
                                          fix=f"give {prop.card} {pid} a positive {name}."))
    for key in ("MID", "MID1", "MID2", "MID3", "MID4"):
        mid = prop.fields.get(key)
        if mid:
            model.material(mid, card=prop.card, pid=pid)


def validate_model(model: FEModel) -> None:
    """Check every reference and value an assembly will use; raise on the first problem."""
    grids = model.grids
    for card, es in model.elements.items():
        for row, eid in zip(es.nodes, es.eids):
            used = row[row > 0]
            grids.index(used, card=card, card_id=eid, filename=model.filename)
        if card in _PROPERTY_OF:
            for eid, pid in zip(es.eids, es.pids):
                if card == "CELAS" and pid == 0:
                    continue
                _check_property(model, card, eid, pid)
        if card == "CMASS2":
            for eid, m in zip(es.eids, es.data["mass"]):
                if not m > 0:
                    raise InputError(card_message(f"mass {m} is not positive.", card="CMASS2",
                                                  card_id=eid, filename=model.filename,
                                                  fix="give a positive mass (or remove the card)."))
    for elem in model.rigid:
        for gid, _ in elem.independent + elem.dependent:
            grids.index([gid], card=elem.card, card_id=elem.eid, filename=model.filename)
    for gid, _ in model.spc + model.suport:
        grids.index([gid], card="SPC", card_id=gid, filename=model.filename)
    for mid, mat in model.materials.items():
        rho = mat.fields.get("RHO")
        if rho is not None and rho < 0:
            raise InputError(card_message(f"RHO = {rho} is negative.", card=mat.card, card_id=mid,
                                          filename=model.filename, fix="give RHO >= 0."))
