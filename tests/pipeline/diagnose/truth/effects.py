"""The truth's own effects: hidden changes to a parsed analysis deck (pyNastran BDF), richer than
any single-parameter library.

Each effect is drawn (``draw``: location and size from a numpy Generator, in the ANALYSIS deck's
ids) and then applied to a freshly parsed deck (``apply``), so that the same draw goes into every
configuration of a structure. Nuisance scatter (``scatter``) is applied before the effect.

| kind | truth (this module) |
|---|---|
| lumped_mass | 1-5 % of the total CONM2 mass, spread over 1-3 adjacent grids, each a CONM2 with the inertia of a box of random size |
| joint_flexibility | an RBE2 carrying mass on its dependent side, whose link is really six CELAS2 springs of random stiffness: either the whole RBE2 hangs on a new grid at its independent grid, or one dependent grid is detached and hangs on a new grid at its place |
| member_taper | a member (CBAR chain of one PBAR, or one CBAR) re-meshed in 4-8 segments, section size r from ``root`` (0.95-1.15) down to ``root * tip`` (tip/root 0.5-0.8), A ~ r^2, I1, I2, J ~ r^4 |
| member_curvature | the member re-meshed in 4-8 segments, its grids bowed sideways by ``bow * L * sin(pi s)`` (bow 5-15 %) in a random direction normal to it |
| boundary_stiffness | grounded CELAS2 (a bungee) at a grid in z, y, x or y and z |
| outside | a missing load path: a massless CROD brace between two grids three or more elements apart (bar grids, or the structure's ``brace_grids``) |
| outside (``panel``) | a panel whose stiffness is wrong (a disbond, damage): 1-3 shell elements sharing an edge, none at a fixed grid, E and G times 0.03-0.5 (copies of their PSHELL and MAT1), the mass unchanged |
| none | nothing |

Stiffness scales (the draw multiplies them by log-uniform factors; ``make_case`` re-draws until
the effect shifts some measured mode by a few %): a joint's springs put the mass hung on it
(CONM2s of its dependent grids; their largest moment of inertia about the joint) at a local
frequency of 3-20 x f_1 (f_1 the first elastic frequency), each spring x exp(U(-0.5, 0.5)); a
bungee from the total mass times (2 pi f_1)^2; a brace from E A of the bars at its ends.
"""
from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np

#: Line elements and rigid elements whose grids define the structure's adjacency.
_LINE = ("CBAR", "CBEAM", "CROD")


@dataclass(frozen=True)
class Effect:
    """One drawn truth effect, in the analysis deck's ids.

    ``grids``, ``elements``, ``properties``: what a correct diagnosis would name; ``size``: one
    number (kind-specific, see ``SIZE``); ``params``: everything ``apply`` needs.
    """

    kind: str
    grids: tuple = ()
    elements: tuple = ()
    properties: tuple = ()
    size: float = 0.0
    params: dict = field(default_factory=dict)


#: What ``Effect.size`` is, per kind.
SIZE = {"lumped_mass": "added mass / total mass", "joint_flexibility":
        "local joint frequency / first elastic frequency",
        "member_taper": "1 - tip / root section size", "member_curvature": "bow / member length",
        "boundary_stiffness": "sum of k / (total mass (2 pi f_1)^2)",
        "outside": "E A of the brace / E A of the stiffest bar at its ends (of the model, for a "
        "brace between grids no bar reaches); a panel's: 1 - its E / the model's",
        "none": "0"}

#: The forms of an ``outside`` effect (``draw``'s ``outside``).
OUTSIDE = ("brace", "panel")
#: Shell elements a soft panel is made of.
_SHELL = ("CQUAD4", "CTRIA3")


