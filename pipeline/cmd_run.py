"""``pipeline run [CASE.toml] [--out DIR] [--from STAGE]``: run a case end to end (the shipped
example by default); ``pipeline status [CASE.toml] [--out DIR]`` lists its stages."""
from __future__ import annotations

from pathlib import Path

from structures.common.errors import InputError


def add_parser(sub) -> None:
    p = sub.add_parser("run", help="run a case end to end (default: the shipped example)")
    p.add_argument("case", nargs="?", default=None, help="TOML case file (default: shipped example)")
    p.add_argument("--out", default=None, help="run folder (default: runs/<case name>)")
    p.add_argument("--from", dest="from_stage", metavar="STAGE", default=None,
                   help="rerun this stage (name, prefix such as stage1, or glob) and all after it")
    p.set_defaults(func=run)
    s = sub.add_parser("status", help="list the stages of a run folder: done / stale / missing")
    s.add_argument("case", nargs="?", default=None, help="TOML case file (default: shipped example)")
    s.add_argument("--out", default=None, help="run folder (default: runs/<case name>)")
    s.set_defaults(func=status)


def case_and_run_folder(args):
    """The case and its run folder from the arguments."""
    from pipeline.case import read_case
    from pipeline.run import EXAMPLE_CASE

    path = Path(args.case) if args.case else EXAMPLE_CASE
    if args.case is None and not path.exists():
        raise InputError(f"the shipped example {path} is missing. Fix: run from a checkout of the "
                         "project (pip install -e .) or give a case file.")
    case = read_case(path)
    return case, Path(args.out) if args.out else Path("runs") / case.name


def run(args) -> int:
    # The whole chain (matplotlib, flutter) is imported here, not when every command's parser is
    # built.
    from pipeline.run import run_case

    case, out = case_and_run_folder(args)
    run_case(case, out, from_stage=args.from_stage)
    return 0


def status(args) -> int:
    from pipeline.run import run_status

    case, out = case_and_run_folder(args)
    rows = run_status(case, out)
    width = max(len(name) for name, _, _ in rows)
    print(f"run folder {out}")
    for name, state, reason in rows:
        print(f"  {name:{width}s}  {state:7s}  {reason}".rstrip())
    return 0
