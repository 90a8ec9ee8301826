"""``pipeline check DECK [--nmodes N]``: read, assemble and check a deck before any analysis.

Prints the cards read per type (and the unsupported ones with their ids), the grid point
singularity table (Nastran's AUTOSPC processing), mechanisms with the grids involved, coincident
grids, free shell edges, grids not connected to anything, the mass properties and the lowest modes.
Nothing else is computed, so it runs in seconds on a model of a few thousand grids.
"""
from __future__ import annotations

from structures.assembly import assemble
from structures.bdf import NON_STRUCTURAL_CARDS, SUPPORTED_CARDS, read_model
from structures.common.nastran import read_pynastran
from structures.common.errors import SolverError
from structures.massprops import mass_properties
from structures.modal import compute_modes
from pipeline.cli import positive_int
from pipeline.tables import frequency_table, mass_table


def add_parser(sub) -> None:
    p = sub.add_parser("check", help="model checks of a Nastran deck: cards, singularities, "
                                     "mechanisms, coincident grids, free edges, mass, lowest modes")
    p.add_argument("deck", help="bulk-data deck (.bdf/.dat), INCLUDEs followed")
    p.add_argument("--nmodes", type=positive_int, default=10,
                   help="number of lowest modes to print (default 10)")
    p.set_defaults(func=run)


def _card_table(card_count) -> str:
    lines = [f"{'card':>10} {'count':>8}  status"]
    for name, count in sorted(card_count.items()):
        status = ("" if name in SUPPORTED_CARDS else
                  "ignored (non-structural)" if name in NON_STRUCTURAL_CARDS else "UNSUPPORTED")
        lines.append(f"{name:>10} {count:>8d}  {status}")
    return "\n".join(lines)


def run(args) -> int:
    from structures.checks import model_checks   # scipy.spatial: here, not in every parser

    parsed = read_pynastran(args.deck)
    print("cards read")
    print(_card_table(parsed.card_count))
    # unsupported cards: the CLI's error line, exit code 2
    model = read_model(args.deck, parsed=parsed)
    system = assemble(model, warn=False)
    checks = model_checks(model, system.singularities)
    print()
    print(checks.format())
    print("\nmass properties")
    print(mass_table(mass_properties(model, m_basic=system.m_basic)))
    try:
        modes = compute_modes(model, args.nmodes, system=system)
    except SolverError as exc:
        print(f"\nlowest {args.nmodes} modes")
        print(f"mechanism: {exc}")
        return 1
    count = modes.sizes["mode"]
    print(f"\nlowest {count} modes" if count == args.nmodes else
          f"\nall {count} of the model's modes ({args.nmodes} asked for; a model has as many as "
          "its degrees of freedom that carry mass)")
    print("mechanisms: none (every zero-frequency mode is a rigid-body motion)")
    print(frequency_table(modes))
    return 0