@dataclass(frozen=True)
class Topology:
    """Connectivity of a deck: element grids, CBAR chains, RBE2s, positions, masses."""

    element_grids: dict          # eid -> tuple of grids (line and rigid elements)
    bars: dict                   # CBAR eid -> (pid, ga, gb)
    rigid: dict                  # RBE2 eid -> (independent grid, dependent grids)
    xyz: dict                    # grid -> (3,) position
    total_mass: float            # sum of CONM2 masses (deck units, before WTMASS)
    wtmass: float                # PARAM WTMASS (1 when absent)
    size: float                  # largest extent of the grid cloud
    massive: frozenset           # grids carrying a CONM2
    grid_elements: dict          # grid -> set of the eids of ``element_grids`` holding it
    fixed: frozenset = frozenset()  # grids whose translations are all constrained

    def structural_grids(self) -> list[int]:
        """Grids referenced by a line or rigid element and free to move, sorted."""
        return sorted(set(self.grid_elements) - self.fixed)

    def adjacent(self, grid: int) -> list[int]:
        """Grids sharing an element with ``grid``, sorted."""
        return sorted({g for e in self.grid_elements.get(grid, ()) for g in self.element_grids[e]}
                      - {grid})


def topology(bdf) -> Topology:
    """The connectivity of a parsed deck."""
    eg, bars = {}, {}
    for eid, e in bdf.elements.items():
        if e.type in _LINE:
            ga, gb = (int(n) for n in e.node_ids[:2])
            eg[eid] = (ga, gb)
            if e.type != "CROD":
                bars[eid] = (int(e.pid), ga, gb)
    rigid = {}
    for eid, r in bdf.rigid_elements.items():
        if r.type == "RBE2":
            rigid[eid] = (int(r.gn), tuple(int(g) for g in r.Gmi))
            eg[eid] = (int(r.gn), *rigid[eid][1])
        elif r.type == "RBAR":
            eg[eid] = (int(r.ga), int(r.gb))
        elif r.type == "RBE3":
            eg[eid] = (int(r.refgrid), *(int(g) for gs in r.Gijs for g in gs))
    xyz = {int(n): np.asarray(bdf.nodes[n].get_position(), float) for n in bdf.nodes}
    pts = np.array(list(xyz.values()))
    conm2 = [m for m in bdf.masses.values() if m.type == "CONM2"]
    wtmass = float(bdf.params["WTMASS"].values[0]) if "WTMASS" in bdf.params else 1.0
    ge = defaultdict(set)
    for eid, gs in eg.items():
        for g in gs:
            ge[g].add(eid)
    return Topology(eg, bars, rigid, xyz, float(sum(m.mass for m in conm2)), wtmass,
                    float(np.ptp(pts, axis=0).max()), frozenset(int(m.nid) for m in conm2),
                    dict(ge), _fixed(bdf))


def draw_suspension(topo: Topology, rng: np.random.Generator, f_1: float, mass: float) -> list:
    """A test suspension of three bungees: a mirror pair (y -> -y) and a grid on the plane of
    symmetry at least 5 % of the structure's size off the pair's line (three bungees in a line
    would leave the rotation about it free), drawn among the grids elements touch and nothing
    fixes; heave at 0.1-0.3 x f_1
    (the truth's first elastic frequency, Hz) over ``mass`` (consistent units), 30-70 % of its
    stiffness on the pair, each bungee's sway (x) 10-50 % of its vertical stiffness and y within
    20 % of x. Returns [(grid, (k_x, k_y, k_z))] for :func:`hang`."""
    grids = topo.structural_grids()
    tol = 1e-6 * topo.size
    plane = [g for g in grids if abs(topo.xyz[g][1]) <= tol]
    image = {}
    for g in grids:
        x, y, z = topo.xyz[g]
        if y > tol:
            near = [h for h in grids if np.linalg.norm(topo.xyz[h] - (x, -y, z)) <= tol]
            if near:
                image[g] = near[0]
    pairs = sorted(image.items())
    if not pairs or not plane:
        raise ValueError("the structure has no mirror pair and plane grid for a suspension")
    pair = pairs[rng.integers(len(pairs))]
    centre = plane[rng.integers(len(plane))]
    for _ in range(100):             # three points on one line leave the rotation about it free
        a, b = topo.xyz[pair[0]], topo.xyz[pair[1]]
        off = np.linalg.norm(np.cross(b - a, topo.xyz[centre] - a)) / np.linalg.norm(b - a)
        if off > 0.05 * topo.size:
            break
        pair = pairs[rng.integers(len(pairs))]
        centre = plane[rng.integers(len(plane))]
    heave = mass * (2.0 * np.pi * f_1 * rng.uniform(0.1, 0.3)) ** 2
    share = rng.uniform(0.3, 0.7)
    k_z = np.array([share * heave / 2.0, (1.0 - share) * heave])
    k_x = k_z * rng.uniform(0.1, 0.5, 2)
    k = np.column_stack([k_x, k_x * rng.uniform(0.8, 1.2, 2), k_z])
    return [(int(pair[0]), tuple(k[0])), (int(pair[1]), tuple(k[0])), (int(centre), tuple(k[1]))]


