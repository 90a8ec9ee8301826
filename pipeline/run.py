"""``pipeline run``: the stages of a case, resumable, each written atomically to the run folder.

A stage's outputs are recorded in ``manifest.json`` together with a fingerprint of its inputs
(deck files and settings); a re-run skips every stage whose fingerprint still matches, so an
interrupted run resumes from the last finished stage. A failed or interrupted run keeps the outputs
of its finished stages (recorded in the manifest) and removes every other file it wrote.

:func:`configuration_modes` and :func:`configuration_flutter` are the computations of the modes
and flutter stages; ``pipeline flutter CASE.toml`` calls the same two functions, so it cannot
disagree with ``pipeline run``.
"""
from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np

from flutter.run import read_flutter_requests, run_flutter
from pipeline.case import Case, Configuration, FlutterSettings
from pipeline.report import write_report
from pipeline.stage import running
from structures.assembly import assemble
from structures.bdf import read_model
from structures.common.nastran import read_pynastran
from structures.correlation import CorrelationSettings, correlate
from structures.correlation_plots import save_correlation_figures
from structures.common.errors import InputError
from structures.gvt import load_gvt
from structures.massprops import compare_mass_properties, mass_properties
from structures.modal import compute_modes
from structures.modes import read_modes, write_modes
from structures.common.files import (check_output, read_dataset, staged_folder, write_dataset,
                               write_json)

EXAMPLE_CASE = Path(__file__).resolve().parents[1] / "data" / "bah_wing" / "case.toml"


