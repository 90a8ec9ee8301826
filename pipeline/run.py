"""``pipeline run``: the stages of a case, resumable, each written atomically to the run folder.

A stage's outputs are recorded in ``manifest.json`` together with a fingerprint of its inputs
(deck files and settings); a re-run skips every stage whose fingerprint still matches, so an
interrupted run resumes from the last finished stage.
"""
from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

from pipeline.case import Case, Configuration
from pipeline.report import write_report
from structures.assembly import assemble
from structures.bdf import read_model
from structures.massprops import mass_properties
from structures.modal import compute_modes
from structures.modes import read_modes, write_modes
from structures.netcdf import read_dataset, write_dataset

EXAMPLE_CASE = Path(__file__).resolve().parents[1] / "data" / "bah_wing" / "case.toml"


def _write_json(obj, path: Path) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    with os.fdopen(fd, "w") as fh:
        json.dump(obj, fh, indent=2, default=str)
    os.replace(tmp, path)


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
        self.dir = Path(out_dir)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.manifest_path = self.dir / "manifest.json"
        self.manifest = (json.loads(self.manifest_path.read_text())
                         if self.manifest_path.exists() else {})

    def done(self, stage: str, fingerprint: str) -> bool:
        entry = self.manifest.get(stage)
        return bool(entry and entry["fingerprint"] == fingerprint and
                    all((self.dir / f).exists() for f in entry["outputs"]))

    def finish(self, stage: str, fingerprint: str, outputs) -> None:
        self.manifest[stage] = {"fingerprint": fingerprint, "outputs": [str(o) for o in outputs]}
        _write_json(self.manifest, self.manifest_path)


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
        model = read_model(config.deck)
        system = assemble(model, config.mass)
        modes = compute_modes(model, config.nmodes, mass=config.mass, system=system)
        props = mass_properties(model, m_basic=system.m_basic)
        write_modes(modes, run.dir / modes_file)
        write_dataset(props.to_dataset(), run.dir / mass_file)
        run.finish(stage, fp, [modes_file, mass_file])
        log(f"[{stage}] {modes.sizes['mode']} modes, {modes['frequency'].values[-1]:.4g} Hz highest")
    return {"modes": read_modes(run.dir / modes_file),
            "mass_properties": read_dataset(run.dir / mass_file)}


def run_case(case: Case, out_dir, log=print) -> Path:
    """Run every stage of a case into ``out_dir``; returns the HTML report's path."""
    run = Run(out_dir)
    results = {config.name: modes_stage(run, config, log) for config in case.configurations}
    report = write_report(case, results, run.dir)
    log(f"report: {report}")
    return report
