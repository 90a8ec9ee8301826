"""``pipeline modes DECK.bdf [--nmodes N] [--out modes.nc]``: modes and mass properties of a deck."""
from __future__ import annotations

from structures.assembly import MASS_OPTIONS, assemble
from structures.bdf import read_model
from structures.massprops import mass_properties
from structures.modal import compute_modes
from structures.modes import write_modes
from structures.common.files import check_output
from pipeline.cli import positive_int
from pipeline.tables import frequency_table, mass_table


def add_parser(sub) -> None:
    p = sub.add_parser("modes", help="normal modes and mass properties of a Nastran deck")
    p.add_argument("deck", help="bulk-data deck (.bdf/.dat), INCLUDEs followed")
    p.add_argument("--nmodes", type=positive_int, default=None,
                   help="number of modes (default: the deck's EIGRL/EIGR ND, else 20; at most "
                   "as many as degrees of freedom carry mass)")
    p.add_argument("--mass", choices=MASS_OPTIONS, default="deck",
                   help="mass formulation (default: PARAM COUPMASS of the deck, as Nastran)")
    p.add_argument("--out", default=None, help="write the modes Dataset to this netCDF file")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.out:
        check_output(args.out, folder=False)
    model = read_model(args.deck)
    system = assemble(model, args.mass)
    modes = compute_modes(model, args.nmodes, mass=args.mass, system=system)
    props = mass_properties(model, m_basic=system.m_basic)
    print(frequency_table(modes))
    if modes.attrs["modes_requested"] > modes.sizes["mode"]:
        print(f"note: {modes.attrs['modes_requested']} modes were asked for; the model has "
              f"{modes.sizes['mode']}, as many as its degrees of freedom that carry mass.")
    print()
    print(mass_table(props))
    if args.out:
        write_modes(modes, args.out)
        print(f"\nmodes written to {args.out}")
    return 0
