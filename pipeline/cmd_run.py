"""``pipeline run [CASE.toml] [--out DIR]``: run a case end to end (the shipped example by default)."""
from __future__ import annotations

from pathlib import Path

from structures.common.errors import InputError


def add_parser(sub) -> None:
    p = sub.add_parser("run", help="run a case end to end (default: the shipped example)")
    p.add_argument("case", nargs="?", default=None, help="TOML case file (default: shipped example)")
    p.add_argument("--out", default=None, help="run folder (default: runs/<case name>)")
    p.set_defaults(func=run)


def run(args) -> int:
    # The whole chain (matplotlib, flutter) is imported here, not when every command's parser is
    # built.
    from pipeline.case import read_case
    from pipeline.run import EXAMPLE_CASE, run_case

    path = Path(args.case) if args.case else EXAMPLE_CASE
    if args.case is None and not path.exists():
        raise InputError(f"the shipped example {path} is missing. Fix: run from a checkout of the "
                         "project (pip install -e .) or give a case file.")
    case = read_case(path)
    out = Path(args.out) if args.out else Path("runs") / case.name
    run_case(case, out)
    return 0
