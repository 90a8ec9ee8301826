"""Primary and secondary modes from flutter participation (Pak & Truong, sec. IV.B and Table 6).

The paper picks the modes to tune from the modal participation factors of its flutter roots: the
modes "together with rigid body modes" whose participation reaches 89-96.5 % of every flutter mode at
every Mach are the *primary* modes; modes added to reach 93-99 % are the next ones. Here, per
configuration and with P_pj the participation [%] of mode j in critical root p (participation.nc,
:mod:`flutter.participation`; it sums to 100 over j):

- critical roots: the points whose ``flutter_mode`` (1st, 2nd, ... crossing of its sweep) is at
  most ``flutter_modes``, at every Mach and density of the configuration;
- primary modes: the smallest set S of flexible modes with, for every critical root p,
  ``sum_{j rigid} P_pj + sum_{j in S} P_pj >= 100 * primary``;
- secondary modes: the smallest set T of the remaining flexible modes with
  ``rigid + S + T >= 100 * secondary`` for every critical root.

"Smallest" is exact (:func:`smallest_cover`): sets are searched by increasing size k among the
candidate modes (those with a positive share in some critical root: a mode that adds nothing to any
root is never needed), exhaustively by branch and bound -- a partial set is dropped as soon as its
total plus the k - |set| largest shares still available falls short for some root, which loses no
set that works. Among the sets of the smallest size that reach the threshold, the one with the
largest minimum total over the roots wins (then the lowest mode ids). The search is bounded: past
``MAX_NODES`` partial sets (working arrays of at most 8 bytes x MAX_NODES x roots: 40 MB at 10
roots; realistic cases, where the roots share their dominant modes, stay far below) the max-min
greedy rule decides instead: add the mode that raises the smallest root total most (the lowest
mode id on a tie) until every root reaches the threshold. The ``search`` variable of the result
says which rule chose each configuration's modes. A total within ``TOLERANCE`` (1e-6 %) below a
threshold reaches it, so that floating-point rounding of shares that sum to exactly the threshold
does not add a mode.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from structures.common.errors import InputError, card_message
from structures.units import system_of, unit_labels

TOLERANCE = 1e-6          # [%] a total this close below a threshold reaches it
SUM_TOLERANCE = 1e-6      # [%] participation of a point must sum to 100 within this
MAX_NODES = 500_000       # exact search bound: partial sets per cover before the greedy rule
_POINT_COORDS = ("case", "mach", "density", "velocity", "frequency", "root", "flutter_mode")


def check_thresholds(primary: float, secondary: float) -> None:
    """Raise :class:`InputError` unless ``0 < primary <= secondary <= 1`` (fractions, not %)."""
    for key, value in (("primary", primary), ("secondary", secondary)):
        if not 0.0 < value <= 1.0:
            raise InputError(card_message(
                f"threshold {key} = {value} is not a fraction in (0, 1].", card="[selection]",
                card_id=key, fix=f"give {key} as a fraction, e.g. {key} = "
                                 f"{0.9 if key == 'primary' else 0.98} (not a percentage)."))
    if primary > secondary:
        raise InputError(card_message(
            f"threshold primary = {primary} exceeds secondary = {secondary}.", card="[selection]",
            card_id="secondary", fix="make secondary >= primary, e.g. primary = 0.9, "
                                     "secondary = 0.98."))


def _greedy(shares: np.ndarray, cand: np.ndarray, base: np.ndarray, need: float) -> np.ndarray:
    """Max-min greedy over the columns ``cand``: add the column that raises the smallest row total
    most (the lowest column index on a tie) until every row reaches ``need``; sorted indices."""
    cand = np.sort(cand)
    shares = shares[:, cand]
    total = base.copy()
    chosen = []
    free = np.ones(shares.shape[1], dtype=bool)
    while np.any(total < need) and free.any():
        gain = np.where(free, (total[:, None] + shares).min(axis=0), -np.inf)
        j = int(np.argmax(gain))
        chosen.append(j)
        free[j] = False
        total = total + shares[:, j]
    return cand[np.sort(np.array(chosen, dtype=int))]


def _suffix_bounds(pos: np.ndarray) -> np.ndarray:
    """``U[l, r, p]``: the largest total r columns from ``l`` on can add to row p (its r largest
    shares among columns l, l+1, ...); shape (n + 1, n + 1, n_points), -inf where r > n - l."""
    n_pts, n = pos.shape
    U = np.full((n + 1, n + 1, n_pts), -np.inf)
    for l in range(n + 1):
        top = -np.sort(-pos[:, l:], axis=1)
        U[l, :n - l + 1] = np.concatenate([np.zeros((n_pts, 1)), np.cumsum(top, axis=1)], axis=1).T
    return U


def _covers_of_size(A: np.ndarray, U: np.ndarray, base: np.ndarray, need: float, k: int,
                    budget: int):
    """Every k-set of columns reaching ``need`` in every row, grown one column at a time in
    increasing column order; a partial set is dropped as soon as its total plus the best
    completion from the columns after its last one (``U``) falls short in some row.

    Returns (sets (m, k), totals (n_points, m), nodes used), or None past ``budget`` nodes."""
    n = A.shape[1]
    sets, totals, nodes = np.zeros((1, 0), dtype=int), base[:, None], 0
    for d in range(k):
        r = k - d - 1                                         # columns still to add after this one
        first = sets[:, -1] + 1 if d else np.zeros(1, dtype=int)
        count = np.maximum(n - r - first, 0)                  # next column j in [first, n - r - 1]
        nodes += int(count.sum())
        if nodes > budget:
            return None
        parent = np.repeat(np.arange(len(sets)), count)
        j = first[parent] + np.arange(parent.size) - np.repeat(np.cumsum(count) - count, count)
        new = totals[:, parent] + A[:, j]
        keep = np.all(new + U[j + 1, r].T >= need, axis=0)
        sets = np.concatenate([sets[parent[keep]], j[keep, None]], axis=1)
        totals = new[:, keep]
    return sets, totals, nodes


def smallest_cover(shares: np.ndarray, base: np.ndarray, target: float, *,
                   max_nodes: int = MAX_NODES) -> tuple[np.ndarray, bool]:
    """Smallest set of columns whose shares, added to ``base``, reach ``target`` in every row.

    Sizes k = 1, 2, ... are searched exhaustively (branch and bound, :func:`_covers_of_size`, over
    the candidate columns: those with a positive share in some row); the first size with a set
    that works is the answer, and among its sets the one with the largest smallest row total wins
    (ties within 1e-9 %: the lowest column indices).

    Parameters
    ----------
    shares : ndarray, shape (n_points, n_modes)
        Participation [%] of each candidate mode in each critical root.
    base : ndarray, shape (n_points,)
        Participation already counted (rigid-body modes, and the primary modes for the secondary
        search) [%].
    target : float
        Threshold [%] every row must reach (within ``TOLERANCE``).
    max_nodes : int
        Bound of the exact search: partial sets generated over all sizes; past it the max-min
        greedy rule decides.

    Returns
    -------
    columns : ndarray, shape (k,)
        Sorted column indices of the chosen set (empty when ``base`` already reaches the target).
    exact : bool
        True when the exact search decided (False: greedy fallback, see module docstring).
    """
    shares = np.asarray(shares, dtype=float)
    base = np.asarray(base, dtype=float)
    need = target - TOLERANCE
    if np.all(base >= need):
        return np.zeros(0, dtype=int), True
    cand = np.flatnonzero((shares > 0).any(axis=0))
    # large shares first: partial sets that skip them fail the bound early
    cand = cand[np.argsort(-np.clip(shares[:, cand], 0.0, None).sum(axis=0), kind="stable")]
    A = shares[:, cand]
    U = _suffix_bounds(np.clip(A, 0.0, None))
    budget = max_nodes
    for k in range(1, len(cand) + 1):
        if np.any(base + U[0, k] < need):
            continue
        found = _covers_of_size(A, U, base, need, k, budget)
        if found is None:
            return _greedy(shares, cand, base, need), False
        sets, totals, nodes = found
        budget -= nodes
        if len(sets):
            ids = np.sort(cand[sets], axis=1)
            worst = np.round(totals.min(axis=0), 9)
            best = np.lexsort((*ids.T[::-1], -worst))[0]
            return ids[best], True
    return _greedy(shares, cand, base, need), False  # unreachable for shares summing to 100


def _source(name: str, ds) -> str:
    source = ds.encoding.get("source") if isinstance(ds, xr.Dataset) else None
    return str(source or f"participation.nc of configuration {name!r}")


def _check_participation(name: str, ds: xr.Dataset) -> None:
    """The participation.nc contract (pipeline.chain) and sums of 100 % per point."""
    fix = "pass the participation Dataset written by pipeline.chain.flutter_chain."
    if not isinstance(ds, xr.Dataset) or "participation" not in ds:
        raise InputError(card_message("no 'participation' variable.", filename=_source(name, ds),
                                      fix=fix))
    missing = [c for c in ("rigid", "fe_frequency", *_POINT_COORDS) if c not in ds.coords]
    if ds["participation"].dims != ("flutter_point", "mode") or missing:
        raise InputError(card_message(
            f"participation has dims {ds['participation'].dims} and lacks coordinates {missing}; "
            "expected participation(flutter_point, mode) with the contract's coordinates.",
            filename=_source(name, ds), fix=fix))
    P = ds["participation"].values
    bad = np.flatnonzero(~np.isfinite(P).all(axis=1) | (np.abs(P.sum(axis=1) - 100.0) > SUM_TOLERANCE))
    if bad.size:
        p = int(bad[0])
        raise InputError(card_message(
            f"the participation of flutter point {p} (Mach {float(ds['mach'][p]):.4g}, flutter mode "
            f"{int(ds['flutter_mode'][p])}) sums to {P[p].sum():.6g} %, not 100 %.",
            filename=_source(name, ds), card_id=p, fix=fix))


def _units(participation: dict) -> str | None:
    systems = {system_of(ds.attrs) for ds in participation.values()}
    if len(systems) > 1:
        raise InputError(card_message(
            "the configurations' participation is in different unit systems "
            f"{sorted(map(str, systems))}.",
            card="units", fix="run every configuration of one case with the case's units."))
    return systems.pop()


def _check_inputs(participation: dict, flutter_modes: int) -> str | None:
    """Check the participation Datasets and ``flutter_modes``; return their unit system."""
    if int(flutter_modes) < 1:
        raise InputError(card_message(f"flutter_modes = {flutter_modes} must be >= 1.",
                                      card="[selection]", card_id="flutter_modes",
                                      fix="e.g. flutter_modes = 2."))
    if not participation:
        raise InputError(card_message("no configuration given.", card="participation",
                                      fix="pass {configuration: participation Dataset}."))
    for name, ds in participation.items():
        _check_participation(name, ds)
    return _units(participation)


def _critical(ds: xr.Dataset, flutter_modes: int) -> np.ndarray:
    return ds["flutter_mode"].values <= flutter_modes


def _select_one(ds: xr.Dataset, primary: float, secondary: float, flutter_modes: int):
    """Roles of one configuration's modes, shape (n_modes,), and the search rule used."""
    rigid = ds["rigid"].values.astype(bool)
    roles = np.where(rigid, "rigid", "").astype("<U9")
    crit = _critical(ds, flutter_modes)
    if not crit.any():
        return roles, "no critical roots"
    P = ds["participation"].values[crit]
    flex = np.flatnonzero(~rigid)
    base = P[:, rigid].sum(axis=1)
    S, exact_s = smallest_cover(P[:, flex], base, 100.0 * primary)
    roles[flex[S]] = "primary"
    rest = np.setdiff1d(flex, flex[S])
    T, exact_t = smallest_cover(P[:, rest], base + P[:, flex[S]].sum(axis=1), 100.0 * secondary)
    roles[rest[T]] = "secondary"
    return roles, "exact" if exact_s and exact_t else "greedy"


