"""``pipeline flutter CASE_OR_DECK [--out DIR]``: modes -> GAFs -> flutter (pipeline.chain)."""
from __future__ import annotations

from contextlib import nullcontext
from pathlib import Path

from pipeline.cli import positive_int
from pipeline.stage import running
from structures.common.files import check_output, staged_folder
from structures.units import unit_labels


def add_parser(sub) -> None:
    p = sub.add_parser("flutter", help="flutter analysis (PK / PKNL / KE) of a deck or a case file")
    p.add_argument("target", metavar="CASE_OR_DECK",
                   help="Nastran deck with FLUTTER/FLFACT/MKAERO1 cards, or a case file (.toml): "
                        "every configuration's deck is run")
    p.add_argument("--out", default=None, help="output folder for flutter.nc and summary.json "
                                               "(per configuration in a sub-folder for a case file)")
    p.add_argument("--nmodes", type=positive_int, default=None,
                   help="number of modes (default: PARAM LMODES, else the deck's EIGR/EIGRL)")
    p.add_argument("--flutter-id", type=int, action="append", default=None,
                   help="FLUTTER card id to run (repeatable; default: the FMETHOD selection)")
    p.set_defaults(func=run)


def _print(name: str, summary: list) -> None:
    """The crossings of a run, each number with its unit (the entry's ``units``, structures.units)."""
    print(f"{name}: {len(summary)} crossing(s)")
    for c in summary:
        u = c.get("units") or unit_labels(None).as_dict()
        print(f"  {c['kind']:10s} root {c['root']:3d}  Mach {c['mach']:.3f}  density "
              f"{c['density']:.5g} {u['density']}  V {c['velocity']:.5g} {u['velocity']}  "
              f"f {c['frequency']:.4g} {u['frequency']}")


def run(args) -> int:
    """A deck: :func:`pipeline.chain.deck_modes` and :func:`pipeline.chain.flutter_chain`. A case
    file: for every configuration the same two library calls as ``pipeline run``
    (:func:`pipeline.chain.configuration_modes` with the configuration's nmodes and mass option,
    :func:`pipeline.chain.case_flutter` with the case's ``[flutter]`` and ``[selection]``
    settings, on the grid GAFs that configurations with one aerodynamic grid share,
    :func:`pipeline.chain.aero_groups`); ``--nmodes`` / ``--flutter-id`` override them (with
    ``--flutter-id`` each configuration computes its own GAFs). All outputs are written only when
    every configuration has finished."""
    # here, not when every command's parser is built
    from pipeline.chain import (aero_groups, case_flutter, case_grid_gaf, check_flutter_requests,
                                configuration_modes, deck_modes, flutter_chain)

    target = Path(args.target)
    if args.out:
        check_output(args.out, folder=True)
    if target.suffix.lower() == ".toml":
        from pipeline.case import read_case

        case = read_case(target)
        check_flutter_requests(case, args.flutter_id)
        done, grids = [], {}
        groups = aero_groups(case) if args.flutter_id is None else {}
        with staged_folder(args.out) if args.out else nullcontext() as staged:
            for conf in case.configurations:
                with running(f"flutter/{conf.name}"):
                    grid = None
                    if conf.name in groups:
                        leader = groups[conf.name][0]
                        if leader not in grids:
                            grids[leader] = case_grid_gaf(case, next(
                                c for c in case.configurations if c.name == leader))
                        grid = grids[leader]
                    modes, _ = configuration_modes(conf, args.nmodes)
                    out = None if staged is None else staged / conf.name
                    done.append((conf.name, case_flutter(case, conf, modes, out, args.flutter_id,
                                                         grid_gaf=grid)))
        for name, res in done:
            _print(name, res["summary"])
        if args.out:
            print(f"results written to {args.out}")
        return 0
    with staged_folder(args.out) if args.out else nullcontext() as staged:
        res = flutter_chain(target, deck_modes(target, args.nmodes), flutter_ids=args.flutter_id,
                            out_dir=staged)
    _print(target.name, res["summary"])
    if args.out:
        print(f"results written to {args.out}")
    return 0
