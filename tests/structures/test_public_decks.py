"""Public Nastran decks that nobody on this project wrote, against Nastran's own eigenvalue tables.

The decks and F06 excerpts are in ``tests/data`` (see ``tests/data/SOURCES.md``):

* ``goland_wingbox``: Goland wing box from pyNastran (MSC Nastran 2018, SOL 200 ANALYSIS=MODES):
  built-up membrane skin (t = 0.0155), spars, ribs, rod caps and posts, 66 CONM2; one mode.
* ``cofe_72bar``: the 72-bar space truss from NASTRAN_CoFE (MSC Nastran 2019, SOL 103); 10 modes.
* ``dakota_cylinder``: free-free CQUAD4 cylinder with RBE2 end rings and a 1000 lb seismic mass
  (CONM2), PARAM COUPMASS 1 and WTMASS, from Dakota's Nastran example (MSC.Nastran 70.7.2); 20
  modes, 6 of them rigid.
* ``windy_fwt``: University of Bristol WINDY wind-tunnel wing with the 'Lite' folding wingtip
  (fwtfemlite, INCLUDE chain of five files): PBEAML BAR spar, CBEAM, CONM2 with offsets and
  inertias in rotated CORD2R frames, GRID CP/CD, three RBE3 carrying the hinge and tip masses,
  RBE2 spiders, PLOTEL, DMI. No F06 is published: cross-checked against MYSTRAN.

Rigid-body roots: an F06 frequency below 1e-3 times the table's largest is numerical noise of a
zero eigenvalue (the cylinder's are 1e-5..7e-4 Hz against 2,687 Hz); ours must then be below 1e-3
times the first elastic frequency too. Elastic roots are compared to 0.5 %.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.cli import COMMANDS, main
from structures.assembly import assemble
from structures.bdf import read_model
from structures.bulk_text import card
from structures.massprops import mass_properties
from structures.modal import RESIDUAL_TOL, compute_modes, eigen_residuals, solve_eigen
from structures.nastran_results import read_f06_eigenvalues
from structures.rigid import element_constraints
from test_mystran import needs_mystran, run_mystran
from tests.pipeline.diagnose.truth.windy import as_bars

DATA = Path(__file__).resolve().parents[1] / "data"
RTOL = 5e-3
RIGID = 1e-3

GOLAND = ("goland_wingbox/goland_final_test.bdf", "goland_wingbox/goland_final_test_excerpt.f06")
BAR72 = ("cofe_72bar/modes.dat", "cofe_72bar/modes_excerpt.f06")
CYLINDER = ("dakota_cylinder/modal.bdf", "dakota_cylinder/modal_excerpt.f06")
FWT = "windy_fwt/sol103.bdf"

#: Cylinder modes (1-based) whose frequencies differ from MSC.Nastran 70.7 by 2.0-2.6 %: the n = 2
#: (ovalling) pairs at 5564, 6717 and 8881 Hz (ours 5706.9, 6869.9, 9062.4 Hz with the consistent
#: mass the deck asks for). The others agree to 0.33 % or better.
CYLINDER_OFF = (10, 11, 13, 14, 17, 18)
#: One mode of each n = 2 pair (1-based), and MSC.Nastran 70.7's frequencies of them [Hz].
CYLINDER_PAIRS = (10, 13, 17)
CYLINDER_PAIRS_MSC = (5564.107, 6716.664, 8881.048)


def _reference(f06):
    return read_f06_eigenvalues(DATA / f06).frequency.values


def _compare(ours, ref, modes):
    """Relative error of the listed 1-based elastic modes; rigid roots checked on the way."""
    rigid = ref < RIGID * ref.max()
    elastic_min = ref[~rigid].min()
    assert np.all(ours[rigid] < RIGID * elastic_min), ours[rigid]
    idx = np.asarray(modes) - 1
    assert not np.any(rigid[idx])
    return ours[idx] / ref[idx] - 1.0


def test_f06_excerpts_hold_nastrans_numbers():
    """The parsed tables are the F06 lines copied verbatim (guards the reference itself)."""
    assert _reference(GOLAND[1]).tolist() == [1.981382]
    bar = _reference(BAR72[1])
    assert bar.size == 10 and bar[0] == 25.4557 and bar[9] == 136.6591
    cyl = _reference(CYLINDER[1])
    assert cyl.size == 20 and cyl[6] == 2687.641 and cyl[19] == 11792.99
    assert np.all(cyl[:6] < 1e-3) and cyl[6] > 2e3


def test_goland_wingbox_first_mode_matches_msc_nastran():
    """Thin membrane skin, spars and ribs (no bending, MID2 blank), caps and posts, 66 CONM2."""
    ref = _reference(GOLAND[1])
    ours = compute_modes(read_model(DATA / GOLAND[0]), 1)["frequency"].values
    err = _compare(ours, ref, [1])
    assert np.all(np.abs(err) < RTOL), err
    # 2.2e-6 measured: no drilling penalty on membrane-only panels, as Nastran (+3.0e-4 with one)
    assert abs(err[0]) < 1e-5


def test_goland_wingbox_singularities_match_msc_nastran():
    """MSC's F06 lists R4-R6 of the 60 unconstrained grids as singular (ratio 0.00E+00): the
    membrane-only panels get no K6ROT drilling stiffness, so AUTOSPC removes those rotations."""
    system = assemble(read_model(DATA / GOLAND[0]))
    table = system.singularities
    assert len(table) == 180
    assert len(np.unique(table.grid)) == 60
    assert set(np.unique(table.component).tolist()) == {4, 5, 6}


def test_72_bar_truss_matches_msc_nastran():
    ref = _reference(BAR72[1])
    ours = compute_modes(read_model(DATA / BAR72[0]), 10)["frequency"].values
    err = _compare(ours, ref, range(1, 11))
    assert np.all(np.abs(err) < RTOL), err
    assert np.all(np.abs(err) < 1e-6)   # same lumped rod mass as Nastran: agreement to 7 digits


@pytest.mark.parametrize("backend", ["superlu", "pardiso"])
def test_cylinder_default_shift_is_rescaled(backend, monkeypatch):
    """Rigid-body modes at 0 Hz and elastic ones at 2.7-11.8 kHz: at the default shift
    -(2 pi 0.1 Hz)^2 the factorisation of K - sigma M loses the elastic components (SuperLU returned
    run-to-run different roots, 2620-2744 Hz for the 2687.6 Hz one); the eigenpair residual check
    re-solves at a tenth of the lowest elastic eigenvalue. Reference: a shift of -(2 pi 100 Hz)^2
    chosen by hand, where both backends agree to 1e-9."""
    if backend == "pardiso":
        pytest.importorskip("pypardiso")
    monkeypatch.setenv("FTP_SPARSE_BACKEND", backend)
    model = read_model(DATA / CYLINDER[0])
    system = assemble(model)
    lam, phi = solve_eigen(system.K, system.M, 20, groups=system.a_dofs // 6)
    ref, _ = solve_eigen(system.K, system.M, 20, shift=-(2.0 * np.pi * 100.0) ** 2,
                         groups=system.a_dofs // 6)
    np.testing.assert_allclose(lam[6:], ref[6:], rtol=1e-8)
    assert np.all(eigen_residuals(system.K, system.M, lam[6:], phi[:, 6:]) < RESIDUAL_TOL)
    assert np.all(np.abs(lam[:6]) < 1e-6 * lam[6])


def test_cylinder_matches_msc_nastran_except_the_known_pairs():
    ref = _reference(CYLINDER[1])
    ours = compute_modes(read_model(DATA / CYLINDER[0]), 20)["frequency"].values
    modes = [m for m in range(7, 21) if m not in CYLINDER_OFF]
    err = _compare(ours, ref, modes)
    assert np.all(np.abs(err) < RTOL), dict(zip(modes, err))


@pytest.mark.xfail(strict=True, reason="element discretisation, not a defect: the three n = 2 "
                   "(ovalling) pairs of the 16-facet cylinder are far from converged for every flat "
                   "shell element (see the circumferential-refinement tests below); ours (MITC4 "
                   "bending) is 2.0-2.6 % above MSC 70.7's QUAD4 there, MYSTRAN's MIN4 2.2-3.6 % "
                   "below it")
def test_cylinder_known_pairs_match_msc_nastran():
    """The n = 2 pairs against the F06 at 0.5 %: not met at the deck's mesh (expected failure).

    Cause, measured: these pairs are ovalling modes (80 % radial motion) governed by the bending
    of the wall around the circumference, which 16 flat facets (4 per half-wave) resolve poorly.
    Refining the circumference 16 -> 64 facets lowers ours by 5.6-6.8 %; refining the length
    20 -> 40 elements changes them by 0.04-1.1 %; MSC's values lie between our 16- and 64-facet
    results. Mass variants do not explain it (lumped, lumped in-plane only, rotary inertia
    rho t^3/12: no variant brings all three pairs within 0.5 % without moving the 2688 Hz pair),
    nor do K6ROT (0 to 1e4: < 0.1 %), the membrane (in-plane shear at one point: no change) or
    the PSHELL fields (T, MID2 = MID3 = MID1, 12I/T^3 = 1, TS/T = 5/6 as the deck gives).
    """
    ref = _reference(CYLINDER[1])
    ours = compute_modes(read_model(DATA / CYLINDER[0]), 20)["frequency"].values
    err = _compare(ours, ref, CYLINDER_OFF)
    assert np.all(np.abs(err) < RTOL), err


def _cylinder_deck(path: Path, n_around: int, n_along: int) -> Path:
    """The Dakota cylinder re-meshed: radius 1, length 10, PSHELL/MAT1/CONM2/RBE2 rings as the deck.

    ``n_around`` facets around, ``n_along`` elements along; lumped mass (no COUPMASS), so that
    MYSTRAN, which ignores PARAM COUPMASS, solves the same problem.
    """
    bulk = [card("EIGRL", 1, None, None, 20, 0), "PARAM,WTMASS,.00259",
            card("PSHELL", 101, 101, 0.2, 101, None, 101), card("MAT1", 101, 1.0e7, None, 0.35, 0.1)]
    gid = lambda j, k: 1 + k * n_around + j % n_around  # noqa: E731
    for k in range(n_along + 1):
        for j in range(n_around):
            angle = 2.0 * np.pi * j / n_around
            bulk.append(f"GRID,{gid(j, k)},,{np.cos(angle):.12f},{np.sin(angle):.12f},"
                        f"{10.0 * k / n_along:.12f}")
    eid = 1
    for k in range(n_along):
        for j in range(n_around):
            bulk.append(card("CQUAD4", eid, 101, gid(j, k), gid(j + 1, k), gid(j + 1, k + 1),
                             gid(j, k + 1)))
            eid += 1
    mass_grid, load_grid = gid(0, n_along + 1), gid(1, n_along + 1)
    bulk += [f"GRID,{mass_grid},,0.,0.,-0.5", f"GRID,{load_grid},,0.,0.,10.",
             card("CONM2", eid, mass_grid, None, 1000.0),
             card("RBE2", eid + 1, mass_grid, 123456, *[gid(j, 0) for j in range(n_around)]),
             card("RBE2", eid + 2, load_grid, 123456, *[gid(j, n_along) for j in range(n_around)])]
    path.write_text("\n".join(["SOL 103", "CEND", "METHOD = 1", "DISP(PLOT) = ALL", "BEGIN BULK",
                               *bulk, "ENDDATA"]) + "\n")
    return path


def _pairs(path: Path, mass: str) -> np.ndarray:
    ours = compute_modes(read_model(path), 20, mass=mass)["frequency"].values
    return ours[np.asarray(CYLINDER_PAIRS) - 1]


def test_cylinder_generator_reproduces_the_dakota_deck(tmp_path):
    """The re-meshing helper at 16 x 20 is the Dakota deck (its grids have 6 printed digits)."""
    deck = read_model(DATA / CYLINDER[0])
    ours = compute_modes(deck, 20, mass="lumped")["frequency"].values
    again = compute_modes(read_model(_cylinder_deck(tmp_path / "c16.bdf", 16, 20)), 20,
                          mass="lumped")["frequency"].values
    np.testing.assert_allclose(again[6:], ours[6:], rtol=1e-4)


def test_cylinder_known_pairs_are_circumferential_discretisation(tmp_path):
    """The n = 2 pairs converge with facets around, hardly with elements along, and MSC 70.7's
    16-facet values lie between our 16- and 64-facet ones (its QUAD4 has the smaller coarse-mesh
    error, ours the larger; neither is converged).

    Measured (consistent mass, Hz): 16 x 20 (the deck) 5706.9 / 6869.9 / 9062.4; 16 x 40 5704.6 /
    6843.6 / 8959.7; 64 x 20 5320.8 / 6432.8 / 8553.9; MSC 70.7 at 16 x 20 5564.1 / 6716.7 / 8881.0.
    """
    coarse = _pairs(DATA / CYLINDER[0], "consistent")
    along = _pairs(_cylinder_deck(tmp_path / "c16x40.bdf", 16, 40), "consistent")
    around = _pairs(_cylinder_deck(tmp_path / "c64x20.bdf", 64, 20), "consistent")
    drop_around = 1.0 - around / coarse
    drop_along = 1.0 - along / coarse
    assert np.all(drop_around > 0.05), drop_around                   # 5.6-6.8 %
    assert np.all(np.abs(drop_along) < 0.25 * drop_around), drop_along  # 0.04-1.1 %
    msc = np.asarray(CYLINDER_PAIRS_MSC)
    assert np.all((around < msc) & (msc < coarse)), (around, msc, coarse)


@needs_mystran
def test_cylinder_known_pairs_against_mystran(tmp_path):
    """An independent flat-shell element differs from ours on the n = 2 pairs as MSC's does, and
    the difference shrinks with facets around: it is discretisation, not a modelling defect.

    Same deck, lumped mass both (MYSTRAN ignores COUPMASS). Measured (Hz): 16 x 20 ours 5566.0 /
    6657.3 / 8691.3, MYSTRAN's MIN4 5443.3 / 6531.7 / 8561.2 (+2.3 / +1.9 / +1.5 %, against +2.6 /
    +2.3 / +2.0 % for ours consistent vs MSC's QUAD4); first pair at 64 x 20 ours 5300.6, MYSTRAN
    5255.0 (+0.9 %). MYSTRAN's Lanczos returns a few spurious low roots on the refined free-free
    mesh, so each pair is matched by nearest frequency.
    """
    def nearest(theirs, targets):
        return np.array([theirs[np.argmin(np.abs(theirs - t))] for t in targets])

    coarse = _cylinder_deck(tmp_path / "c16.bdf", 16, 20)
    ours = _pairs(coarse, "lumped")
    gap = ours / nearest(run_mystran(coarse), ours) - 1.0
    assert np.all((0.01 < gap) & (gap < 0.03)), gap
    fine = _cylinder_deck(tmp_path / "c64.bdf", 64, 20)
    ours_fine = _pairs(fine, "lumped")[0]
    gap_fine = ours_fine / nearest(run_mystran(fine), [ours_fine])[0] - 1.0
    assert 0.0 < gap_fine < 0.5 * gap[0], (gap, gap_fine)


def test_windy_fwt_sections_and_mass_by_hand():
    """PBEAML BAR sections become PBEAM properties (A = b h, I1 = b h^3/12, I2 = h b^3/12, Roark's
    J), and the assembled mass is the deck's by hand: eight panel and eight cable CONM2s, the
    masses on the three RBE3 reference grids (hinge 0.207 + 0.040 + 0.106, wingtip hinge 0.176 +
    0.010 + 0.006, tip 0.0876) and the spar (MAT1 1: 8000 kg/m^3, 0.03 x 0.005 m, 0.875 m long);
    the hinge and tip beams are massless (MAT1 3, RHO = 0)."""
    model = read_model(DATA / FWT)
    spar = model.properties[1].fields
    b, h = 0.03, 0.005
    assert model.properties[1].card == "PBEAM"
    np.testing.assert_allclose([spar["A"], spar["I1"], spar["I2"]],
                               [b * h, b * h ** 3 / 12, h * b ** 3 / 12], rtol=1e-12)
    j = b * h ** 3 * (1 / 3 - 0.21 * (h / b) * (1 - h ** 4 / (12 * b ** 4)))   # Roark, a = b
    assert spar["J"] == pytest.approx(j, rel=1e-12)
    assert sorted(r.eid for r in model.rigid if r.card == "RBE3") == [501, 502, 503]
    total = 8 * 0.102 + 8 * 0.040 + (0.207 + 0.040 + 0.106) + (0.176 + 0.010 + 0.006) + 0.0876 \
        + 8000.0 * b * h * 0.875
    assert mass_properties(model).mass == pytest.approx(total, rel=1e-12)


def _fwt_mystran_deck(folder: Path) -> Path:
    """The WINDY deck as MYSTRAN 18 reads it, in one file (SOL 103, DISP(PLOT), MPC = 1).

    Equivalent rewrites: PBEAML -> PBAR with the same section and CBEAM -> CBAR (no warping, no
    taper: :func:`tests.pipeline.diagnose.truth.windy.as_bars`), the coincident hinge grids 208/209
    (tied 123456 by RBE2 300, same CD) merged, PLOTEL/DMI/output PARAMs dropped. MYSTRAN's RBE3
    ignores rotational independent components (measured on a cantilever with an RBE3 on three
    grids: its frequencies are the same with C = 123 and C = 123456, ours differ by up to 0.5 %),
    and the deck's RBE3s rest on collinear grids with C = 123456, where MYSTRAN's RMM
    factorisation then fails. They are given to MYSTRAN as the MPC equations u_ref = G u_ind of
    Nastran's definition (G from :func:`structures.rigid.element_constraints`, whose weighting is
    checked by hand in tests/structures/test_rigid.py); frames, offsets, sections and the RBE3-
    borne masses are then MYSTRAN's own.
    """
    from pyNastran.bdf.bdf import BDF

    model = read_model(DATA / FWT)
    bdf = BDF(debug=None)
    bdf.read_bdf(str(DATA / FWT), xref=False)
    as_bars(bdf)
    merged = {209: 208}
    del bdf.rigid_elements[300], bdf.nodes[209]
    bdf.elements[2190].ga = 208
    mpcs = []
    for elem in (r for r in model.rigid if r.card == "RBE3"):
        del bdf.rigid_elements[elem.eid]
        dep, indep, g = element_constraints(model.grids, elem)
        for d, row in zip(dep, g):
            terms = [int(model.grids.ids[d // 6]), int(d % 6 + 1), -1.0]
            for c, coef in zip(indep, row):
                gid = int(model.grids.ids[c // 6])
                terms += [merged.get(gid, gid), int(c % 6 + 1), float(coef)] if coef else []
            triples = [terms[i:i + 3] for i in range(0, len(terms), 3)]
            fields = [1, *triples[0], *(triples[1] if len(triples) > 1 else []), None]
            for k in range(2, len(triples), 2):                 # MPC continuations: 2 terms each
                pair = sum(triples[k:k + 2], [])
                fields += [None, *pair] + [None] * (7 - len(pair))
            mpcs.append(card("MPC", *fields))
    bdf.dmi.clear()
    bdf.plotels.clear()
    for name in ("SNORM", "PRTMAXIM", "POST"):
        bdf.params.pop(name, None)
    bdf.write_bdf(str(folder / "bulk.tmp"), enddata=False, size=8)
    bulk = (folder / "bulk.tmp").read_text().split("\nBEGIN BULK\n", 1)[1]
    deck = folder / "windy_mpc.bdf"
    deck.write_text("SOL 103\nCEND\nSPC = 3\nMPC = 1\nMETHOD = 1\nDISP(PLOT) = ALL\nBEGIN BULK\n"
                    + bulk + "\n".join(mpcs) + "\nENDDATA\n")
    return deck


@needs_mystran
def test_windy_fwt_matches_mystran(tmp_path):
    """10 modes of the cantilevered WINDY wing (1.97-80.0 Hz) against MYSTRAN, lumped mass both
    (the deck has no COUPMASS). Measured: within 7.2e-5 (8-character fields of the MYSTRAN copy);
    1 % is the project's tolerance without an F06."""
    theirs = run_mystran(_fwt_mystran_deck(tmp_path))
    ours = compute_modes(read_model(DATA / FWT), 10)["frequency"].values
    assert ours[0] == pytest.approx(1.9664, rel=1e-3)
    np.testing.assert_allclose(ours, theirs, rtol=0.01)
    assert np.max(np.abs(ours / theirs - 1.0)) < 5e-4


@pytest.mark.parametrize("deck", [GOLAND[0], BAR72[0], CYLINDER[0], FWT])
def test_pipeline_modes_runs(deck, capsys):
    assert main(["modes", str(DATA / deck), "--nmodes", "8"]) == 0
    assert "frequency" in capsys.readouterr().out


@pytest.mark.skipif("pipeline.cmd_check" not in COMMANDS, reason="no `pipeline check` command")
@pytest.mark.parametrize("deck", [GOLAND[0], BAR72[0], CYLINDER[0], FWT])
def test_pipeline_check_runs(deck, capsys):
    assert main(["check", str(DATA / deck), "--nmodes", "8"]) == 0
    out = capsys.readouterr().out
    assert "UNSUPPORTED" not in out
    assert "mechanisms: none" in out
