"""``pipeline correlate CASE_OR_DECK [GVT] [--out corr.nc]``: test-analysis correlation with GVT data.

CASE_OR_DECK is a bulk-data deck (modes computed with ``compute_modes``), a modes netCDF file
(``.nc``, e.g. from ``pipeline modes --out``) or a TOML case file (``.toml``: the configuration named
by ``--config``, by default the first one with a ``gvt``, gives deck, nmodes, mass, gvt and
measured mass; its modes and correlation are computed by the same library calls as the stages of
``pipeline run``, pipeline.chain.configuration_modes / configuration_correlation). GVT is a
universal file (UFF 15 + 55, ``.unv``/``.uff``) or a GVT netCDF file; with a case file it defaults
to the configuration's ``gvt``.

Prints the frequency table, MAC, orthogonality and cross-orthogonality matrices like the paper's
Tables 1-4 and writes the correlation Dataset (``--out``) and figures (``--figures DIR``).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from structures.acceptance import DEFAULT_CRITERIA
from structures.assembly import MASS_OPTIONS
from structures.common.errors import InputError
from structures.gvt import load_gvt
from structures.common.files import check_output, staged_folder, write_dataset
from pipeline.cli import positive_int

_FAIL_CODES = (("pass_frequency", "f"), ("pass_cross_orthogonality_diagonal", "d"),
               ("pass_cross_orthogonality_off_diagonal", "x"), ("pass_orthogonality", "o"))


def _int_list(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(t) for t in text.replace(" ", "").split(",") if t)
    except ValueError:
        raise InputError(f"--primary {text!r}: give comma-separated test mode numbers, e.g. 7,8,9,11.")


def add_parser(sub) -> None:
    p = sub.add_parser("correlate", help="test-analysis correlation with GVT data (MAC, SEREP "
                                         "orthogonality, cross-orthogonality, acceptance checks)")
    p.add_argument("model", metavar="CASE_OR_DECK",
                   help="bulk-data deck, modes netCDF (.nc) or TOML case file (.toml)")
    p.add_argument("gvt", metavar="GVT", nargs="?", default=None,
                   help="GVT modes: UFF 15+55 (.unv/.uff) or GVT netCDF (.nc); default: the case's gvt")
    p.add_argument("--out", default=None, help="write the correlation Dataset to this netCDF file")
    p.add_argument("--figures", default=None, help="write MAC / orthogonality / frequency figures here")
    p.add_argument("--config", default=None, help="configuration of a case file (default: first with a gvt)")
    p.add_argument("--nmodes", type=positive_int, default=None,
                   help="analysis modes (default: a deck's 2 x test modes + 6, at most the number "
                        "of measured DOFs; a case's configuration nmodes as pipeline run)")
    p.add_argument("--mass", choices=MASS_OPTIONS, default="deck", help="mass formulation for a deck")
    p.add_argument("--pair-by", choices=("mac", "cross_orthogonality"), default="mac",
                   help="metric of the Hungarian mode pairing")
    p.add_argument("--a-set", choices=("all", "translational"), default="all",
                   help="analysis DOFs forming the SEREP A-set")
    p.add_argument("--primary", type=_int_list, default=None,
                   help="comma-separated primary test modes (others are secondary); default all")
    p.set_defaults(func=run)


def _analysis_modes(path: Path, gvt, nmodes, mass):
    if path.suffix.lower() == ".nc":
        from structures.modes import read_modes
        return read_modes(path)
    from structures.bdf import read_model
    from structures.correlation import default_nmodes
    from structures.modal import compute_modes
    model = read_model(path)
    return compute_modes(model, nmodes or default_nmodes(gvt), mass=mass)


def _configuration(args):
    """The case file's configuration named by --config (default: the first with a gvt), with the
    command line's GVT file if given."""
    from dataclasses import replace

    from pipeline.case import read_case
    case = read_case(args.model)
    configs = [c for c in case.configurations if args.config in (None, c.name)]
    if args.config is None:
        configs = [c for c in configs if c.gvt is not None] or configs
    if not configs:
        raise InputError(f"case {args.model}: no configuration {args.config!r}; valid: "
                         f"{[c.name for c in case.configurations]}.")
    config = configs[0]
    if args.gvt is None and config.gvt is None:
        raise InputError(f"case {args.model}, configuration {config.name}: no gvt. Fix: give GVT on the "
                         "command line or set gvt = \"...\" in the configuration.")
    return config if args.gvt is None else replace(config, gvt=Path(args.gvt))


def run(args) -> int:
    # Imported here (it loads scipy.optimize), not when every command's parser is built.
    from structures.correlation import CorrelationSettings, correlate

    if args.out:
        check_output(args.out, folder=False)
    if args.figures:
        check_output(args.figures, folder=True, option="--figures")
    path = Path(args.model)
    settings = CorrelationSettings(pair_by=args.pair_by, a_set=args.a_set)
    if path.suffix.lower() == ".toml":
        # a case: the same modes and correlation as the stages of pipeline run
        from pipeline.chain import configuration_correlation, configuration_modes
        config = _configuration(args)
        load_gvt(config.gvt)                     # a bad GVT file fails before the eigen solve
        modes, props = configuration_modes(config, args.nmodes)
        corr = configuration_correlation(config, modes, props, settings, args.primary)
    elif args.gvt is None:
        raise InputError("pipeline correlate: GVT file missing. Fix: pipeline correlate DECK GVT.unv.")
    else:
        gvt = load_gvt(Path(args.gvt))
        modes = _analysis_modes(path, gvt, args.nmodes, args.mass)
        corr = correlate(modes, gvt, settings, DEFAULT_CRITERIA, primary_modes=args.primary)
    print(correlation_tables(corr))
    if "mass_model" in corr:
        print("\nMass properties (model vs measured):")
        print(mass_comparison_table(corr))
    figures = []
    if args.figures:
        from structures.correlation_plots import save_correlation_figures
        with staged_folder(args.figures) as staged:
            figures = [Path(args.figures) / p.relative_to(staged)
                       for p in save_correlation_figures(corr, staged)]
            if args.out:
                write_dataset(corr, args.out)
    elif args.out:
        write_dataset(corr, args.out)
    if args.out:
        print(f"\ncorrelation written to {args.out}")
    for p in figures:
        print(f"figure written to {p}")
    return 0