def hang(bdf, springs) -> None:
    """Grounded CELAS2 in x, y and z at each grid of ``springs`` (:func:`draw_suspension`)."""
    eid = _next([*bdf.elements, *bdf.rigid_elements])
    for i, (grid, k) in enumerate(springs):
        for c in range(3):
            bdf.add_celas2(eid + 3 * i + c, float(k[c]), [grid, 0], c1=c + 1, c2=0)


def _fixed(bdf) -> frozenset:
    """Grids whose three translations GRID PS, an SPC1 or an SPC constrains (every SPC1 and SPC
    of the deck; an SPC's enforced value is 0 on the decks of the study)."""
    held = defaultdict(set)
    for nid, node in bdf.nodes.items():
        held[int(nid)].update(str(node.ps or ""))
    for cards in bdf.spcs.values():
        for spc in cards:
            if spc.type == "SPC1":
                for nid in spc.node_ids:
                    held[int(nid)].update(str(spc.components))
            elif spc.type == "SPC":
                for nid, comps in zip(spc.node_ids, spc.components):
                    held[int(nid)].update(str(comps))
    return frozenset(g for g, comps in held.items() if {"1", "2", "3"} <= comps)


def neighbours(topo: Topology, grids, elements) -> tuple[list[int], list[int]]:
    """The location grown by one element layer: (grids, elements).

    Grids: the location's grids, the grids of its elements and every grid sharing an element with
    them; elements: the location's elements and every element with a grid among the former.
    """
    core = set(grids) | {g for e in elements for g in topo.element_grids.get(e, ())}
    ge = topo.grid_elements
    els = set(elements) | {e for g in core for e in ge.get(g, ())}
    out = core | {g for e in els for g in topo.element_grids.get(e, ())}
    return sorted(out), sorted(els)


def members(topo: Topology) -> list[tuple[int, ...]]:
    """Members: for each PBAR, its CBARs when they form one open chain (in order along it), else
    each CBAR alone. Returns element-id tuples ordered along the member."""
    by_pid = defaultdict(list)
    for eid, (pid, _, _) in sorted(topo.bars.items()):
        by_pid[pid].append(eid)
    out = []
    for pid, eids in sorted(by_pid.items()):
        chain = _chain(topo, eids)
        out += [chain] if chain else [(e,) for e in eids]
    return out


def _chain(topo: Topology, eids: list[int]) -> tuple[int, ...] | None:
    """``eids`` ordered along one open path, or None when they do not form one."""
    if len(eids) == 1:
        return tuple(eids)
    deg = defaultdict(list)
    for e in eids:
        for g in topo.bars[e][1:]:
            deg[g].append(e)
    ends = [g for g, es in deg.items() if len(es) == 1]
    if len(ends) != 2 or any(len(es) > 2 for es in deg.values()):
        return None
    order, g, used = [], min(ends), set()
    while True:
        nxt = [e for e in deg[g] if e not in used]
        if not nxt:
            break
        e = nxt[0]
        used.add(e)
        order.append(e)
        ga, gb = topo.bars[e][1:]
        g = gb if g == ga else ga
    return tuple(order) if len(order) == len(eids) else None


def chain_grids(topo: Topology, chain) -> list[int]:
    """The grids along a member, in order (len(chain) + 1)."""
    ga, gb = topo.bars[chain[0]][1:]
    if len(chain) > 1 and ga in topo.bars[chain[1]][1:]:
        ga, gb = gb, ga
    out = [ga, gb]
    for e in chain[1:]:
        a, b = topo.bars[e][1:]
        out.append(b if a == out[-1] else a)
    return out


