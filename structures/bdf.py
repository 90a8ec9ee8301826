"""Read a Nastran bulk-data deck (INCLUDEs resolved) through pyNastran into an :class:`FEModel`.

pyNastran parses the cards; this module validates them and converts them into the project's frozen
dataclasses, so that every later step works on checked, basic-frame data. Structural cards the
project does not model raise :class:`UnsupportedCardError` listing them with their ids.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from structures.common.errors import (InputError, MissingReferenceError, UnsupportedCardError,
                                      card_message)
from structures.common.nastran import read_pynastran
from structures.frames import displacement_axes
from structures.model import (ConcentratedMass, ElementSet, FEModel, Grids, Material, Property,
                              RigidElement)
from structures.sections import section_fields

#: Structural cards this project models.
SUPPORTED_CARDS = frozenset({
    "GRID", "CORD1R", "CORD1C", "CORD1S", "CORD2R", "CORD2C", "CORD2S",
    "CBAR", "CBEAM", "PBAR", "PBARL", "PBEAM", "PBEAML", "CROD", "PROD", "CELAS1", "CELAS2",
    "PELAS", "CBUSH", "PBUSH", "CONM2", "CMASS2", "RBE2", "RBAR", "RBE3", "CQUAD4", "CTRIA3",
    "PSHELL", "MAT1", "MAT2", "MAT8", "SPC", "SPC1", "SPCADD", "SUPORT", "SUPORT1", "EIGRL", "EIGR",
    "PARAM",
})

#: Cards read elsewhere (aerodynamics, flutter, output control) and ignored by the structures;
#: SOL 200 design-model cards too: the analysis model is the deck's initial design, as in SOL 103;
#: static loads do not enter normal modes.
NON_STRUCTURAL_CARDS = frozenset({
    "ENDDATA", "AERO", "AEROS", "CAERO1", "PAERO1", "SPLINE1", "SPLINE2", "SET1", "SET2", "AEFACT",
    "MKAERO1", "MKAERO2", "FLUTTER", "FLFACT", "TABDMP1", "MDLPRM", "AELIST", "AESTAT", "TRIM",
    "DTI", "DMI", "DMIG", "PLOTEL",
    "DESVAR", "DLINK", "DVPREL1", "DVPREL2", "DVMREL1", "DVGRID", "DRESP1", "DRESP2", "DCONSTR",
    "DCONADD", "DSCREEN", "DOPTPRM",
    "FORCE", "MOMENT", "LOAD", "GRAV", "PLOAD2", "PLOAD4",
})

#: CBAR/CBEAM OFFT values (orientation vector, end A offset, end B offset frames; MSC QRG CBAR).
_OFFT = ("GGG", "BGG", "GGO", "BGO", "GOG", "BOG", "GOO", "BOO")

def _comp_mask(components) -> int:
    """Bit mask of a Nastran component string such as '1246' (bit c-1 for component c)."""
    text = "" if components in (None, "", 0) else str(int(components)) if not isinstance(
        components, str) else components.strip()
    mask = 0
    for ch in text:
        if ch == "0":
            continue
        if ch not in "123456":
            raise InputError(f"component string {components!r} has an invalid digit {ch!r}. "
                             "Fix: use digits 1-6.")
        mask |= 1 << (int(ch) - 1)
    return mask


def _check_cards(model, filename: str) -> None:
    unsupported = {}
    for name, count in model.card_count.items():
        if name in SUPPORTED_CARDS or name in NON_STRUCTURAL_CARDS:
            continue
        unsupported[name] = count
    rejects = []
    for lines in getattr(model, "reject_lines", []):
        first = next((text for text in lines if text.strip()), "")
        name = (first.split(",")[0].split() or [first.strip()[:16]])[0].rstrip("*").upper()
        if name:
            rejects.append(name)
    for name in rejects:
        unsupported.setdefault(name, 1)
    if unsupported:
        ids = {}
        for store in (model.elements, model.properties, model.masses, model.rigid_elements,
                      model.materials):
            for key, card in store.items():
                if card.type in unsupported:
                    ids.setdefault(card.type, []).append(key)
        listing = "; ".join(
            f"{name} ({', '.join(map(str, sorted(ids.get(name, []))[:10])) or count})"
            for name, count in sorted(unsupported.items()))
        raise UnsupportedCardError(card_message(
            f"unsupported structural cards: {listing}.", filename=filename,
            fix="replace them by supported cards (" + ", ".join(sorted(SUPPORTED_CARDS)) + ") or "
                "remove them from the deck."))


def _grids(model, filename: str) -> Grids:
    ids = np.array(sorted(model.nodes), dtype=np.int64)
    xyz = np.zeros((len(ids), 3))
    cd = np.zeros(len(ids), dtype=np.int64)
    ps = np.zeros(len(ids), dtype=np.int64)
    for i, nid in enumerate(ids):
        node = model.nodes[nid]
        xyz[i] = node.get_position()
        cd[i] = node.cd
        ps[i] = _comp_mask(node.ps)
    axes = np.tile(np.eye(3), (len(ids), 1, 1))
    for cid in np.unique(cd):
        if cid == 0:
            continue
        if cid not in model.coords:
            bad = ids[cd == cid][:5].tolist()
            raise MissingReferenceError(card_message(
                f"displacement coordinate system CD={cid} is not defined (grids {bad}).",
                card="GRID", card_id=bad[0], filename=filename,
                fix=f"add CORD2R/CORD2C/CORD2S {cid} or correct the CD field."))
        coord = model.coords[cid]
        sel = cd == cid
        axes[sel] = displacement_axes(coord.Type, coord.origin, coord.beta(), xyz[sel])
    return Grids(ids=ids, xyz=xyz, cd_axes=axes, cd=cd, ps=ps)


def _materials(model) -> dict:
    out = {}
    names = {
        "MAT1": (("E", "e"), ("G", "g"), ("NU", "nu"), ("RHO", "rho")),
        "MAT2": (("G11", "G11"), ("G12", "G12"), ("G13", "G13"), ("G22", "G22"), ("G23", "G23"),
                 ("G33", "G33"), ("RHO", "rho")),
        "MAT8": (("E1", "e11"), ("E2", "e22"), ("NU12", "nu12"), ("G12", "g12"), ("G1Z", "g1z"),
                 ("G2Z", "g2z"), ("RHO", "rho")),
    }
    for mid, mat in model.materials.items():
        fields = {key: getattr(mat, attr) for key, attr in names[mat.type]}
        if mat.type == "MAT8":
            # pyNastran stores a blank G1Z/G2Z as 1e8; Nastran's blank means rigid in shear.
            for key in ("G1Z", "G2Z"):
                if fields[key] == 1e8:
                    fields[key] = None
        out[mid] = Material(mid, mat.type, fields)
    return out


def _properties(model, filename: str) -> dict:
    out = {}
    for pid, prop in model.properties.items():
        kind = prop.type
        if kind == "PBAR":
            fields = dict(MID=prop.mid, A=prop.A, I1=prop.i1, I2=prop.i2, I12=prop.i12, J=prop.j,
                          NSM=prop.nsm, K1=prop.k1, K2=prop.k2)
        elif kind == "PBARL":
            fields = section_fields("PBARL", pid, prop.mid, prop.beam_type, [prop.dim], [0.0],
                                    [prop.nsm], filename)
        elif kind == "PBEAM":
            # Tapered PBEAMs use the mean of the end-station values (a stated approximation).
            def mean(values):
                return 0.5 * (float(values[0]) + float(values[-1]))
            fields = dict(MID=prop.mid, A=mean(prop.A), I1=mean(prop.i1), I2=mean(prop.i2),
                          I12=mean(prop.i12), J=mean(prop.j), NSM=mean(prop.nsm),
                          K1=prop.k1, K2=prop.k2)
        elif kind == "PBEAML":
            fields = section_fields("PBEAML", pid, prop.mid, prop.beam_type, prop.dim, prop.xxb,
                                    prop.nsm, filename)
        elif kind == "PROD":
            fields = dict(MID=prop.mid, A=prop.A, J=prop.j, NSM=prop.nsm)
        elif kind == "PELAS":
            fields = dict(K=prop.k, GE=prop.ge)
        elif kind == "PBUSH":
            kvals = list(prop.Ki) + [0.0] * (6 - len(prop.Ki))
            fields = {f"K{i + 1}": (kvals[i] or 0.0) for i in range(6)}
        elif kind == "PSHELL":
            fields = {"MID1": prop.mid1, "T": prop.t, "MID2": prop.mid2,
                      "12I/T**3": prop.twelveIt3, "MID3": prop.mid3, "TS/T": prop.tst,
                      "NSM": prop.nsm, "MID4": prop.mid4, "Z1": prop.z1, "Z2": prop.z2}
        else:
            raise UnsupportedCardError(card_message(f"property type {kind} is not supported.",
                                                    card=kind, card_id=pid, filename=filename))
        if kind in ("PBAR", "PBARL", "PBEAM") and (fields["K1"] is not None and fields["K1"] >= 1e8):
            fields["K1"] = fields["K2"] = None  # pyNastran's blank default: no shear flexibility
        out[pid] = Property(pid, {"PBARL": "PBAR", "PBEAML": "PBEAM"}.get(kind, kind), fields)
    return out


def _line_elements(model, kind, filename):
    cards = [e for e in model.elements.values() if e.type == kind]
    if not cards:
        return None
    eids, pids, nodes = [], [], []
    vector, g0, offt, pa, pb, wa, wb = [], [], [], [], [], [], []
    for e in cards:
        eids.append(e.eid)
        pids.append(e.pid)
        nodes.append([e.ga, e.gb])
        g0.append(e.g0 or 0)
        vector.append(np.zeros(3) if e.x is None else np.asarray(e.x, float))
        flag = getattr(e, "offt", "GGG")
        # An integer in the OFFT field is the legacy "F" flag (1: X vector, 2: G0): default frames.
        flag = flag if isinstance(flag, str) and flag else "GGG"
        if flag not in _OFFT:
            raise InputError(card_message(f"OFFT = {flag!r} is not a valid offset flag.", card=kind,
                                          card_id=e.eid, filename=filename,
                                          fix=f"use one of {', '.join(_OFFT)} (or leave it blank)."))
        offt.append(flag)
        pa.append(_comp_mask(e.pa))
        pb.append(_comp_mask(e.pb))
        wa.append(np.asarray(e.wa, float))
        wb.append(np.asarray(e.wb, float))
        if kind == "CBEAM" and (getattr(e, "sa", 0) or getattr(e, "sb", 0)):
            raise UnsupportedCardError(card_message("warping scalar points SA/SB are not supported.",
                                                    card="CBEAM", card_id=e.eid, filename=filename,
                                                    fix="leave SA and SB blank."))
    return ElementSet(kind, eids, pids, nodes, dict(v=np.array(vector), g0=np.array(g0),
                                                    offt=np.array(offt), pa=np.array(pa),
                                                    pb=np.array(pb), wa=np.array(wa),
                                                    wb=np.array(wb)))


def _elements(model, filename: str) -> dict:
    coords = model.coords
    sets = {}
    for kind in ("CBAR", "CBEAM"):
        es = _line_elements(model, kind, filename)
        if es is not None:
            sets[kind] = es
    rods = [e for e in model.elements.values() if e.type == "CROD"]
    if rods:
        sets["CROD"] = ElementSet("CROD", [e.eid for e in rods], [e.pid for e in rods],
                                  [e.nodes for e in rods])
    springs = [e for e in model.elements.values() if e.type in ("CELAS1", "CELAS2")]
    if springs:
        k = [np.nan if e.type == "CELAS1" else e.k for e in springs]
        sets["CELAS"] = ElementSet(
            "CELAS", [e.eid for e in springs], [e.pid if e.type == "CELAS1" else 0 for e in springs],
            [[n or 0 for n in e.nodes] for e in springs],
            dict(c1=[int(e.c1 or 0) for e in springs], c2=[int(e.c2 or 0) for e in springs], k=k))
    bushes = [e for e in model.elements.values() if e.type == "CBUSH"]
    for e in bushes:
        if e.ocid not in (None, -1):
            raise UnsupportedCardError(card_message(
                "a spring-damper offset system OCID is not supported.", card="CBUSH",
                card_id=e.eid, filename=filename,
                fix="leave OCID blank (the spring then lies on the line GA-GB at S)."))
    if bushes:
        sets["CBUSH"] = ElementSet(
            "CBUSH", [e.eid for e in bushes], [e.pid for e in bushes],
            [[e.nodes[0], e.nodes[1] or 0] for e in bushes],
            dict(v=[np.zeros(3) if e.x is None or e.x[0] is None else np.asarray(e.x, float)
                    for e in bushes],
                 g0=[e.g0 or 0 for e in bushes],
                 cid=[-1 if e.cid is None else e.cid for e in bushes],
                 s=[0.5 if e.s is None else e.s for e in bushes]))
    for kind, nn in (("CQUAD4", 4), ("CTRIA3", 3)):
        shells = [e for e in model.elements.values() if e.type == kind]
        if not shells:
            continue
        for e in shells:
            if isinstance(e.theta_mcid, int) and e.theta_mcid not in coords:
                raise MissingReferenceError(card_message(
                    f"material coordinate system MCID={e.theta_mcid} is not defined.",
                    card=kind, card_id=e.eid, filename=filename,
                    fix=f"add CORD2R {e.theta_mcid} or give THETA instead."))
            if getattr(e, "tflag", 0):
                raise UnsupportedCardError(card_message("TFLAG=1 (relative thicknesses) is not "
                                                        "supported.", card=kind, card_id=e.eid,
                                                        filename=filename,
                                                        fix="give absolute corner thicknesses."))
        # Whole-family arrays: MCID (-1 for THETA), THETA [rad], ZOFFS, corner thicknesses
        # (blank or -1: the PSHELL T, as NaN).
        mcid = np.array([e.theta_mcid if isinstance(e.theta_mcid, int) else -1 for e in shells])
        theta = np.deg2rad([0.0 if isinstance(e.theta_mcid, int) else e.theta_mcid or 0.0
                            for e in shells])
        mcid_x = np.zeros((len(shells), 3))
        for i in np.flatnonzero(mcid >= 0):
            mcid_x[i] = coords[mcid[i]].beta()[0]
        zoff = np.array([e.zoffset or 0.0 for e in shells], dtype=float)
        corners = [f"T{i + 1}" for i in range(nn)]
        tnodal = np.array([[getattr(e, t) for t in corners] for e in shells], dtype=float)
        tnodal[tnodal == -1.0] = np.nan
        sets[kind] = ElementSet(kind, [e.eid for e in shells], [e.pid for e in shells],
                                [e.nodes for e in shells],
                                dict(theta=theta, mcid=mcid, mcid_x=mcid_x, zoffset=zoff,
                                     t_nodal=tnodal))
    cmass = [m for m in model.masses.values() if m.type == "CMASS2"]
    if cmass:
        sets["CMASS2"] = ElementSet(
            "CMASS2", [m.eid for m in cmass], [0] * len(cmass),
            [[n or 0 for n in m.nodes] for m in cmass],
            dict(c1=[int(m.c1 or 0) for m in cmass], c2=[int(m.c2 or 0) for m in cmass],
                 mass=[m.mass for m in cmass]))
    return sets


def _conm2(model, grids: Grids, filename: str) -> ConcentratedMass:
    cards = [m for m in model.masses.values() if m.type == "CONM2"]
    eids, gids, mass, offset, inertia = [], [], [], [], []
    for m in cards:
        values = np.array([m.mass, *m.X, *m.I], float)
        if not np.all(np.isfinite(values)):
            raise InputError(card_message(f"mass, offset or inertia {values.tolist()} holds a "
                                          "non-finite number.", card="CONM2", card_id=m.eid,
                                          filename=filename, fix="give real values."))
        if m.mass < 0 or (m.mass == 0 and not np.any(m.I)):
            raise InputError(card_message(f"mass {m.mass} is not positive.", card="CONM2",
                                          card_id=m.eid, filename=filename,
                                          fix="give a positive mass (or remove the card)."))
        g = grids.index([m.nid], card="CONM2", card_id=m.eid, filename=filename)[0]
        i11, i21, i22, i31, i32, i33 = m.I
        tensor = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]], float)
        if np.any(np.linalg.eigvalsh(tensor) < -1e-12 * max(1.0, abs(tensor).max())):
            raise InputError(card_message("the inertia tensor is not positive semi-definite.",
                                          card="CONM2", card_id=m.eid, filename=filename,
                                          fix="check the signs and magnitudes of I11..I33."))
        if m.cid == -1:
            rot = np.eye(3)
            off = np.asarray(m.X, float) - grids.xyz[g]
        else:
            if m.cid == 0:
                rot = np.eye(3)
            elif m.cid in model.coords:
                coord = model.coords[m.cid]
                rot = displacement_axes(coord.Type, coord.origin, coord.beta(), grids.xyz[g][None])[0]
            else:
                raise MissingReferenceError(card_message(
                    f"coordinate system {m.cid} is not defined.", card="CONM2", card_id=m.eid,
                    filename=filename, fix=f"add CORD2R {m.cid} or correct CID."))
            off = rot @ np.asarray(m.X, float)
        eids.append(m.eid)
        gids.append(m.nid)
        mass.append(m.mass)
        offset.append(off)
        inertia.append(rot @ tensor @ rot.T)
    return ConcentratedMass(eids, gids, mass, offset, inertia)


def _rigid(model, filename: str) -> tuple:
    out = []
    for eid, r in sorted(model.rigid_elements.items()):
        if r.type == "RBE2":
            out.append(RigidElement(eid, "RBE2", ((r.gn, "123456"),),
                                    tuple((g, str(r.cm)) for g in r.Gmi)))
        elif r.type == "RBAR":
            indep = tuple((g, str(c)) for g, c in ((r.ga, r.cna), (r.gb, r.cnb)) if c)
            dep = tuple((g, str(c)) for g, c in ((r.ga, r.cma), (r.gb, r.cmb)) if c)
            out.append(RigidElement(eid, "RBAR", indep, dep))
        elif r.type == "RBE3":
            if r.Gmi:
                raise UnsupportedCardError(card_message("UM (alternative dependent DOFs) is not "
                                                        "supported.", card="RBE3", card_id=eid,
                                                        filename=filename,
                                                        fix="leave the UM fields blank."))
            indep, weights = [], []
            for wt, comp, gids in zip(r.weights, r.comps, r.Gijs):
                if not (np.isfinite(wt) and wt > 0):
                    raise InputError(card_message(f"weight WT = {wt} is not a positive number.",
                                                  card="RBE3", card_id=eid, filename=filename,
                                                  fix="give positive, finite weights."))
                for g in gids:
                    indep.append((g, str(comp)))
                    weights.append(float(wt))
            out.append(RigidElement(eid, "RBE3", tuple(indep), ((r.refgrid, str(r.refc)),),
                                    tuple(weights)))
        else:
            raise UnsupportedCardError(card_message(f"rigid element {r.type} is not supported.",
                                                    card=r.type, card_id=eid, filename=filename))
    return tuple(out)


def _case_value(model, name: str):
    """The value of a case-control command (the highest subcase that has it), or None."""
    cc = model.case_control_deck
    if cc is None:
        return None
    for sub_id in sorted(cc.subcases, reverse=True):
        sub = cc.subcases[sub_id]
        found = sub.has_parameter(name)  # pyNastran returns [bool] for one name
        if found[0] if isinstance(found, list) else found:
            return sub.get_parameter(name)[0]
    return None


def _case_id(model, name: str):
    value = _case_value(model, name)
    return None if value is None else int(value)


def _yes_no(value, name: str, filename: str) -> bool:
    text = str(value).strip().upper()
    if text not in ("YES", "NO"):
        raise InputError(card_message(f"{name} = {value!r} is not YES or NO.", card="PARAM",
                                      card_id=name, filename=filename, fix="give YES or NO."))
    return text == "YES"


def _params(model, filename: str) -> dict:
    """PARAMs the structures use, with Nastran's defaults (MSC QRG, SOL 103).

    WTMASS (1.0), COUPMASS (-1: lumped), K6ROT (100.), EPZERO (1e-8) and AUTOSPC (YES; the case
    control command AUTOSPC, when present, overrides PARAM AUTOSPC). Other PARAMs (LMODES, GRDPNT,
    NEWSEQ, ...) do not change the stiffness or mass and are ignored.
    """
    def value(name, default):
        return model.params[name].values[0] if name in model.params else default
    autospc = _case_value(model, "AUTOSPC")
    return dict(wtmass=float(value("WTMASS", 1.0)), coupmass=int(value("COUPMASS", -1)),
                k6rot=float(value("K6ROT", FEModel.k6rot)),
                epzero=float(value("EPZERO", FEModel.epzero)),
                autospc=_yes_no(value("AUTOSPC", "YES") if autospc is None else autospc,
                                "AUTOSPC", filename))


def _spc(model, filename: str, spc_id) -> tuple:
    if not model.spcs and not model.spcadds:
        return ()
    if spc_id is None:
        spc_id = _case_id(model, "SPC")
    available = sorted(set(model.spcs) | set(model.spcadds))
    if spc_id is None:
        if len(available) > 1:
            raise InputError(card_message(
                f"several SPC sets {available} and no SPC= selection in the case control.",
                filename=filename, fix="add 'SPC = id' to the case control or pass spc_id."))
        spc_id = available[0]
    if spc_id not in available:
        raise MissingReferenceError(card_message(
            f"SPC set {spc_id} is selected but not defined (defined: {available}).", card="SPC",
            card_id=spc_id, filename=filename, fix="define the set or correct the selection."))
    ids = [spc_id]
    if spc_id in model.spcadds:
        ids = [sid for add in model.spcadds[spc_id] for sid in add.sets]
    out = []
    for sid in ids:
        for card in model.spcs.get(sid, []):
            if card.type == "SPC1":
                out.extend((g, _comp_mask(card.components)) for g in card.nodes)
            else:
                out.extend((g, _comp_mask(c)) for g, c in zip(card.nodes, card.components))
    return tuple(out)


def _suport(model, grids, filename: str) -> tuple:
    """(grid, component mask) of the r-set: every SUPORT card and the SUPORT1 set the case
    control selects (``SUPORT1 = id``; Nastran ignores unselected SUPORT1 sets)."""
    cards = [("SUPORT", card) for card in model.suport]
    sid = _case_id(model, "SUPORT1")
    if sid is not None:
        if sid not in model.suport1:
            raise MissingReferenceError(card_message(
                f"SUPORT1 set {sid} is selected but not defined (defined: "
                f"{sorted(model.suport1)}).", card="SUPORT1", card_id=sid, filename=filename,
                fix="define the set or correct the case control's SUPORT1 = selection."))
        cards.append(("SUPORT1", model.suport1[sid]))
    out = []
    for name, card in cards:
        for gid, comps in zip(card.nodes, card.Cs):
            grids.index([gid], card=name, card_id=gid, filename=filename)
            try:
                mask = _comp_mask(comps)
            except InputError:
                raise InputError(card_message(
                    f"grid {gid} has invalid components {comps!r}.", card=name, card_id=gid,
                    filename=filename, fix="give components as digits 1-6 (e.g. 35).")) from None
            if mask == 0:
                raise InputError(card_message(
                    f"grid {gid} has no components.", card=name, card_id=gid, filename=filename,
                    fix="give the supported components as digits 1-6 (e.g. 35)."))
            out.append((int(gid), mask))
    return tuple(out)


def read_model(path, *, spc_id: int | None = None, parsed=None) -> FEModel:
    """Read a Nastran bulk-data deck into a validated :class:`FEModel`.

    Parameters
    ----------
    path : str or Path
        The deck (executive and case control sections are allowed; INCLUDEs are followed).
    spc_id : int, optional
        The SPC set to apply; by default the case control's ``SPC =`` selection (or the only set).
    parsed : pyNastran BDF, optional
        ``path`` already parsed by :func:`structures.common.nastran.read_pynastran` (not read
        again).

    Raises
    ------
    UnsupportedCardError
        For structural cards outside :data:`SUPPORTED_CARDS`, listing them and their ids.
    MissingReferenceError, InputError
        For undefined grids, properties, materials or coordinate systems and invalid values.
    """
    path = Path(path)
    model = read_pynastran(path) if parsed is None else parsed
    filename = str(path)
    if not model.nodes:
        raise InputError(card_message("the deck has no grids (no GRID cards).", card="GRID",
                                      filename=filename, fix="add GRID and element cards, or "
                                      "INCLUDE the file that holds them."))
    _check_cards(model, filename)
    grids = _grids(model, filename)
    nd = None
    method_id = _case_id(model, "METHOD")
    method = model.methods.get(method_id) if method_id is not None else None
    if method is None and len(model.methods) == 1:
        method = next(iter(model.methods.values()))
    if method is not None:
        nd = getattr(method, "nd", None)
    suport = _suport(model, grids, filename)
    fe = FEModel(filename=filename, grids=grids, elements=_elements(model, filename),
                 properties=_properties(model, filename), materials=_materials(model),
                 masses=_conm2(model, grids, filename), rigid=_rigid(model, filename),
                 spc=_spc(model, filename, spc_id), suport=suport, eigrl_nd=nd,
                 **_params(model, filename))
    from structures.validate import validate_model
    validate_model(fe)
    return fe