def _point_coords(participation: dict, mask_of, labels) -> dict:
    """flutter_point coordinates of the points ``mask_of(ds)`` of every configuration, concatenated,
    with the units of ``labels`` (structures.units.UnitLabels)."""
    names, keep = [], {}
    for name, ds in participation.items():
        keep[name] = mask_of(ds)
        names += [name] * int(keep[name].sum())
    coords = {"point_configuration": ("flutter_point", np.array(names, dtype=str))}
    for c in _POINT_COORDS:
        values = [ds[c].values[keep[n]] for n, ds in participation.items()]
        attrs = next(iter(participation.values()))[c].attrs
        coords[c] = ("flutter_point", np.concatenate(values), dict(attrs))
    for c, unit in (("velocity", labels.velocity), ("density", labels.density), ("frequency", "Hz")):
        coords[c][2]["units"] = unit
    return coords


def select_modes(participation: dict[str, xr.Dataset], *, primary: float = 0.9,
                 secondary: float = 0.98, flutter_modes: int = 2,
                 pairing: dict[str, dict[int, int]] | None = None) -> xr.Dataset:
    """Primary and secondary modes of every configuration (selection.nc; module docstring).

    Parameters
    ----------
    participation : dict of str -> xarray.Dataset
        Configuration name -> its participation.nc Dataset: ``participation(flutter_point, mode)``
        [%] with coordinates ``rigid(mode)``, ``fe_frequency(mode)`` [Hz] and ``case``, ``mach``,
        ``density``, ``velocity``, ``frequency`` [Hz], ``root``, ``flutter_mode`` on flutter_point.
    primary, secondary : float
        Thresholds as fractions, ``0 < primary <= secondary <= 1``.
    flutter_modes : int
        Critical roots: the points with ``flutter_mode <= flutter_modes``.
    pairing : dict of str -> dict of int -> int, optional
        Configuration -> {FE mode: paired GVT test mode} (correlation.nc ``paired_fe_mode``).

    Returns
    -------
    xarray.Dataset
        Dims ``configuration``, ``mode`` (union of the configurations' mode ids), ``flutter_point``
        (every point of every configuration, concatenated): ``role(configuration, mode)`` ("rigid",
        "primary", "secondary" or ""), ``test_mode(configuration, mode)`` (0: unpaired),
        ``fe_frequency(configuration, mode)`` [Hz] (NaN: no such mode), ``participation(flutter_point,
        mode)`` [%], ``primary_total`` / ``secondary_total(flutter_point)`` [%] (rigid + selected),
        ``search(configuration)`` ("exact", "greedy", "no critical roots") and
        ``critical_roots(configuration)``; flutter_point coordinates ``point_configuration`` (the
        name ``configuration`` is the dimension), ``case``, ``mach``, ``density``, ``velocity``,
        ``frequency`` [Hz], ``root``, ``flutter_mode``, ``critical``.
    """
    check_thresholds(primary, secondary)
    units = _check_inputs(participation, flutter_modes)
    pairing = pairing or {}
    unknown = sorted(set(pairing) - set(participation))
    if unknown:
        raise InputError(card_message(f"pairing names configurations {unknown} without participation.",
                                      card="pairing", fix=f"use names among {list(participation)}."))
    configs = list(participation)
    modes = np.unique(np.concatenate([ds["mode"].values for ds in participation.values()])).astype(int)
    shape = (len(configs), len(modes))
    role = np.full(shape, "", dtype="<U9")
    test = np.zeros(shape, dtype=int)
    fe_f = np.full(shape, np.nan)
    motion = np.full(shape, "", dtype="<U12")
    search, n_crit, P_rows, prim_tot, sec_tot = [], [], [], [], []
    for c, (name, ds) in enumerate(participation.items()):
        col = np.searchsorted(modes, ds["mode"].values)
        roles, rule = _select_one(ds, primary, secondary, flutter_modes)
        role[c, col], fe_f[c, col] = roles, ds["fe_frequency"].values
        if "rigid_motion" in ds.coords:
            motion[c, col] = ds["rigid_motion"].values.astype(str)
        for fe_mode, test_mode in pairing.get(name, {}).items():
            if int(fe_mode) not in ds["mode"].values:
                raise InputError(card_message(
                    f"pairing of configuration {name!r} names FE mode {fe_mode}, which it does not "
                    "have.", card="pairing", card_id=fe_mode,
                    fix=f"pair FE modes among {[int(m) for m in ds['mode'].values]}."))
            test[c, np.searchsorted(modes, int(fe_mode))] = int(test_mode)
        search.append(rule)
        n_crit.append(int(_critical(ds, flutter_modes).sum()))
        P = np.full((ds.sizes["flutter_point"], len(modes)), np.nan)
        P[:, col] = ds["participation"].values
        P_rows.append(P)
        rows = ds["participation"].values
        prim_tot.append(rows[:, np.isin(roles, ("rigid", "primary"))].sum(axis=1))
        sec_tot.append(rows[:, roles != ""].sum(axis=1))
    labels = unit_labels(units)
    coords = _point_coords(participation, lambda ds: np.ones(ds.sizes["flutter_point"], bool), labels)
    coords["critical"] = ("flutter_point", np.concatenate(
        [_critical(ds, flutter_modes) for ds in participation.values()]))
    pct = {"units": "%"}
    out = xr.Dataset(
        {"role": (("configuration", "mode"), role, {"values": "rigid | primary | secondary | ''"}),
         "test_mode": (("configuration", "mode"), test, {"description": "paired GVT mode, 0: none"}),
         "fe_frequency": (("configuration", "mode"), fe_f, {"units": "Hz"}),
         "rigid_motion": (("configuration", "mode"), motion,
                          {"description": "rigid-body motion (plunge, pitch, ...), '' if none"}),
         "participation": (("flutter_point", "mode"), np.concatenate(P_rows), pct),
         "primary_total": ("flutter_point", np.concatenate(prim_tot), pct),
         "secondary_total": ("flutter_point", np.concatenate(sec_tot), pct),
         "search": ("configuration", np.array(search, dtype=str)),
         "critical_roots": ("configuration", np.array(n_crit, dtype=int))},
        coords={"configuration": configs, "mode": modes,
                "flutter_point": np.arange(sum(len(p) for p in P_rows)), **coords})
    without = [n for n, k in zip(configs, n_crit) if k == 0]
    out.attrs.update(
        primary_threshold=float(primary), secondary_threshold=float(secondary),
        flutter_modes=int(flutter_modes), units=labels.system, tolerance_percent=TOLERANCE,
        max_nodes=MAX_NODES,
        without_critical_roots=", ".join(without),
        note=("configurations without critical flutter roots have no primary or secondary modes: "
              + ", ".join(without)) if without else "every configuration has critical flutter roots")
    return out