def _loguniform(rng, lo: float, hi: float) -> float:
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _hung(bdf, topo: Topology, pivot: int, grids) -> tuple[float, float]:
    """(mass, moment of inertia about ``pivot``) of the CONM2s at ``grids`` (x WTMASS): the sum
    over the masses of each one's largest moment about the pivot's axes, at least
    1e-3 x mass x size^2."""
    mass, inertia = 0.0, 0.0
    for m in bdf.masses.values():
        if m.type == "CONM2" and int(m.nid) in grids:
            r = topo.xyz[int(m.nid)] + np.asarray(m.X, float) - topo.xyz[pivot]
            own = np.asarray(m.I, float)[[0, 2, 5]]
            mass += m.mass
            inertia += float(np.max(m.mass * (r @ r - r ** 2) + own))
    floor = 1e-3 * mass * topo.size ** 2
    return mass * topo.wtmass, max(inertia, floor) * topo.wtmass


def _bar_ea(bdf, eid: int) -> float:
    """E A of a CBAR."""
    p = bdf.properties[bdf.elements[eid].pid]
    return bdf.materials[p.mid].e * p.A


def draw(kind: str, bdf, topo: Topology, rng: np.random.Generator, f1: float,
         brace_grids=None, outside: str = "brace") -> Effect:
    """Draw an effect of ``kind`` on the analysis deck ``bdf`` (its ``topology``).

    Parameters
    ----------
    kind : one of the truth kinds
    bdf : pyNastran BDF of the analysis deck (read only)
    topo : Topology of ``bdf``
    rng : numpy Generator
    f1 : first elastic frequency of the truth without the effect [Hz] (bungee scale)
    brace_grids : sequence of int, optional
        The grids an ``outside`` brace may join (default: the CBARs' grids; a stick model's bar
        grids lie on one line, where a massless brace changes no bending or torsion mode).
    outside : one of ``OUTSIDE``, the form of an ``outside`` effect: a missing load path
        (``brace``) or a soft panel of a shell structure (``panel``).
    """
    if outside not in OUTSIDE:
        raise ValueError(f"outside {outside!r}; valid: {', '.join(OUTSIDE)}")
    grids = topo.structural_grids()
    if kind == "none":
        return Effect("none")
    if kind == "lumped_mass":
        chain = [int(rng.choice(grids))]
        for _ in range(int(rng.integers(0, 3))):
            nxt = [g for g in topo.adjacent(chain[-1]) if g not in chain]
            if nxt:
                chain.append(int(rng.choice(nxt)))
        frac = float(rng.uniform(0.01, 0.05))
        share = rng.dirichlet(np.ones(len(chain)))
        side = rng.uniform(0.01, 0.05, (len(chain), 3)) * topo.size
        masses = [(g, frac * topo.total_mass * s, tuple(float(v) for v in d))
                  for g, s, d in zip(chain, share, side)]
        return Effect(kind, grids=tuple(sorted(chain)), size=frac, params={"masses": masses})
    if kind == "joint_flexibility":
        eid = int(rng.choice([r for r, (_, dep) in sorted(topo.rigid.items())
                              if any(g in topo.massive for g in dep)]))
        gn, dep = topo.rigid[eid]
        detach = None if len(dep) == 1 or rng.random() < 0.5 else int(rng.choice(dep))
        mass, inertia = _hung(bdf, topo, gn, dep if detach is None else (detach,))
        ratio = _loguniform(rng, 3.0, 20.0)
        omega2 = (2.0 * math.pi * ratio * f1) ** 2
        jitter = np.exp(rng.uniform(-0.5, 0.5, 6))
        k = [mass * omega2 * j for j in jitter[:3]] + [inertia * omega2 * j for j in jitter[3:]]
        return Effect(kind, grids=tuple(sorted((gn, *dep))), elements=(eid,), size=ratio,
                      params={"rbe2": eid, "k": k, "detach": detach})
    if kind in ("member_taper", "member_curvature"):
        mem = members(topo)
        chain = mem[int(rng.integers(len(mem)))]
        path = chain_grids(topo, chain)
        nseg = int(rng.integers(4, 9))
        common = {"chain": chain, "path": path, "nseg": nseg}
        pids = tuple(sorted({topo.bars[e][0] for e in chain}))
        if kind == "member_taper":
            tip = float(rng.uniform(0.5, 0.8))
            common.update(root=float(rng.uniform(0.95, 1.15)), tip=tip,
                          reverse=bool(rng.random() < 0.5))
            return Effect(kind, grids=tuple(path), elements=chain, properties=pids,
                          size=1.0 - tip, params=common)
        axis = topo.xyz[path[-1]] - topo.xyz[path[0]]
        axis /= np.linalg.norm(axis)
        helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
        n1 = np.cross(axis, helper)
        n1 /= np.linalg.norm(n1)
        n2 = np.cross(axis, n1)
        phi = rng.uniform(0.0, 2.0 * math.pi)
        bow = float(rng.uniform(0.05, 0.15))
        common.update(bow=bow, direction=tuple(math.cos(phi) * n1 + math.sin(phi) * n2))
        return Effect(kind, grids=tuple(path), elements=chain, properties=pids, size=bow,
                      params=common)
    if kind == "boundary_stiffness":
        g = int(rng.choice(grids))
        dirs = [(3,), (2,), (1,), (2, 3)][int(rng.integers(4))]
        scale = topo.total_mass * topo.wtmass * (2.0 * math.pi * f1) ** 2
        fr = [_loguniform(rng, 0.05, 1.0) for _ in dirs]
        return Effect(kind, grids=(g,), size=float(sum(fr)),
                      params={"grid": g, "springs": [(c, f * scale) for c, f in zip(dirs, fr)]})
    if kind == "outside" and outside == "panel":
        return _draw_panel(bdf, topo, rng)
    if kind == "outside":
        ends = sorted({g for e in topo.bars for g in topo.bars[e][1:]} if brace_grids is None
                      else brace_grids)
        far = _graph_distance(topo, ends)
        pairs = [(a, b) for a in ends for b in ends if a < b and far[(a, b)] >= 3
                 and np.linalg.norm(topo.xyz[a] - topo.xyz[b]) <= 0.25 * topo.size]
        a, b = pairs[int(rng.integers(len(pairs)))]
        near = topo.bars if brace_grids is not None else \
            [e for g in (a, b) for e in topo.grid_elements[g] if e in topo.bars]
        ea = max(_bar_ea(bdf, e) for e in near)
        frac = _loguniform(rng, 0.05, 1.0)
        return Effect(kind, grids=(a, b), size=frac, params={"ends": (a, b), "EA": frac * ea})
    raise ValueError(f"unknown truth kind {kind!r}")


