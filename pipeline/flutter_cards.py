"""The deck side of a flutter run: FLUTTER / FLFACT / FMETHOD / AERO / SDAMP / TABDMP1 cards as
:class:`flutter.solve.FlutterRequest` data.

FLFACT densities are ratios to AERO RHOREF (1.0 without AERO); negative FLFACT velocities
(Nastran's "print eigenvectors" flag) are taken by magnitude. SDAMP in the case control selects a
TABDMP1 (TYPE G, CRIT or Q, converted to g: G as is, CRIT g = 2 zeta, Q g = 1 / Q).

Structural damping in Nastran's flutter solution (PARAM KDAMP = 1, its default) is modal viscous
damping: b_j = g(f_j) omega_j m_j on each in-vacuo mode, the ``"viscous"`` kind of
:class:`flutter.system.StructuralDamping`. Every request gets that kind, from the deck's table or
from the case's ``structural_damping`` g (a constant g on every mode, in place of the table);
KDAMP = -1 (damping as complex stiffness) is refused rather than silently treated as viscous.
"""
from __future__ import annotations

import numpy as np

from flutter.solve import FlutterRequest
from flutter.system import StructuralDamping
from structures.common.errors import InputError, UnsupportedCardError, card_message

#: The damping kind of Nastran's modal flutter with PARAM KDAMP = 1 (the default).
NASTRAN_DAMPING_KIND = "viscous"


def _param(bdf, name: str):
    """Value of PARAM ``name`` (None when absent)."""
    card = bdf.params.get(name)
    return None if card is None else card.values[0]


def lmodes(bdf) -> int | None:
    """PARAM LMODES (the number of modes of the flutter solution), None when absent.

    Parameters
    ----------
    bdf : pyNastran BDF
    """
    value = _param(bdf, "LMODES")
    return int(value) if value else None


def _sdamp_table(bdf, sdamp: int, filename: str) -> StructuralDamping:
    """TABDMP1 ``sdamp`` as modal viscous structural damping in g units."""
    if sdamp not in bdf.tables_sdamping:
        raise InputError(card_message(f"SDAMP selects TABDMP1 {sdamp}, which is not defined.",
                                      card="TABDMP1", card_id=sdamp, filename=filename,
                                      fix="add the TABDMP1 card or correct SDAMP."))
    tab = bdf.tables_sdamping[sdamp]
    y = np.asarray(tab.y, dtype=float)
    kind = str(getattr(tab, "Type", "G")).upper()
    g = {"G": y, "CRIT": 2.0 * y, "Q": 1.0 / np.where(y == 0, np.inf, y)}.get(kind)
    if g is None:
        raise UnsupportedCardError(card_message(f"TABDMP1 TYPE {kind} is not supported.",
                                                card="TABDMP1", card_id=sdamp, filename=filename,
                                                fix="use TYPE G, CRIT or Q."))
    return StructuralDamping(frequency=tuple(np.asarray(tab.x, dtype=float)), table_g=tuple(g),
                             kind=NASTRAN_DAMPING_KIND)


def _damping(bdf, sdamp: int | None, structural_damping: float | None,
             filename: str) -> StructuralDamping:
    """The case's constant g if given, else the SDAMP table, else none."""
    kdamp = _param(bdf, "KDAMP")
    if kdamp is not None and int(kdamp) < 0:
        raise UnsupportedCardError(card_message(
            f"PARAM KDAMP = {kdamp} (modal damping as complex stiffness) is not supported.",
            card="PARAM", card_id="KDAMP", filename=filename,
            fix="remove PARAM KDAMP (Nastran's default 1: modal viscous damping)."))
    if structural_damping is not None:
        return StructuralDamping(g=structural_damping, kind=NASTRAN_DAMPING_KIND)
    return StructuralDamping() if sdamp is None else _sdamp_table(bdf, sdamp, filename)


def _case_control(bdf) -> tuple[list[tuple[int, int | None]], int | None]:
    """(FMETHOD id, SDAMP id) of every subcase with an FMETHOD (its SDAMP, else the global one),
    and the global SDAMP. pyNastran files the case control's SDAMP under its full name SDAMPING."""
    selected = []
    glob_sdamp = None
    cc = bdf.case_control_deck
    if cc is not None:
        for sid, sc in sorted(cc.subcases.items()):
            key = next((k for k in ("SDAMPING", "SDAMP") if k in sc.params), None)
            sdamp = None if key is None else sc.get_parameter(key)[0]
            if sid == 0:
                glob_sdamp = sdamp
            if "FMETHOD" in sc.params:
                selected.append((int(sc.get_parameter("FMETHOD")[0]), sdamp or glob_sdamp))
    return selected, glob_sdamp


def _selection(bdf, flutter_ids) -> list[tuple[int, int | None]]:
    """(FLUTTER id, SDAMP id) pairs: each subcase's FMETHOD (with its SDAMP, else the global one),
    else every FLUTTER card undamped; the ``flutter_ids`` override keeps the SDAMP of the subcase
    whose FMETHOD names the id (the global one for an id no FMETHOD names)."""
    selected, glob_sdamp = _case_control(bdf)
    if flutter_ids is not None:
        by_fmethod = dict(selected)
        return [(int(sid), by_fmethod.get(int(sid), glob_sdamp)) for sid in flutter_ids]
    return selected or [(sid, None) for sid in sorted(bdf.flutters)]