def ordinal(n: int) -> str:
    """1st, 2nd, 3rd, 4th, ..., 11th, 12th, 13th, ..., 21st (the paper's flutter-mode names)."""
    return f"{n}{'th' if 10 <= n % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(n % 10, 'th')}"


def point_labels(ds: xr.Dataset) -> list[str]:
    """Labels "EFEW M=0.200 1st" of the flutter points of a selection or study Dataset (the density
    is added where two points would otherwise read the same)."""
    base = [f"{c} M={float(m):.3f} {ordinal(int(f))}" for c, m, f in
            zip(ds["point_configuration"].values, ds["mach"].values, ds["flutter_mode"].values)]
    return [f"{b} rho={float(r):.4g}" if base.count(b) > 1 else b
            for b, r in zip(base, ds["density"].values)]


def _mode_rows(modes: np.ndarray, cfg: xr.Dataset, sub: xr.Dataset, role: str) -> list[str]:
    """Table rows of one configuration's modes of one role: id, f_FE, GVT mode, role, shares."""
    rows = []
    keep = np.isfinite(cfg["fe_frequency"].values) & (cfg["role"].values == role)
    for j in np.flatnonzero(keep):
        tm = int(cfg["test_mode"].values[j])
        rows.append(f"{int(modes[j]):5d} {float(cfg['fe_frequency'].values[j]):10.4g} "
                    f"{str(tm) if tm else '-':>5s}  {role or '-':<9s}"
                    + "".join(f"{v:11.1f}" for v in sub["participation"].values[:, j]))
    return rows