def _draw_panel(bdf, topo: Topology, rng: np.random.Generator) -> Effect:
    """A soft panel (module table): a shell element at no fixed grid, grown by up to two more
    sharing an edge (two grids) with it, their stiffness times 0.03-0.5 (log-uniform)."""
    shells = {int(e): frozenset(int(g) for g in el.node_ids)
              for e, el in sorted(bdf.elements.items())
              if el.type in _SHELL and not set(el.node_ids) & topo.fixed}
    if not shells:
        raise ValueError("a soft panel needs shell elements away from the fixed grids")
    patch = [int(rng.choice(sorted(shells)))]
    for _ in range(int(rng.integers(0, 3))):
        grids = set().union(*(shells[e] for e in patch))
        edge = [e for e in shells if e not in patch and len(shells[e] & grids) >= 2]
        if edge:
            patch.append(int(rng.choice(edge)))
    factor = _loguniform(rng, 0.03, 0.5)
    grids = tuple(sorted(set().union(*(shells[e] for e in patch))))
    pids = tuple(sorted({int(bdf.elements[e].pid) for e in patch}))
    return Effect("outside", grids=grids, elements=tuple(sorted(patch)), properties=pids,
                  size=1.0 - factor, params={"panel": sorted(patch), "factor": factor})


def _graph_distance(topo: Topology, grids: list[int]) -> dict:
    """Element-hop distance between every pair of ``grids`` (breadth-first, capped at 3)."""
    out = {}
    for a in grids:
        seen, front = {a: 0}, [a]
        for d in (1, 2):
            front = [n for g in front for n in topo.adjacent(g) if n not in seen]
            for n in front:
                seen.setdefault(n, d)
        for b in grids:
            out[(a, b)] = seen.get(b, 3)
    return out


