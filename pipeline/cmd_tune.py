"""``pipeline tune CASE.toml``: tune the configurations' decks to their GVT data (paper eq. 25).

The case file's ``[[configurations]]`` (name, deck, gvt, nmodes, mass) and its ``[tuning]`` section
are read and validated by :func:`pipeline.case.read_case`; ``[tuning]`` holds::

    [tuning]
    method = "slsqp"              # slsqp | trust-constr | differential_evolution
    maxiter = 50
    shape_method = "nelson"       # nelson (exact) | modal (fast, truncated)
    restart = "old/history.nc"    # optional: start from the best design of that history
    allowed_violation = 0.05      # restart rule (structures.tuning.best_from_history)
    out = "tuning"                # output folder, relative to the case file

    [[tuning.variables]]
    name = "wing_I1"
    fields = [["PBAR", 11, "I1"], ["PBAR", 12, "I1"]]   # linked fields (card, id, field)
    lower = 1.6e-6                # optional; default -20 % / +20 % of the deck value
    upper = 2.4e-6
    scale = 2e-6                  # optional; default |deck value|

    [[tuning.objective]]
    index = "empty:frequency:*"   # index name or glob (structures.indices)
    weight = 1.0

    [[tuning.constraints]]
    index = "*:cross_orthogonality:*"
    limit = 0.01                  # J_k <= eps_k (MAC: J_k >= eps_k)

    # noisy test shapes: weight every term by its noise, w = sigma_f^2 / sigma^2 (frequency
    # terms weight 1 <-> sigma_f). With white sensor noise of s x rms per DOF, the MAC terms with
    # w = n_DOF sigma_f^2 / s^2 are the maximum-likelihood shape fit (1 %, 5 %, 120 DOFs: 4.8);
    # cross-orthogonality terms pass the noise through SEREP's pseudo-inverse and are better kept
    # as checks. The design-change terms are a prior of std sigma_p: w = (sigma_f / sigma_p)^2.
    [[tuning.objective]]
    index = "*:mac:*"
    weight = 4.8
    [[tuning.objective]]
    index = "design:change:*"     # ((x - x0) / x0)^2 of every design variable
    weight = 0.013

    [tuning.configurations.empty] # optional, per configuration
    test_modes = [7, 8, 9]
    mass_targets = { weight = 1500.0, x_cg = 4.2 }  # default: the configuration's measured_mass
    mass_references = { y_cg = 1.0 }

Writes ``history.nc`` (every evaluation), ``<config>_tuned.bdf`` per configuration and
``report.txt`` (frequency, design-change and index tables) into the output folder, and prints one
progress line per optimiser iteration.
"""
from __future__ import annotations

from pathlib import Path

from pipeline.cli import positive_int
from structures.common.errors import InputError


def read_tuning(path) -> tuple:
    """Read a case file with a ``[tuning]`` section (validated by :func:`pipeline.case.read_case`).

    Returns
    -------
    (pipeline.case.Case, pipeline.case.TuningSettings)
    """
    from pipeline.case import read_case

    case = read_case(path)
    if case.tuning is None:
        raise InputError(f"file {case.path}: no [tuning] section. Fix: add [tuning] with variables "
                         "and objective (see pipeline/cmd_tune.py).")
    for c in case.configurations:
        if c.gvt is None:
            raise InputError(f"file {case.path}: configuration {c.name} has no gvt file. Fix: add "
                             "gvt = \"...\" to it.")
    return case, case.tuning


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("tune", help="tune the decks to the GVT data (paper eq. 25)")
    p.add_argument("case", help="TOML case file with [[configurations]] and [tuning]")
    p.add_argument("--out", help="output folder (default: [tuning] out)")
    p.add_argument("--maxiter", type=positive_int, help="override [tuning] maxiter")
    p.set_defaults(func=run)


def run(args) -> int:
    from structures.design import write_tuned_bdf
    from structures.common.files import (check_output, read_dataset, staged_folder, write_dataset,
                                   write_text)
    from structures.tuning import best_from_history, tune
    from structures.tuning_report import tuning_report
    from pipeline.loop import tuning_problem

    case, settings = read_tuning(args.case)
    out = check_output(Path(args.out).resolve() if args.out else settings.out, folder=True,
                       option="--out" if args.out else "[tuning] out")
    problem = tuning_problem(case, settings.objective, settings.constraints)
    start = None
    if settings.restart is not None:
        start = best_from_history(read_dataset(settings.restart), settings.allowed_violation)
        print(f"restart from the best design of {settings.restart}")

    def progress(iteration, objective, violation, seconds):
        print(f"iteration {iteration:4d}  objective {objective:12.5e}  max violation "
              f"{violation:10.3e}  {seconds:8.1f} s", flush=True)

    result = tune(problem, method=settings.method, start=start,
                  maxiter=args.maxiter or settings.maxiter, progress=progress)
    report = tuning_report(result.history)
    with staged_folder(out) as staged:
        write_dataset(result.history, staged / "history.nc")
        for c in case.configurations:
            write_tuned_bdf(c.deck, staged / f"{c.name}_tuned.bdf", result.space, result.x)
        write_text(report + "\n", staged / "report.txt")
    print(report)
    print(f"{'converged' if result.success else 'not converged'}: {result.message}; results in {out}")
    return 0
