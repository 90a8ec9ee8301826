"""``pipeline flutter CASE_OR_DECK [--out DIR]``: modes -> GAFs -> flutter (library: flutter.run)."""
from __future__ import annotations

from pathlib import Path

from flutter.run import run_flutter


def add_parser(sub) -> None:
    p = sub.add_parser("flutter", help="flutter analysis (PK / PKNL / KE) of a deck or a case file")
    p.add_argument("target", metavar="CASE_OR_DECK",
                   help="Nastran deck with FLUTTER/FLFACT/MKAERO1 cards, or a case file (.toml): "
                        "every configuration's deck is run")
    p.add_argument("--out", default=None, help="output folder for flutter.nc and summary.json "
                                               "(per configuration in a sub-folder for a case file)")
    p.add_argument("--nmodes", type=int, default=None,
                   help="number of modes (default: PARAM LMODES, else the deck's EIGR/EIGRL)")
    p.add_argument("--flutter-id", type=int, action="append", default=None,
                   help="FLUTTER card id to run (repeatable; default: the FMETHOD selection)")
    p.set_defaults(func=run)


def _print(name: str, summary: list) -> None:
    print(f"{name}: {len(summary)} crossing(s)")
    for c in summary:
        print(f"  {c['kind']:10s} root {c['root']:3d}  Mach {c['mach']:.3f}  density {c['density']:.5g}"
              f"  V {c['velocity']:.5g}  f {c['frequency']:.4g} Hz")


def run(args) -> int:
    target = Path(args.target)
    if target.suffix.lower() == ".toml":
        from pipeline.case import read_case

        case = read_case(target)
        for conf in case.configurations:
            out = None if args.out is None else Path(args.out) / conf.name
            res = run_flutter(conf.deck, out, nmodes=args.nmodes or conf.nmodes,
                              flutter_ids=args.flutter_id)
            _print(conf.name, res["summary"])
        return 0
    res = run_flutter(target, args.out, nmodes=args.nmodes, flutter_ids=args.flutter_id)
    _print(target.name, res["summary"])
    if args.out:
        print(f"results written to {args.out}")
    return 0