def scatter(bdf, rng: np.random.Generator, pbar: float = 0.03, conm2: float = 0.02,
            young: float = 0.01) -> None:
    """Nuisance scatter in place: every PBAR's A, I1, I2, J, every CONM2's mass and inertia and
    every MAT1's E (and G) times 1 + sigma N(0, 1), the normal draw clipped at +-2 (ids sorted,
    so every configuration of a structure gets the same factor for the same card)."""
    for pid in sorted(bdf.properties):
        p = bdf.properties[pid]
        if p.type == "PBAR":
            f = 1.0 + pbar * np.clip(rng.standard_normal(4), -2.0, 2.0)
            p.A, p.i1, p.i2, p.j = p.A * f[0], p.i1 * f[1], p.i2 * f[2], p.j * f[3]
    for eid in sorted(bdf.masses):
        m = bdf.masses[eid]
        if m.type == "CONM2":
            f = 1.0 + conm2 * np.clip(rng.standard_normal(), -2.0, 2.0)
            m.mass *= f
            m.I = np.asarray(m.I, float) * f
    for mid in sorted(bdf.materials):
        mat = bdf.materials[mid]
        if mat.type == "MAT1":
            f = 1.0 + young * np.clip(rng.standard_normal(), -2.0, 2.0)
            mat.e *= f
            mat.g *= f