def selection_table(selection: xr.Dataset) -> str:
    """Participation of the critical roots and the selected modes, in the paper's Table 6 layout.

    One block per configuration: modes as rows (FE mode, in-vacuo frequency [Hz], paired GVT mode,
    role), one column per critical root (Mach x flutter mode, with its speed and frequency); rigid
    and primary modes first (the rigid-body modes named by their motion, "1 plunge, 2 pitch", when
    the participation has ``rigid_motion``), then "Total" (rigid + primary), the secondary modes,
    "Total" (rigid + primary + secondary) and the remaining modes.

    Parameters
    ----------
    selection : xarray.Dataset
        From :func:`select_modes`.

    Returns
    -------
    str
    """
    labels = unit_labels(system_of(selection.attrs))
    head = (f"Modal participation factors [%] of the critical flutter roots (first "
            f"{selection.attrs['flutter_modes']} flutter modes of every sweep); primary threshold "
            f"{100 * selection.attrs['primary_threshold']:g} %, secondary "
            f"{100 * selection.attrs['secondary_threshold']:g} %, both with the rigid-body modes.")
    blocks = [head]
    for name in selection["configuration"].values:
        cfg = selection.sel(configuration=name)
        pts = np.flatnonzero((selection["point_configuration"].values == name)
                             & selection["critical"].values)
        if pts.size == 0:
            blocks.append(f"configuration {name}: no critical flutter roots (no flutter crossing), "
                          "so no primary or secondary modes.")
            continue
        sub = selection.isel(flutter_point=pts)
        rows = [f"configuration {name} (search: {str(cfg['search'].values)})",
                f"{'':33s}" + "".join(f"{'M=' + format(float(m), '.3f'):>11s}"
                                      for m in sub["mach"].values),
                f"{'':33s}" + "".join(f"{ordinal(int(f)):>11s}" for f in sub["flutter_mode"].values),
                f"{'V [' + labels.velocity + ']':>33s}" + "".join(f"{float(v):11.4g}"
                                                                  for v in sub["velocity"].values),
                f"{'rho [' + labels.density + ']':>33s}" + "".join(f"{float(r):11.4g}"
                                                                    for r in sub["density"].values),
                f"{'f [Hz]':>33s}" + "".join(f"{float(f):11.4g}" for f in sub["frequency"].values),
                f"{'mode':>5s} {'f_FE [Hz]':>10s} {'GVT':>5s}  {'role':<9s}"]
        rows += _mode_rows(selection["mode"].values, cfg, sub, "rigid")
        motions = cfg["rigid_motion"].values if "rigid_motion" in cfg else ()
        named = [f"{int(m)} {n}" for m, n in zip(selection["mode"].values, motions) if str(n)]
        if named:
            rows.append(f"{'':5s} rigid-body modes: {', '.join(named)}")
        rows += _mode_rows(selection["mode"].values, cfg, sub, "primary")
        rows.append(f"{'Total (rigid + primary)':<33s}"
                    + "".join(f"{v:11.1f}" for v in sub["primary_total"].values))
        rows += _mode_rows(selection["mode"].values, cfg, sub, "secondary")
        rows.append(f"{'Total (+ secondary)':<33s}"
                    + "".join(f"{v:11.1f}" for v in sub["secondary_total"].values))
        rows += _mode_rows(selection["mode"].values, cfg, sub, "")
        blocks.append("\n".join(rows))
    return "\n\n".join(blocks)