def mass_comparison_table(corr) -> str:
    """Model vs measured mass properties (a correlation Dataset's ``mass_*`` variables) with the
    error in %."""
    lines = [f"{'quantity':>10} {'model':>14} {'measured':>14} {'error %':>9}"]
    for q in corr["quantity"].values:
        c = corr.sel(quantity=q)
        lines.append(f"{q:>10} {float(c.mass_model):14.6g} {float(c.mass_measured):14.6g} "
                     f"{float(c.mass_relative_error):9.3f}")
    return "\n".join(lines)


def _matrix(values, row_labels, col_labels, fmt) -> str:
    """A labelled matrix with columns wide enough for labels and signed values."""
    cells = [[fmt.format(v) for v in row] for row in np.asarray(values)]
    width = max([len(str(c)) for c in col_labels] + [len(c) for row in cells for c in row]) + 1
    label = max(len(str(r)) for r in row_labels) + 1
    lines = [" " * label + "".join(f"{str(c):>{width}}" for c in col_labels)]
    lines += [f"{str(r):<{label}}" + "".join(f"{c:>{width}}" for c in row)
              for r, row in zip(row_labels, cells)]
    return "\n".join(lines)


def correlation_tables(corr) -> str:
    """Text of the paper's Tables 1-4 for one correlation Dataset (formatting only)."""
    names = corr["test_name"].values if "test_name" in corr else [""] * corr.sizes["test_mode"]
    rows = [f"{int(m)} {n}".strip() for m, n in zip(corr["test_mode"].values, names)]
    paired = corr["paired_fe_mode"].values
    checks = [str(c) for c in corr["check"].values]
    head = (f"{'GVT mode':>12} {'f GVT':>10} {'FE mode':>8} {'f FE':>10} {'error %':>8} {'MAC':>5} "
            f"{'|S_ii|':>6} {'class':>9} " + " ".join(f"{c:>14}" for c in checks))
    lines = ["Frequencies [Hz] and checks (f: frequency, d: |S_ii|, x: S off-diagonal, o: orthogonality)",
             head]
    for k, label in enumerate(rows):
        verdicts = []
        for c in checks:
            failed = "".join(code for var, code in _FAIL_CODES if not bool(corr[var].sel(check=c).values[k]))
            verdicts.append("PASS" if not failed else f"FAIL({failed})")
        klass = "primary" if bool(corr["primary"].values[k]) else "secondary"
        lines.append(f"{label:>12} {corr['test_frequency'].values[k]:10.4g} {int(paired[k]):8d} "
                     f"{corr['paired_fe_frequency'].values[k]:10.4g} "
                     f"{corr['frequency_error'].values[k]:8.1f} "
                     f"{corr['paired_mac'].values[k]:5.2f} "
                     f"{abs(corr['paired_cross_orthogonality'].values[k]):6.3f} {klass:>9} "
                     + " ".join(f"{v:>14}" for v in verdicts))
    lines.append(f"mode interchanges: {corr.attrs.get('interchanges', 'none')}")
    if corr.attrs.get("suspension_modes", "none") != "none":
        lines.append(f"suspension modes left out: {corr.attrs['suspension_modes']} (rigid-body "
                     "motions at the sensors below the first elastic analysis frequency)")
    if "max_sensor_offset" in corr.attrs:
        lines.append(f"largest distance GVT node - model grid: {corr.attrs['max_sensor_offset']:.4g} "
                     "(model units; large values mean misnumbered nodes)")
    fe_labels = [str(int(m)) for m in paired]
    lines += ["", "MAC (rows: GVT modes, columns: paired FE modes)",
              _matrix(corr["mac"].sel(fe_mode=paired).values, rows, fe_labels, fmt="{:5.2f}"),
              "", "Orthogonality of GVT modes (SEREP mass, diagonal normalised to 1)",
              _matrix(corr["orthogonality"].values, rows,
                      [str(int(m)) for m in corr["test_mode"].values], fmt="{:6.3f}"),
              "", "Cross-orthogonality (rows: GVT modes, columns: paired FE modes)",
              _matrix(corr["cross_orthogonality"].sel(fe_mode=paired).values, rows, fe_labels,
                            fmt="{:6.3f}")]
    n_pass = {c: int(np.sum(corr["pass_all"].sel(check=c).values)) for c in checks}
    lines += ["", "Summary: " + "; ".join(f"{c}: {v}/{corr.sizes['test_mode']} modes pass"
                                          for c, v in n_pass.items())]
    return "\n".join(lines)
