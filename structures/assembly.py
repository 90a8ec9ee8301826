"""Sparse assembly of K and M, constraint elimination and the free (a-set) system.

DOF sets follow Nastran: the g-set has 6 DOFs per grid in its displacement (CD) frame; rigid
elements make the m-set dependent (u_m = G_mo u_o); SPC, GRID PS and the automatic SPCs form the
s-set; the remaining a-set is what the eigensolver sees. Automatic SPCs are Nastran's grid point
singularity processing of K_nn (:mod:`structures.singularity`, PARAM EPZERO / AUTOSPC) plus, whatever
AUTOSPC says, the DOFs with no stiffness at all (diagonal <= 1e-12 of the model's largest
translational / rotational one), which no eigensolver can keep. ``T`` maps a-set
displacements to g-set ones (u_g = T u_a), so K_aa = T^T K_gg T and M_aa = T^T M_gg T.

Mass formulation: ``mass="deck"`` follows PARAM COUPMASS like Nastran (lumped unless COUPMASS > 0),
``"lumped"`` and ``"consistent"`` force one.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from structures.elements import beam, scalar, shell, shell_materials
from structures.common.errors import InputError, card_message
from structures.frames import rigid_offset
from structures.model import FEModel
from structures.rigid import solve_constraints
from structures.singularity import SingularityTable, grid_point_singularities, warn_singularities

MASS_OPTIONS = ("deck", "consistent", "lumped")


@dataclass(frozen=True)
class AssembledSystem:
    """Free-DOF stiffness and mass, and the maps back to all grid DOFs.

    Attributes
    ----------
    K, M : scipy.sparse.csc_matrix (na, na)
    T : scipy.sparse.csr_matrix (ng, na), u_g = T u_a (g-set in CD frames).
    a_dofs : (na,) int g-set numbers (grid index * 6 + component - 1) of the a-set.
    m_basic : scipy.sparse.csr_matrix (ng, ng), the g-set mass in BASIC axes (mass properties).
    rotation : scipy.sparse.csr_matrix (ng, ng), u_basic = rotation @ u_cd.
    autospc : (ns,) int g-set DOFs removed by automatic SPC (singularity table + no stiffness).
    singularities : SingularityTable, Nastran's GRID POINT SINGULARITY TABLE of K_nn.
    """

    K: sp.csc_matrix
    M: sp.csc_matrix
    T: sp.csr_matrix
    a_dofs: np.ndarray
    m_basic: sp.csr_matrix
    rotation: sp.csr_matrix
    autospc: np.ndarray
    singularities: SingularityTable


def _lumped(model: FEModel, mass: str) -> bool:
    if mass not in MASS_OPTIONS:
        raise InputError(f"unknown mass formulation {mass!r}; valid: {', '.join(MASS_OPTIONS)}.")
    if mass == "deck":
        return model.coupmass <= 0
    return mass == "lumped"


def line_offsets(model, es, gi, filename):
    """Orientation vectors and end offsets of CBAR/CBEAM in basic.

    Parameters
    ----------
    model : FEModel
    es : ElementSet of CBAR or CBEAM (ne elements).
    gi : (ne, 2) grid rows of the element ends.
    filename : str, for messages.

    Returns
    -------
    v, wa, wb : (ne, 3) orientation vector and end-A / end-B offsets, basic axes.
    """
    grids = model.grids
    axes = grids.cd_axes[gi]
    offt = es.data["offt"]
    v = np.array(es.data["v"], float)
    g0 = es.data["g0"]
    for e in np.flatnonzero(g0):
        v[e] = grids.xyz[grids.index([g0[e]], card=es.card, card_id=es.eids[e],
                                     filename=filename)[0]] - grids.xyz[gi[e, 0]]
    for e in np.flatnonzero(g0 == 0):
        if offt[e][0] == "G":
            v[e] = axes[e, 0] @ v[e]
    wa = np.array(es.data["wa"], float)
    wb = np.array(es.data["wb"], float)
    for e in range(len(es)):
        for col, w in ((0, wa), (1, wb)):
            flag = offt[e][1 + col]
            if flag == "G":
                w[e] = axes[e, col] @ w[e]
            elif flag == "O" and np.any(w[e]):
                raise InputError(card_message("element-frame offsets (OFFT with 'O') are not "
                                              "supported.", card=es.card, card_id=es.eids[e],
                                              filename=filename, fix="give offsets in G or B frames."))
    axis = grids.xyz[gi[:, 1]] + wb - grids.xyz[gi[:, 0]] - wa
    lengths = np.linalg.norm(axis, axis=1)
    cross = np.linalg.norm(np.cross(axis, v), axis=1)
    for e in np.flatnonzero((lengths <= 0) | (cross <= 1e-8 * lengths * np.linalg.norm(v, axis=1))):
        fix = ("separate its grids" if lengths[e] <= 0 else
               "give an orientation vector (X1-X3 or G0) that is not parallel to the axis")
        raise InputError(card_message("zero length or orientation vector parallel to the element "
                                      "axis.", card=es.card, card_id=es.eids[e], filename=filename,
                                      fix=fix + "."))
    return v, wa, wb


def _beams(model, es, lumped):
    gi = model.grids.index(es.nodes, card=es.card, filename=model.filename)
    v, wa, wb = line_offsets(model, es, gi, model.filename)
    cols = {k: np.zeros(len(es)) for k in ("E", "G", "A", "I1", "I2", "I12", "J", "NSM", "RHO")}
    k1, k2 = np.full(len(es), np.nan), np.full(len(es), np.nan)
    for e, (eid, pid) in enumerate(zip(es.eids, es.pids)):
        prop = model.property(pid, card=es.card, eid=eid)
        if prop.card not in ("PBAR", "PBEAM"):
            raise InputError(card_message(f"references {prop.card} {pid}; a PBAR/PBARL/PBEAM is "
                                          "required.", card=es.card, card_id=eid,
                                          filename=model.filename, fix="correct PID."))
        mat = model.material(prop.get("MID"), card=prop.card, pid=pid)
        cols["E"][e], cols["G"][e], _ = mat.isotropic()
        cols["RHO"][e] = mat.rho
        for key in ("A", "I1", "I2", "I12", "J", "NSM"):
            cols[key][e] = prop.get(key)
        k1[e] = np.nan if prop.fields.get("K1") is None else prop.fields["K1"]
        k2[e] = np.nan if prop.fields.get("K2") is None else prop.fields["K2"]
    pins = es.data["pa"] | (es.data["pb"] << 6)
    k, m = beam.beam_matrices(model.grids.xyz[gi[:, 0]], model.grids.xyz[gi[:, 1]], v, wa, wb,
                              cols["E"], cols["G"], cols["A"], cols["I1"], cols["I2"], cols["I12"],
                              cols["J"], cols["NSM"], cols["RHO"],
                              None if np.all(np.isnan(k1)) else k1,
                              None if np.all(np.isnan(k2)) else k2, pins, lumped,
                              torsional_inertia=es.card == "CBEAM")
    return gi, k, m


def _rods(model, es, lumped):
    gi = model.grids.index(es.nodes, card="CROD", filename=model.filename)
    vals = np.zeros((6, len(es)))
    for e, (eid, pid) in enumerate(zip(es.eids, es.pids)):
        prop = model.property(pid, card="CROD", eid=eid)
        e_mod, g_mod, _ = model.material(prop.get("MID"), card="PROD", pid=pid).isotropic()
        vals[:, e] = (e_mod, g_mod, prop.get("A"), prop.get("J"), prop.get("NSM"),
                      model.materials[prop.get("MID")].rho)
    k, m = beam.rod_matrices(model.grids.xyz[gi[:, 0]], model.grids.xyz[gi[:, 1]], *vals, lumped)
    return gi, k, m


def _scalar_dirs(model, es):
    """Grid indices (grounded ends mapped to the first grid) and component directions."""
    nodes = es.nodes
    gi = np.zeros_like(nodes)
    dirs = []
    for col, comp in ((0, es.data["c1"]), (1, es.data["c2"])):
        present = nodes[:, col] > 0
        gi[present, col] = model.grids.index(nodes[present, col], card=es.card,
                                             filename=model.filename)
        comp = np.where(present, comp, 0)
        dirs.append(scalar.component_direction(model.grids.cd_axes[gi[:, col]], comp))
    gi[nodes[:, 1] == 0, 1] = gi[nodes[:, 1] == 0, 0]
    return gi, dirs


def _springs(model, es):
    gi, (d1, d2) = _scalar_dirs(model, es)
    k = np.array(es.data["k"], float)
    for e in np.flatnonzero(np.isnan(k)):
        prop = model.property(es.pids[e], card="CELAS1", eid=es.eids[e])
        k[e] = prop.get("K")
    return gi, scalar.scalar_pair_matrices(k, d1, d2), None


def _cmass2(model, es):
    """CMASS2 scalar masses (their values are checked by structures.validate at read time)."""
    gi, (d1, d2) = _scalar_dirs(model, es)
    return gi, None, scalar.scalar_pair_matrices(np.asarray(es.data["mass"], float), d1, d2)


def _bushes(model, es):
    grids = model.grids
    ga = grids.index(es.nodes[:, 0], card="CBUSH", filename=model.filename)
    has_b = es.nodes[:, 1] > 0
    gb = ga.copy()
    gb[has_b] = grids.index(es.nodes[has_b, 1], card="CBUSH", filename=model.filename)
    x_b = np.where(has_b[:, None], grids.xyz[gb], np.nan)
    axes = np.zeros((len(es), 3, 3))
    kd = np.zeros((len(es), 6))
    for e, eid in enumerate(es.eids):
        prop = model.property(es.pids[e], card="CBUSH", eid=eid)
        kd[e] = [prop.get(f"K{i}") for i in range(1, 7)]
        cid = int(es.data["cid"][e])
        d = grids.xyz[gb[e]] - grids.xyz[ga[e]]
        if cid == 0:
            axes[e] = np.eye(3)
        elif cid > 0:
            raise InputError(card_message("CID > 0 is not supported; give CID=0 or an orientation "
                                          "vector.", card="CBUSH", card_id=eid,
                                          filename=model.filename,
                                          fix="express the stiffness in the basic frame (CID=0)."))
        elif np.linalg.norm(d) > 0:
            v = np.array(es.data["v"][e], float)
            if es.data["g0"][e]:
                v = grids.xyz[grids.index([es.data["g0"][e]])[0]] - grids.xyz[ga[e]]
            else:
                v = grids.cd_axes[ga[e]] @ v
            axes[e], _ = beam.beam_axes(grids.xyz[ga[e]][None], grids.xyz[gb[e]][None], v[None])
        else:
            raise InputError(card_message("coincident or grounded CBUSH without CID.", card="CBUSH",
                                          card_id=eid, filename=model.filename,
                                          fix="set CID=0 (basic) for coincident grids."))
    k = scalar.bush_matrices(grids.xyz[ga], x_b, axes, kd, es.data["s"])
    return np.stack([ga, gb], axis=1), k, None


def _shells(model, es, lumped):
    grids = model.grids
    gi = grids.index(es.nodes, card=es.card, filename=model.filename)
    xyz = grids.xyz[gi]
    axes = shell.element_axes(xyz)
    normal = axes[:, 2]
    theta = np.array(es.data["theta"], float)
    with_mcid = np.flatnonzero(es.data["mcid"] >= 0)
    if with_mcid.size:
        theta[with_mcid] = shell.material_angle(axes[with_mcid],
                                                es.data["mcid_x"][with_mcid])
    zoff = np.asarray(es.data["zoffset"], float)
    t_nodal = np.asarray(es.data["t_nodal"], float)
    nn = xyz.shape[1]
    mats = {mid: shell_materials.material_from_fields(mid, m.card, m.fields)
            for mid, m in model.materials.items()}
    k = m = None
    order = np.argsort(es.pids, kind="stable")
    for pid in np.unique(es.pids):
        prop = model.property(pid, card=es.card, eid=es.eids[es.pids == pid][0])
        if prop.card != "PSHELL":
            raise InputError(card_message(f"references {prop.card} {pid}; a PSHELL is required.",
                                          card=es.card, card_id=es.eids[es.pids == pid][0],
                                          filename=model.filename, fix="correct PID."))
        sel = order[es.pids[order] == pid]
        t_elem = np.nanmean(np.where(np.isnan(t_nodal[sel]), prop.get("T"), t_nodal[sel]), axis=1)
        for t_val in np.unique(t_elem):
            part = sel[t_elem == t_val]
            fields = dict(prop.fields)
            fields["T"] = t_val
            section = shell_materials.pshell_section(shell_materials.pshell_from_fields(pid, fields),
                                                     mats, len(part))
            shifted = xyz[part] + zoff[part, None, None] * normal[part, None, :]
            fn = shell.quad4_matrices if nn == 4 else shell.tria3_matrices
            kp, mp = fn(shifted, section, theta[part], lumped, model.k6rot)
            if np.any(zoff[part]):
                t = np.zeros((len(part), 6 * nn, 6 * nn))
                off = rigid_offset(zoff[part, None] * normal[part])
                for node in range(nn):
                    t[:, 6 * node:6 * node + 6, 6 * node:6 * node + 6] = off
                kp = np.einsum("eji,ejk,ekl->eil", t, kp, t)
                mp = np.einsum("eji,ejk,ekl->eil", t, mp, t)
            if len(part) == len(es):             # one property and thickness: no copy
                k, m = kp, mp
                continue
            if k is None:
                k, m = np.zeros((2, len(es), 6 * nn, 6 * nn))
            k[part], m[part] = kp, mp
    return gi, k, m


def _conm2(model):
    cm = model.masses
    if len(cm) == 0:
        return None
    gi = model.grids.index(cm.grid, card="CONM2", filename=model.filename)
    return gi[:, None], None, scalar.conm2_matrices(cm.mass, cm.offset, cm.inertia)


def element_matrices(model: FEModel, mass: str = "deck"):
    """Yield (grid_index (ne, nn), K or None, M or None) per element family, basic axes."""
    lumped = _lumped(model, mass)
    for kind, es in model.elements.items():
        if kind in ("CBAR", "CBEAM"):
            yield _beams(model, es, lumped)
        elif kind == "CROD":
            yield _rods(model, es, lumped)
        elif kind == "CELAS":
            yield _springs(model, es)
        elif kind == "CMASS2":
            yield _cmass2(model, es)
        elif kind == "CBUSH":
            yield _bushes(model, es)
        elif kind in ("CQUAD4", "CTRIA3"):
            yield _shells(model, es, lumped)
    conm = _conm2(model)
    if conm is not None:
        yield conm


def _scatter(entries, n_g):
    """Sum element matrices (ne, nd, nd) on grid indices (ne, nn) into a CSR (n_g, n_g).

    Only the nonzero entries are scattered (a flat shell's membrane and bending blocks do not
    couple, lumped masses are diagonal), with 32-bit indices when they fit: the sums are the same.
    """
    index = np.int32 if n_g < np.iinfo(np.int32).max else np.int64
    rows, cols, vals = [], [], []
    for gi, mat in entries:
        dofs = (6 * gi[:, :, None] + np.arange(6)).reshape(len(gi), -1).astype(index)
        nonzero = mat != 0.0
        rows.append(np.broadcast_to(dofs[:, :, None], mat.shape)[nonzero])
        cols.append(np.broadcast_to(dofs[:, None, :], mat.shape)[nonzero])
        vals.append(mat[nonzero])
    if not rows:
        return sp.csr_matrix((n_g, n_g))
    out = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                        shape=(n_g, n_g)).tocsr()
    out.eliminate_zeros()
    return out


def rotation_matrix(model: FEModel) -> sp.csr_matrix:
    """Block-diagonal map from CD-frame to basic-frame g-set DOFs (u_basic = R u_cd)."""
    axes = model.grids.cd_axes
    n = len(axes)
    blocks = np.repeat(axes, 2, axis=0)
    base = 3 * np.arange(2 * n)
    rows = np.broadcast_to(base[:, None, None] + np.arange(3)[None, :, None], (2 * n, 3, 3))
    cols = np.broadcast_to(base[:, None, None] + np.arange(3)[None, None, :], (2 * n, 3, 3))
    return sp.csr_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(6 * n, 6 * n))


def assemble_g(model: FEModel, mass: str = "deck"):
    """K_gg and M_gg in BASIC axes (sparse, symmetric)."""
    n_g = 6 * len(model.grids)
    k_entries, m_entries = [], []
    for gi, k, m in element_matrices(model, mass):
        if k is not None:
            k_entries.append((gi, k))
        if m is not None:
            m_entries.append((gi, m))
    return _scatter(k_entries, n_g), _scatter(m_entries, n_g) * model.wtmass


def _constrained(model: FEModel, m_dofs) -> np.ndarray:
    """g-set DOFs fixed by SPC and GRID PS."""
    grids = model.grids
    fixed = np.zeros(6 * len(grids), dtype=bool)
    for gid, mask in model.spc:
        g = grids.index([gid], card="SPC", filename=model.filename)[0]
        for c in range(6):
            if mask >> c & 1:
                fixed[6 * g + c] = True
    for g, mask in enumerate(grids.ps):
        for c in range(6):
            if mask >> c & 1:
                fixed[6 * g + c] = True
    clash = np.intersect1d(np.flatnonzero(fixed), m_dofs)
    if clash.size:
        d = clash[0]
        raise InputError(card_message(
            f"grid {grids.ids[d // 6]} component {d % 6 + 1} is constrained by SPC/PS and is also "
            "dependent in a rigid element.", card="SPC", card_id=grids.ids[d // 6],
            filename=model.filename, fix="constrain the rigid element's independent grid instead."))
    return fixed


def _check_finite(filename: str, *matrices: sp.spmatrix) -> None:
    """Raise when finite but huge inputs overflowed an assembled matrix."""
    if not all(np.all(np.isfinite(m.data)) for m in matrices):
        raise InputError(card_message(
            "the assembled stiffness or mass overflows (non-finite entries).", filename=filename,
            fix="check for huge values (such as 1e300) in GRID coordinates, properties, "
                "materials and masses."))


def assemble(model: FEModel, mass: str = "deck", *, warn: bool = True) -> AssembledSystem:
    """Assemble and reduce to the free (a-set) system.

    Parameters
    ----------
    model : FEModel
    mass : {'deck', 'consistent', 'lumped'}
    warn : bool, issue the singularity-table warning (one per call) when it is not empty.

    Returns
    -------
    AssembledSystem
    """
    n_g = 6 * len(model.grids)
    k_basic, m_basic = assemble_g(model, mass)
    rot = rotation_matrix(model)
    if np.any(model.grids.cd != 0):
        k_cd = (rot.T @ k_basic @ rot).tocsr()
        m_cd = (rot.T @ m_basic @ rot).tocsr()
    else:
        k_cd, m_cd = k_basic, m_basic
    m_dofs, g_mo = solve_constraints(model.grids, model.rigid, n_g, model.filename)
    fixed = _constrained(model, m_dofs)
    is_m = np.zeros(n_g, dtype=bool)
    is_m[m_dofs] = True
    n_dofs = np.flatnonzero(~is_m)
    # u_g = T_gn u_n: identity on the n-set, G on the m-set.
    t_gn = sp.csr_matrix((np.ones(len(n_dofs)), (n_dofs, np.arange(len(n_dofs)))),
                         shape=(n_g, len(n_dofs)))
    if len(m_dofs):
        g_mn = g_mo[:, n_dofs]
        t_gn = t_gn + sp.csr_matrix((np.ones(len(m_dofs)), (m_dofs, np.arange(len(m_dofs)))),
                                    shape=(n_g, len(m_dofs))) @ g_mn
        k_nn = (t_gn.T @ k_cd @ t_gn).tocsr()
    else:
        k_nn = k_cd[n_dofs][:, n_dofs]
    _check_finite(model.filename, k_nn, m_cd)
    diag = np.abs(k_nn.diagonal())
    rot_dof = (n_dofs % 6) >= 3
    scale = np.array([diag[~rot_dof].max(initial=0.0), diag[rot_dof].max(initial=0.0)])
    no_stiffness = ~fixed[n_dofs] & (diag <= 1e-12 * scale[rot_dof.astype(int)])
    table = grid_point_singularities(k_nn, n_dofs, fixed[n_dofs], model.grids.ids,
                                     epzero=model.epzero, autospc=model.autospc,
                                     floor=1e-12 * scale)
    if not model.autospc:
        forced = np.isin(table.dof, n_dofs[no_stiffness])
        table = replace(table, action=np.where(forced, "autospc", table.action))
    if warn:
        warn_singularities(table, model.filename)
    removed = no_stiffness | np.isin(n_dofs, table.constrained)
    free = ~fixed[n_dofs] & ~removed
    autospc = n_dofs[removed]
    t_ga = t_gn[:, np.flatnonzero(free)].tocsr()
    if len(m_dofs):
        k_aa = (t_ga.T @ k_cd @ t_ga).tocsc()
        m_aa = (t_ga.T @ m_cd @ t_ga).tocsc()
    else:  # T is a selection: slicing is much cheaper than two sparse products
        a_dofs = n_dofs[free]
        k_aa = k_cd[a_dofs][:, a_dofs].tocsc()
        m_aa = m_cd[a_dofs][:, a_dofs].tocsc()
    _check_finite(model.filename, k_aa, m_aa)
    if k_aa.shape[0] == 0:
        raise InputError(card_message("the model has no free degrees of freedom.",
                                      filename=model.filename,
                                      fix="check the SPC set and the element connectivity."))
    return AssembledSystem(K=k_aa, M=m_aa, T=t_ga, a_dofs=n_dofs[free], m_basic=m_basic,
                           rotation=rot, autospc=autospc, singularities=table)
