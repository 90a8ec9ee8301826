"""``pipeline tune CASE.toml``: tune the configurations' decks to their GVT data (paper eq. 25).

The case file's ``[[configurations]]`` (name, deck, gvt, nmodes, mass) are read as in
:mod:`pipeline.case`; the ``[tuning]`` section (read here, by :func:`read_tuning`) adds::

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

from dataclasses import dataclass
from pathlib import Path

from structures.errors import InputError

_TUNING_KEYS = {"method", "maxiter", "shape_method", "restart", "allowed_violation", "out",
                "variables", "objective", "constraints", "configurations"}
_VARIABLE_KEYS = {"name", "fields", "lower", "upper", "scale"}
_CONFIG_KEYS = {"test_modes", "mass_targets", "mass_references"}


@dataclass(frozen=True)
class TuningSettings:
    """The validated ``[tuning]`` section of a case file."""

    variables: tuple
    objective: tuple
    constraints: tuple = ()
    method: str = "slsqp"
    maxiter: int = 50
    shape_method: str = "nelson"
    restart: Path | None = None
    allowed_violation: float = 0.05
    out: Path | None = None
    per_configuration: tuple = ()


def _unknown(table: dict, valid: set, where: str) -> None:
    bad = sorted(set(table) - valid)
    if bad:
        raise InputError(f"{where}: unknown keys {bad}; valid: {sorted(valid)}.")


def read_tuning(path) -> tuple:
    """Read a case file with a ``[tuning]`` section.

    Returns
    -------
    (pipeline.case.Case, TuningSettings)
    """
    from pipeline.case import read_case
    from structures.design import DesignVariable

    case = read_case(path)
    path = case.path
    base = path.parent
    configs = case.configurations
    tun = case.tuning
    if tun is None:
        raise InputError(f"file {path}: no [tuning] section. Fix: add [tuning] with variables and "
                         "objective (see pipeline/cmd_tune.py).")
    _unknown(tun, _TUNING_KEYS, f"file {path}, [tuning]")
    variables = []
    for i, v in enumerate(tun.get("variables", [])):
        _unknown(v, _VARIABLE_KEYS, f"file {path}, [[tuning.variables]] #{i + 1}")
        if "name" not in v or "fields" not in v:
            raise InputError(f"file {path}, [[tuning.variables]] #{i + 1}: 'name' and 'fields' are required.")
        variables.append(DesignVariable(v["name"], tuple(tuple(f) for f in v["fields"]),
                                        v.get("lower"), v.get("upper"), v.get("scale")))
    objective = tuple((t["index"], float(t.get("weight", 1.0))) for t in tun.get("objective", []))
    constraints = tuple((t["index"], float(t["limit"])) for t in tun.get("constraints", []))
    names = {c.name for c in configs}
    per = []
    for name, table in tun.get("configurations", {}).items():
        if name not in names:
            raise InputError(f"file {path}: [tuning.configurations.{name}] names no configuration "
                             f"{sorted(names)}.")
        _unknown(table, _CONFIG_KEYS, f"file {path}, [tuning.configurations.{name}]")
        per.append((name, table))
    for c in configs:
        if c.gvt is None:
            raise InputError(f"file {path}: configuration {c.name} has no gvt file. Fix: add gvt = ...")
    settings = TuningSettings(
        variables=tuple(variables), objective=objective, constraints=constraints,
        method=tun.get("method", "slsqp"), maxiter=int(tun.get("maxiter", 50)),
        shape_method=tun.get("shape_method", "nelson"),
        restart=(base / tun["restart"]).resolve() if tun.get("restart") else None,
        allowed_violation=float(tun.get("allowed_violation", 0.05)),
        out=(base / tun.get("out", f"{case.name}_tuning")).resolve(), per_configuration=tuple(per))
    return case, settings


def build_problem(case, settings):
    """The structures.tuning problem of a case (reads the decks and the GVT files)."""
    from structures.bdf import read_model
    from structures.gvt import load_gvt
    from structures.tuning import TuningConfiguration, TuningProblem

    extra = dict(settings.per_configuration)
    configs = []
    for c in case.configurations:
        more = extra.get(c.name, {})
        configs.append(TuningConfiguration(
            c.name, read_model(c.deck), load_gvt(c.gvt), nmodes=c.nmodes or 30, mass=c.mass,
            test_modes=tuple(more["test_modes"]) if "test_modes" in more else None,
            mass_targets=more.get("mass_targets", dict(c.measured_mass)),
            mass_references=more.get("mass_references", {})))
    return TuningProblem(tuple(configs), settings.variables, settings.objective,
                         settings.constraints, shape_method=settings.shape_method)


def add_parser(subparsers) -> None:
    p = subparsers.add_parser("tune", help="tune the decks to the GVT data (paper eq. 25)")
    p.add_argument("case", help="TOML case file with [[configurations]] and [tuning]")
    p.add_argument("--out", help="output folder (default: [tuning] out)")
    p.add_argument("--maxiter", type=int, help="override [tuning] maxiter")
    p.set_defaults(func=run)


def run(args) -> int:
    from structures.design import write_tuned_bdf
    from structures.netcdf import read_dataset, write_dataset
    from structures.tuning import best_from_history, tune
    from structures.tuning_report import tuning_report

    case, settings = read_tuning(args.case)
    problem = build_problem(case, settings)
    out = Path(args.out).resolve() if args.out else settings.out
    start = None
    if settings.restart is not None:
        start = best_from_history(read_dataset(settings.restart), settings.allowed_violation)
        print(f"restart from the best design of {settings.restart}")

    def progress(iteration, objective, violation, seconds):
        print(f"iteration {iteration:4d}  objective {objective:12.5e}  max violation "
              f"{violation:10.3e}  {seconds:8.1f} s", flush=True)

    result = tune(problem, method=settings.method, start=start,
                  maxiter=args.maxiter or settings.maxiter, progress=progress)
    write_dataset(result.history, out / "history.nc")
    for c in case.configurations:
        write_tuned_bdf(c.deck, out / f"{c.name}_tuned.bdf", result.space, result.x)
    report = tuning_report(result.history)
    (out / "report.txt").write_text(report + "\n")
    print(report)
    print(f"{'converged' if result.success else 'not converged'}: {result.message}; results in {out}")
    return 0