def _deck_fingerprint(deck: Path) -> str:
    """Hash of the deck and every file beside it that it may INCLUDE."""
    digest = hashlib.sha256()
    for path in sorted(Path(deck).parent.glob("*")):
        if path.is_file() and path.suffix.lower() in (".bdf", ".dat", ".inc", ".nas", ".blk"):
            digest.update(path.name.encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


class Run:
    """A run folder with its manifest of finished stages."""

    def __init__(self, out_dir):
        self.dir = check_output(out_dir, folder=True)
        self.created = [p for p in (self.dir, *self.dir.parents) if not p.exists()]
        self.dir.mkdir(parents=True, exist_ok=True)
        self.before = {p for p in self.dir.rglob("*")}
        self.manifest_path = self.dir / "manifest.json"
        self.manifest = self._read_manifest()

    def _read_manifest(self) -> dict:
        if not self.manifest_path.exists():
            return {}
        try:
            manifest = json.loads(self.manifest_path.read_text())
        except (ValueError, UnicodeDecodeError) as exc:
            manifest = exc
        if not (isinstance(manifest, dict) and all(
                isinstance(e, dict) and {"fingerprint", "outputs"} <= set(e)
                for e in manifest.values())):
            raise InputError(f"file {self.manifest_path}: the run manifest is damaged. Fix: delete "
                             "it (every stage then runs again) or give another --out folder.")
        return manifest

    def done(self, stage: str, fingerprint: str) -> bool:
        entry = self.manifest.get(stage)
        return bool(entry and entry["fingerprint"] == fingerprint and
                    all((self.dir / f).exists() for f in entry["outputs"]))

    def finish(self, stage: str, fingerprint: str, outputs) -> None:
        self.manifest[stage] = {"fingerprint": fingerprint, "outputs": [str(o) for o in outputs]}
        write_json(self.manifest, self.manifest_path)

    def discard_unfinished(self) -> None:
        """Remove what this run wrote outside finished stages (and the folders it created, if
        empty)."""
        kept = {self.dir / f for entry in self.manifest.values() for f in entry["outputs"]}
        kept |= {self.manifest_path} if self.manifest else set()
        kept |= {folder for path in kept for folder in path.parents}
        for path in sorted(set(self.dir.rglob("*")) - self.before - kept, reverse=True):
            if path.is_dir():
                shutil.rmtree(path, ignore_errors=True)
            elif path.exists():
                path.unlink()
        for folder in self.created:
            if folder.is_dir() and not any(folder.iterdir()):
                folder.rmdir()


def configuration_modes(config: Configuration, nmodes: int | None = None) -> tuple:
    """Modes and mass properties of one configuration (its deck, nmodes and mass option).

    Returns
    -------
    (xarray.Dataset, structures.massprops.MassProperties)
        The modes (DESIGN.md section 6) and the mass properties.
    """
    model = read_model(config.deck)
    system = assemble(model, config.mass)
    modes = compute_modes(model, nmodes or config.nmodes, mass=config.mass, system=system)
    return modes, mass_properties(model, m_basic=system.m_basic)


def configuration_flutter(config: Configuration, settings: FlutterSettings, modes, out_dir,
                          flutter_ids=None, units: str | None = None) -> dict:
    """GAFs and flutter of one configuration on ``modes`` with the case's ``[flutter]`` settings.

    ``flutter_ids`` (a command-line override) replaces ``settings.flutter_ids``; both empty: the
    deck's FMETHOD selection. ``units`` is the case's unit system. Returns :func:`flutter.run.run_flutter`'s dict; writes ``out_dir``.
    """
    return run_flutter(config.deck, out_dir, modes=modes, kernel=settings.kernel,
                       flutter_ids=list(flutter_ids or settings.flutter_ids) or None, units=units)


def check_flutter_requests(case: Case, flutter_ids=None) -> None:
    """Before any computation: every configuration's deck defines the FLUTTER cards (and their
    FLFACT lists) that the case's ``[flutter]`` (or the ``flutter_ids`` override) selects.

    Raises
    ------
    InputError
        Naming the deck, the FLUTTER id and the fix (:func:`flutter.run.read_flutter_requests`).
    """
    if case.flutter is None and not flutter_ids:
        return
    settings = case.flutter or FlutterSettings()
    for config in case.configurations:
        read_flutter_requests(read_pynastran(config.deck), str(config.deck),
                              list(flutter_ids or settings.flutter_ids) or None)


def modes_stage(run: Run, config: Configuration, log=print) -> dict:
    """Modes and mass properties of one configuration."""
    stage = f"modes/{config.name}"
    fp = hashlib.sha256(json.dumps([_deck_fingerprint(config.deck), config.nmodes, config.mass])
                        .encode()).hexdigest()
    modes_file = Path(config.name) / "modes.nc"
    mass_file = Path(config.name) / "mass_properties.nc"
    if run.done(stage, fp):
        log(f"[{stage}] up to date, skipped")
    else:
        log(f"[{stage}] reading {config.deck}")
        modes, props = configuration_modes(config)
        write_modes(modes, run.dir / modes_file)
        write_dataset(props.to_dataset(), run.dir / mass_file)
        run.finish(stage, fp, [modes_file, mass_file])
        log(f"[{stage}] {modes.sizes['mode']} modes, {modes['frequency'].values[-1]:.4g} Hz highest")
    return {"modes": read_modes(run.dir / modes_file),
            "mass_properties": read_dataset(run.dir / mass_file)}


def correlation_stage(run: Run, config: Configuration, modes, log=print) -> dict:
    """Correlation of one configuration's modes with its GVT (paper Tables 1-4, Figs. 7-8).

    Writes ``<config>/correlation.nc`` and the MAC / orthogonality / cross-orthogonality maps and
    frequency bars ``<config>/correlation/*.png``.
    """
    stage = f"correlation/{config.name}"
    fp = hashlib.sha256(json.dumps([_deck_fingerprint(config.deck), config.nmodes, config.mass,
                                    hashlib.sha256(Path(config.gvt).read_bytes()).hexdigest(),
                                    sorted(config.measured_mass.items())]).encode()).hexdigest()
    corr_file = Path(config.name) / "correlation.nc"
    if run.done(stage, fp):
        log(f"[{stage}] up to date, skipped")
    else:
        log(f"[{stage}] {config.gvt}")
        corr = correlate(modes, load_gvt(config.gvt), CorrelationSettings())
        if config.measured_mass:
            props = mass_properties(read_model(config.deck))
            comparison = compare_mass_properties(props, config.measured_mass)
            corr = corr.merge(comparison.rename({v: f"mass_{v}" for v in comparison.data_vars}))
        write_dataset(corr, run.dir / corr_file)
        figures = save_correlation_figures(corr, run.dir / config.name / "correlation")
        run.finish(stage, fp, [corr_file, *(f.relative_to(run.dir) for f in figures)])
        worst = float(np.nanmax(np.abs(corr["frequency_error"].values)))
        log(f"[{stage}] {corr.sizes['test_mode']} test modes paired, largest frequency error "
            f"{worst:.2f} %")
    entry = run.manifest[stage]
    return {"dataset": read_dataset(run.dir / corr_file),
            "figures": [f for f in entry["outputs"] if f.endswith(".png")]}


def flutter_stage(run: Run, config: Configuration, settings: FlutterSettings, modes,
                  log=print, units: str | None = None) -> dict:
    """GAFs and flutter of one configuration from its deck's FLUTTER cards (on the stage's modes).

    Writes the outputs of :func:`flutter.results.write_flutter` (``flutter.nc``, ``summary.json``,
    ``flutter_summary.txt``, V-g / V-f figures ``vg_<case>.png``) and ``gaf.nc``, ``modes.nc`` to
    ``<config>/flutter/``.
    """
    stage = f"flutter/{config.name}"
    fp = hashlib.sha256(json.dumps([_deck_fingerprint(config.deck), config.nmodes, config.mass,
                                    settings.kernel, list(settings.flutter_ids), units]).encode()
                    ).hexdigest()
    folder = Path(config.name) / "flutter"
    if run.done(stage, fp):
        log(f"[{stage}] up to date, skipped")
    else:
        log(f"[{stage}] GAFs ({settings.kernel} kernel) and flutter")
        with staged_folder(run.dir / folder) as staged:
            result = configuration_flutter(config, settings, modes, staged, units=units)
            written = sorted(p.name for p in Path(staged).iterdir() if p.is_file())
        outputs = [folder / name for name in written]
        run.finish(stage, fp, outputs)
        flutter = [c for c in result["summary"] if c["kind"] == "flutter"]
        log(f"[{stage}] {len(flutter)} flutter crossing(s)" +
            (f", lowest {min(c['velocity'] for c in flutter):.5g} at "
             f"{min(flutter, key=lambda c: c['velocity'])['frequency']:.4g} Hz" if flutter else ""))
    entry = run.manifest[stage]
    summary = json.loads((run.dir / folder / "summary.json").read_text())
    return {"summary": summary, "figures": [f for f in entry["outputs"] if f.endswith(".png")]}


def run_case(case: Case, out_dir, log=print) -> Path:
    """Run every stage of a case into ``out_dir``; returns the HTML report's path."""
    check_flutter_requests(case)
    run = Run(out_dir)
    results = {}
    try:
        for config in case.configurations:
            with running(f"modes/{config.name}"):
                results[config.name] = modes_stage(run, config, log)
            if config.gvt is not None:
                with running(f"correlation/{config.name}"):
                    results[config.name]["correlation"] = correlation_stage(
                        run, config, results[config.name]["modes"], log)
            if case.flutter is not None:
                with running(f"flutter/{config.name}"):
                    results[config.name]["flutter"] = flutter_stage(
                        run, config, case.flutter, results[config.name]["modes"], log, case.units)
        with running("report"):
            report = write_report(case, results, run.dir)
    except BaseException:
        run.discard_unfinished()
        raise
    log(f"report: {report}")
    return report