def _single_root_counts(P: np.ndarray, rigid: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """Flexible modes each root needs alone: shape (n_targets, n_points). For one root the k largest
    shares give the largest k-mode total, so taking them in decreasing order is exact."""
    flex = np.clip(P[:, ~rigid], 0.0, None)
    totals = P[:, rigid].sum(axis=1)[:, None] + np.concatenate(
        [np.zeros((len(P), 1)), np.cumsum(-np.sort(-flex, axis=1), axis=1)], axis=1)
    return (totals[None, :, :] < targets[:, None, None] - TOLERANCE).sum(axis=2)


def selection_study(participation: dict[str, xr.Dataset], thresholds, *,
                    flutter_modes: int = 2) -> xr.Dataset:
    """The mode-selection study: how many flexible modes each threshold needs.

    Parameters
    ----------
    participation : dict of str -> xarray.Dataset
        Configuration -> participation.nc Dataset (as for :func:`select_modes`).
    thresholds : sequence of float
        Fractions in (0, 1] (sorted increasingly in the result).
    flutter_modes : int
        Critical roots: the first ``flutter_modes`` flutter crossings of every sweep.

    Returns
    -------
    xarray.Dataset
        ``n_modes(threshold, flutter_point)``: size of the smallest set of flexible modes that,
        with the rigid-body modes, reaches the threshold for that critical root alone;
        ``n_primary(threshold, configuration)`` and ``primary_modes(threshold, configuration)``
        (comma-separated ids): the joint selection of :func:`select_modes` over all of the
        configuration's critical roots; ``critical_roots(configuration)``; flutter_point
        coordinates as in :func:`select_modes` (critical roots only).
    """
    th = np.unique(np.asarray(thresholds, dtype=float))
    bad = th[~((th > 0.0) & (th <= 1.0))]
    if th.size == 0 or bad.size:
        raise InputError(card_message(
            f"thresholds {bad.tolist()} are not fractions in (0, 1]." if bad.size
            else "no threshold given.", card="--thresholds",
            fix="give fractions, e.g. --thresholds 0.85,0.9,0.95 (not percentages)."))
    units = _check_inputs(participation, flutter_modes)
    configs = list(participation)
    counts, n_primary, ids = [], np.zeros((th.size, len(configs)), int), []
    for c, ds in enumerate(participation.values()):
        crit = _critical(ds, flutter_modes)
        rigid = ds["rigid"].values.astype(bool)
        P = ds["participation"].values[crit]
        counts.append(_single_root_counts(P, rigid, 100.0 * th))
        flex = np.flatnonzero(~rigid)
        chosen = [smallest_cover(P[:, flex], P[:, rigid].sum(axis=1), 100.0 * t)[0] if crit.any()
                  else np.zeros(0, int) for t in th]
        n_primary[:, c] = [len(s) for s in chosen]
        ids.append([", ".join(str(int(m)) for m in ds["mode"].values[flex[s]]) for s in chosen])
    labels = unit_labels(units)
    coords = _point_coords(participation, lambda ds: _critical(ds, flutter_modes), labels)
    n_crit = [int(_critical(ds, flutter_modes).sum()) for ds in participation.values()]
    return xr.Dataset(
        {"n_modes": (("threshold", "flutter_point"), np.concatenate(counts, axis=1),
                     {"description": "flexible modes needed with the rigid-body modes, root alone"}),
         "n_primary": (("threshold", "configuration"), n_primary,
                       {"description": "flexible modes needed for every critical root at once"}),
         "primary_modes": (("threshold", "configuration"), np.array(ids, dtype=str).T),
         "critical_roots": ("configuration", np.array(n_crit, dtype=int))},
        coords={"threshold": ("threshold", th, {"units": "1 (fraction)"}), "configuration": configs,
                "flutter_point": np.arange(sum(n_crit)), **coords},
        attrs={"flutter_modes": int(flutter_modes), "units": labels.system,
               "tolerance_percent": TOLERANCE})


def study_table(study: xr.Dataset) -> str:
    """The study as text: per threshold, the modes each critical root needs alone, then the joint
    selection size and modes of each configuration.

    Parameters
    ----------
    study : xarray.Dataset
        From :func:`selection_study`.

    Returns
    -------
    str
    """
    lines = [f"Flexible modes needed, with the rigid-body modes, per threshold (critical roots: first "
             f"{study.attrs['flutter_modes']} flutter modes of every sweep)"]
    if study.sizes["flutter_point"]:
        names = point_labels(study)
        width = max(len(n) for n in names) + 2
        lines.append(f"{'root':<{width}s}" + "".join(f"{100 * float(t):>8.4g}%"
                                                     for t in study["threshold"].values))
        for i, name in enumerate(names):
            lines.append(f"{name:<{width}s}" + "".join(f"{int(n):>9d}"
                                                       for n in study["n_modes"].values[:, i]))
    else:
        lines.append("no critical flutter roots in any configuration")
    lines.append("")
    lines.append("joint selection (every critical root of the configuration):")
    for c, name in enumerate(study["configuration"].values):
        if int(study["critical_roots"].values[c]) == 0:
            lines.append(f"  {name}: no critical flutter roots")
            continue
        for t, n, m in zip(study["threshold"].values, study["n_primary"].values[:, c],
                           study["primary_modes"].values[:, c]):
            lines.append(f"  {name} {100 * float(t):g} %: {int(n)} mode{'s' if n != 1 else ''} "
                         f"({m or 'the rigid-body modes suffice'})")
    return "\n".join(lines)