def read_flutter_requests(bdf, filename: str = "", flutter_ids=None,
                          structural_damping: float | None = None, solver: str = "pk",
                          solvers=()) -> list[FlutterRequest]:
    """The deck's flutter requests: the FLUTTER cards selected by FMETHOD (all if none is selected).

    Parameters
    ----------
    bdf : pyNastran BDF
        The parsed deck (:func:`structures.common.nastran.read_pynastran`).
    filename : str
        The deck's file name, for messages (carried as each request's ``source``).
    flutter_ids : list of int, optional
        FLUTTER card ids to run instead of the case control's FMETHOD selection.
    structural_damping : float, optional
        A g value (e.g. 0.01 from the case's ``[flutter]``): constant modal viscous damping g on
        every mode, replacing the deck's SDAMP / TABDMP1 selection.
    solver : {"pk", "g", "p"}
        Solver of the PK / PKNL cards (:data:`flutter.solve.SOLVERS`); K / KE cards keep the
        k-method.
    solvers : sequence of (int, str) or dict
        Per FLUTTER id overrides of ``solver``.

    Returns
    -------
    list of FlutterRequest
        Densities absolute (FLFACT ratio x AERO RHOREF), each with its StructuralDamping.

    Raises
    ------
    InputError
        No FLUTTER card; a selected FLUTTER, its FLFACT lists or the SDAMP TABDMP1 not defined.
    UnsupportedCardError
        A method other than PK, PKNL, K, KE; TABDMP1 TYPE other than G, CRIT, Q; PARAM KDAMP < 0.
    """
    if not bdf.flutters:
        raise InputError(card_message("the deck has no FLUTTER card.", card="FLUTTER",
                                      filename=filename,
                                      fix="add FLUTTER/FLFACT cards and FMETHOD."))
    rhoref = float(bdf.aero.rho_ref) if bdf.aero is not None else 1.0
    selected = _selection(bdf, flutter_ids)
    extra = sorted(set(dict(solvers)) - {sid for sid, _ in selected})
    if extra:
        raise InputError(card_message(
            f"[flutter] solvers names FLUTTER {extra}, which are not run (run: "
            f"{[sid for sid, _ in selected]}).", card="FLUTTER", card_id=extra[0],
            filename=filename, fix="name only FLUTTER ids that are run, or add them to flutter_ids."))
    out = []
    for sid, sdamp in selected:
        if sid not in bdf.flutters:
            who = "FMETHOD" if flutter_ids is None else "[flutter] flutter_ids (or --flutter-id)"
            raise InputError(card_message(f"{who} names FLUTTER {sid}, which is not defined; "
                                          f"defined: {sorted(bdf.flutters)}.",
                                          card="FLUTTER", card_id=sid, filename=filename,
                                          fix=f"add the FLUTTER card or correct {who}."))
        fl = bdf.flutters[sid]
        lists = []
        for what, fid in (("density", fl.density), ("Mach", fl.mach),
                          ("velocity/k", fl.reduced_freq_velocity)):
            fid = fid if isinstance(fid, int) else fid.sid
            if fid not in bdf.flfacts:
                raise InputError(card_message(f"FLUTTER {sid} refers to FLFACT {fid} ({what}), "
                                              "which is not defined.", card="FLFACT", card_id=fid,
                                              filename=filename, fix="add the FLFACT card."))
            lists.append(np.asarray(bdf.flfacts[fid].factors, dtype=float))
        dens, mach, vals = lists
        chosen = dict(solvers).get(sid, solver)
        if fl.method not in ("PK", "PKNL") and sid not in dict(solvers):
            chosen = "pk"  # a case-wide solver applies to the PK / PKNL cards only
        out.append(FlutterRequest(
            solver=chosen, sid=sid, method=fl.method, density=tuple(dens * rhoref), mach=tuple(mach),
            values=tuple(np.abs(vals)), rhoref=rhoref,
            damping=_damping(bdf, None if sdamp is None else int(sdamp), structural_damping,
                             filename),
            source=filename))
    return out


def deck_damping(bdf, filename: str = "",
                 structural_damping: float | None = None) -> StructuralDamping:
    """Structural damping of flight points that replace the deck's FLUTTER cards (a case's
    ``[flutter.matched]``): the case's constant g if given, else the TABDMP1 that the case
    control's SDAMP selects for flutter (that of the subcases with an FMETHOD, which must agree;
    without one, the global SDAMP), else none.

    Parameters
    ----------
    bdf : pyNastran BDF
    filename : str
        The deck's file name, for messages.
    structural_damping : float, optional
        The case's g on every mode (modal viscous, as Nastran's KDAMP = 1).

    Returns
    -------
    StructuralDamping

    Raises
    ------
    InputError
        The FMETHOD subcases select different SDAMP tables (and no ``structural_damping``); the
        selected TABDMP1 is not defined.
    UnsupportedCardError
        TABDMP1 TYPE other than G, CRIT, Q; PARAM KDAMP < 0.
    """
    selected, glob_sdamp = _case_control(bdf)
    tables = sorted({sdamp for _, sdamp in selected}, key=str) if selected else [glob_sdamp]
    if structural_damping is None and len(tables) > 1:
        raise InputError(card_message(
            f"the FMETHOD subcases select different SDAMP tables {tables}; matched flight "
            "points take one structural damping.", card="SDAMP", filename=filename,
            fix="set [flutter] structural_damping, or give the subcases one SDAMP."))
    sdamp = tables[0]
    return _damping(bdf, None if sdamp is None else int(sdamp), structural_damping, filename)