def _next(ids) -> int:
    return (max(ids, default=0) // 1000 + 1) * 1000 + 1


def apply(bdf, effect: Effect) -> None:
    """Apply ``effect`` to a parsed deck in place (new ids above every existing one)."""
    kind, p = effect.kind, effect.params
    if kind == "none":
        return
    if kind == "lumped_mass":
        eid = _next(bdf.masses)
        for i, (g, m, (a, b, c)) in enumerate(p["masses"]):
            inertia = [m * (b * b + c * c) / 12, 0.0, m * (a * a + c * c) / 12, 0.0, 0.0,
                       m * (a * a + b * b) / 12]
            bdf.add_conm2(eid + i, g, m, I=inertia)
    elif kind == "joint_flexibility":
        _spring_joint(bdf, p["rbe2"], p["k"], p["detach"])
    elif kind in ("member_taper", "member_curvature"):
        _remesh(bdf, effect)
    elif kind == "boundary_stiffness":
        eid = _next([*bdf.elements, *bdf.rigid_elements])
        for i, (c, k) in enumerate(p["springs"]):
            bdf.add_celas2(eid + i, k, [p["grid"], 0], c1=c, c2=0)
    elif kind == "outside" and "panel" in p:
        _soften(bdf, p["panel"], p["factor"])
    elif kind == "outside":
        pid, eid = _next(bdf.properties), _next([*bdf.elements, *bdf.rigid_elements])
        mat, mid = bdf.materials[min(bdf.materials)], _next(bdf.materials)
        bdf.add_mat1(mid, mat.e, mat.g, mat.nu, rho=0.0)       # a brace without mass
        bdf.add_prod(pid, mid, p["EA"] / mat.e)
        bdf.add_crod(eid, pid, list(p["ends"]))
    else:
        raise ValueError(f"unknown truth kind {kind!r}")


def _soften(bdf, panel, factor: float) -> None:
    """The shell elements ``panel`` on copies of their PSHELL and its MAT1s with E and G times
    ``factor`` (rho, nu and the thickness kept: the mass unchanged)."""
    pid, mid = _next(bdf.properties), _next(bdf.materials)
    copies = {}
    for eid in panel:
        el = bdf.elements[eid]
        if el.pid not in copies:
            old = bdf.properties[el.pid]
            mids = {}
            for name in ("mid1", "mid2", "mid3", "mid4"):
                m = getattr(old, name)
                if m and m not in mids:
                    mat = bdf.materials[m]
                    bdf.add_mat1(mid, mat.e * factor, mat.g * factor, mat.nu, rho=mat.rho)
                    mids[m], mid = mid, mid + 1
            bdf.add_pshell(pid, mid1=mids.get(old.mid1), t=old.t, mid2=mids.get(old.mid2),
                           twelveIt3=old.twelveIt3, mid3=mids.get(old.mid3), tst=old.tst,
                           nsm=old.nsm, z1=old.z1, z2=old.z2, mid4=mids.get(old.mid4))
            copies[el.pid], pid = pid, pid + 1
        el.pid = copies[el.pid]


def _spring_joint(bdf, rid: int, k, detach) -> None:
    """Six CELAS2 between a grid and a new coincident grid that takes its place in the RBE2."""
    rbe = bdf.rigid_elements[rid]
    new = _next(bdf.nodes)
    old = int(rbe.gn) if detach is None else int(detach)
    bdf.add_grid(new, list(bdf.nodes[old].get_position()))
    bdf.nodes[new].cross_reference(bdf)
    if detach is None:
        rbe.gn = new
    else:
        rbe.Gmi = [new if int(g) == old else int(g) for g in rbe.Gmi]
    eid = _next([*bdf.elements, *bdf.rigid_elements])
    for c in range(6):
        bdf.add_celas2(eid + c, float(k[c]), [old, new], c1=c + 1, c2=c + 1)


def _remesh(bdf, effect: Effect) -> None:
    """A member re-meshed in ``nseg`` segments: tapered sections or bowed grids."""
    p = effect.params
    path, chain = p["path"], p["chain"]
    xyz = np.array([bdf.nodes[g].get_position() for g in path], float)
    seg = np.linalg.norm(np.diff(xyz, axis=0), axis=1)
    total = float(seg.sum())
    per = max(1, math.ceil(p["nseg"] / len(chain)))
    new_grid, new_eid = _next(bdf.nodes), _next([*bdf.elements, *bdf.rigid_elements])
    new_pid = _next(bdf.properties)
    s0 = np.concatenate([[0.0], np.cumsum(seg)]) / total
    bow = np.zeros(3) if effect.kind == "member_taper" else \
        p["bow"] * total * np.asarray(p["direction"])
    for g, s in zip(path[1:-1], s0[1:-1]):
        bdf.nodes[g].xyz = np.asarray(bdf.nodes[g].xyz, float) + bow * math.sin(math.pi * s)
    for k, eid in enumerate(chain):
        bar = bdf.elements.pop(eid)
        ends = [path[k], path[k + 1]]
        grids = [ends[0]]
        for j in range(1, per):
            t = j / per
            s = s0[k] + t * (s0[k + 1] - s0[k])
            pos = (1 - t) * xyz[k] + t * xyz[k + 1] + bow * math.sin(math.pi * s)
            bdf.add_grid(new_grid, list(pos))
            bdf.nodes[new_grid].cross_reference(bdf)
            grids.append(new_grid)
            new_grid += 1
        grids.append(ends[1])
        x = None if bar.x is None else list(bar.x)
        for j, (a, b) in enumerate(zip(grids[:-1], grids[1:])):
            pid = bar.pid
            if effect.kind == "member_taper":
                s = s0[k] + (j + 0.5) / per * (s0[k + 1] - s0[k])
                s = 1.0 - s if p["reverse"] else s
                r = p["root"] * (1.0 + (p["tip"] - 1.0) * s)
                old = bdf.properties[bar.pid]
                bdf.add_pbar(new_pid, old.mid, A=old.A * r ** 2, i1=old.i1 * r ** 4,
                             i2=old.i2 * r ** 4, j=old.j * r ** 4, nsm=old.nsm)
                pid, new_pid = new_pid, new_pid + 1
            bdf.add_cbar(new_eid, pid, [a, b], x, bar.g0)
            new_eid += 1
