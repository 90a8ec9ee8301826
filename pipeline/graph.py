"""The stage graph: stages that declare their inputs, a manifest that proves their outputs.

A :class:`Stage` declares what it reads -- settings (a case section, any JSON-able value), files
(decks, GVT files) and the outputs of the stages named in ``after`` -- and computes its outputs
into a staging folder. Its **fingerprint** is the SHA-256 of all of it: the settings, the content
of every input file, the recorded content hash of every upstream output and the version of the
code (:func:`source_version`: a hash of the project's sources). A change anywhere therefore
reruns exactly the stages downstream of it, and a stage whose upstream result came out the same
(a rerun that reproduced identical bytes) is not rerun.

The **manifest** (``manifest.json`` in the run folder) records per stage its fingerprint, the
SHA-256 of every output file and the seconds its computation took. A stage is *done* when its
fingerprint matches and every recorded output is present with the recorded hash; a damaged or
partial output (a truncated file, a file edited by hand) is detected, reported with a warning and
recomputed.

Atomicity: a stage computes into ``.staging/<stage>/`` inside the run folder; only when its
compute returns are the files moved into place (one rename each) and then the manifest is
rewritten (atomically). A run killed at any instant leaves at worst a stale staging folder (removed
by the next run) or outputs without a matching manifest entry (recomputed by the next run).

Statuses (:meth:`Graph.status`): ``done``; ``stale`` (computed before, but an input changed, an
upstream stage is not done, or an output is damaged); ``missing`` (never computed).
"""
from __future__ import annotations

import fnmatch
import functools
import hashlib
import json
import os
import shutil
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from structures.common.errors import InputError
from structures.common.files import write_json

MANIFEST = "manifest.json"
STAGING = ".staging"
_CHUNK = 1 << 20


def file_hash(path: Path) -> str:
    """SHA-256 of a file's content (hex)."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(_CHUNK), b""):
            digest.update(block)
    return digest.hexdigest()


@functools.lru_cache(maxsize=None)
def source_version(*packages: str) -> str:
    """SHA-256 of the Python sources of ``packages`` (folders beside this package's parent):
    changes with any edit of the code, so a fixed kernel recomputes what it computed."""
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


@dataclass(frozen=True)
class Stage:
    """One step of a run.

    Attributes
    ----------
    name : str
        Unique, path-like (``stage0/modes/baseline``); also names the staging folder.
    compute : callable(StageContext) -> str or None
        Writes the stage's outputs below ``ctx.folder`` (paths relative to it are the run-folder
        paths of the outputs, e.g. ``ctx.folder / "stage0/baseline/modes.nc"``); returns a
        one-line summary for the log.
    settings : JSON-able
        The settings the stage reads (case sections as dicts, numbers, strings).
    files : tuple of Path
        Input files whose content the stage reads.
    after : tuple of str
        Stages whose outputs the stage reads (their recorded output hashes enter the fingerprint).
    """

    name: str
    compute: Callable
    settings: Any = None
    files: tuple = ()
    after: tuple = ()


@dataclass
class StageContext:
    """What a running stage sees: its staging folder, the run folder and its upstream outputs."""

    stage: Stage
    folder: Path
    run_dir: Path
    upstream: dict = field(default_factory=dict)

    def output(self, relpath: str | os.PathLike) -> Path:
        """The staging path of output ``relpath`` (run-folder relative), parents created."""
        path = self.folder / relpath
        path.parent.mkdir(parents=True, exist_ok=True)
        return path

    def input(self, stage: str) -> list[Path]:
        """The run-folder paths of the outputs of upstream stage ``stage``."""
        if stage not in self.upstream:
            raise KeyError(f"stage {self.stage.name} reads {stage} but does not declare it in after")
        return self.upstream[stage]


class Graph:
    """Stages of a run folder with their manifest.

    Parameters
    ----------
    run_dir : path
        The run folder (created if missing).
    stages : iterable of Stage
        In an order where every stage comes after those it names in ``after``.
    log : callable(str)
        One line per stage event.
    code : str
        Version of the code that computes the stages (e.g. :func:`source_version`): part of every
        fingerprint, so results computed by other code are not reused.
    """

    def __init__(self, run_dir, stages=(), log=print, code: str = ""):
        self.dir = Path(run_dir)
        self.log = log
        self.code = code
        self.stages: dict[str, Stage] = {}
        self.manifest_path = self.dir / MANIFEST
        self.manifest = self._read_manifest()
        self.forced: set[str] = set()       # forced stages not yet rerun
        self._forced_all: set[str] = set()  # every forced stage, rerun or not: their downstream
        for stage in stages:
            self.add(stage)

    # ----------------------------------------------------------------------------- building
    def add(self, stage: Stage) -> Stage:
        """Register ``stage`` (its upstream stages must already be registered)."""
        if stage.name in self.stages:
            raise ValueError(f"stage {stage.name} is registered twice")
        unknown = [s for s in stage.after if s not in self.stages]
        if unknown:
            raise ValueError(f"stage {stage.name} comes after unregistered stages {unknown}")
        self.stages[stage.name] = stage
        if any(s in self._forced_all for s in stage.after):
            self.forced.add(stage.name)
            self._forced_all.add(stage.name)
        return stage

    def force(self, pattern: str, valid=None) -> list[str]:
        """Rerun the stages matching ``pattern`` (a name, a name prefix such as ``stage1`` or a
        glob) and every stage after them, including stages registered later.

        ``valid`` lists the names the pattern may match (default: the registered stages)."""
        names = list(valid if valid is not None else self.stages)
        hit = [n for n in names if n == pattern or n.startswith(pattern.rstrip("/") + "/")
               or fnmatch.fnmatchcase(n, pattern)]
        if not hit:
            raise InputError(f"--from {pattern}: no such stage; valid: {', '.join(names)}.")
        self.forced |= set(hit)
        self._forced_all |= set(hit)
        for name, stage in self.stages.items():
            if any(s in self._forced_all for s in stage.after):
                self.forced.add(name)
                self._forced_all.add(name)
        return hit

    # ----------------------------------------------------------------------------- manifest
    def _read_manifest(self) -> dict:
        if not self.manifest_path.exists():
            return {}
        try:
            manifest = json.loads(self.manifest_path.read_text())
        except (ValueError, UnicodeDecodeError):
            manifest = None
        if not (isinstance(manifest, dict) and all(
                isinstance(e, dict) and isinstance(e.get("fingerprint"), str)
                and isinstance(e.get("outputs"), dict) for e in manifest.values())):
            raise InputError(f"file {self.manifest_path}: the run manifest is damaged. Fix: delete "
                             "it (every stage then runs again) or give another --out folder.")
        return manifest

    def fingerprint(self, stage: Stage) -> str:
        """SHA-256 of the code version, the stage's settings, input file contents and upstream
        output hashes (the upstream stages must be done)."""
        record = {"stage": stage.name,
                  "code": self.code,
                  "settings": stage.settings,
                  "files": [[Path(f).name, file_hash(Path(f))] for f in stage.files],
                  "after": {s: self.manifest[s]["outputs"] for s in stage.after}}
        text = json.dumps(record, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()

    def _damaged(self, name: str) -> list[str]:
        """Recorded outputs of ``name`` that are missing or differ from their recorded hash."""
        bad = []
        for rel, digest in self.manifest[name]["outputs"].items():
            path = self.dir / rel
            if not path.is_file() or file_hash(path) != digest:
                bad.append(rel)
        return bad

    def state(self, name: str, done: set) -> tuple[str, str]:
        """(status, reason) of a registered stage, given the set of stages already done."""
        stage = self.stages[name]
        entry = self.manifest.get(name)
        if entry is None:
            return "missing", "never computed"
        if name in self.forced:
            return "stale", "forced by --from"
        pending = [s for s in stage.after if s not in done]
        if pending:
            return "stale", f"upstream {pending[0]} is not done"
        if entry["fingerprint"] != self.fingerprint(stage):
            return "stale", "an input changed"
        bad = self._damaged(name)
        if bad:
            return "stale", f"output {bad[0]} is missing or damaged"
        return "done", ""

    def status(self) -> list[tuple[str, str, str]]:
        """(stage, status, reason) of every registered stage, in order."""
        done, out = set(), []
        for name in self.stages:
            status, reason = self.state(name, done)
            if status == "done":
                done.add(name)
            out.append((name, status, reason))
        return out

    # ----------------------------------------------------------------------------- running
    def run(self, name: str) -> list[Path]:
        """Bring stage ``name`` up to date (its upstream stages must be up to date); returns the
        run-folder paths of its outputs."""
        stage = self.stages[name]
        done = {s for s in stage.after}
        status, reason = self.state(name, done)
        if status == "done":
            self.log(f"[{name}] up to date, skipped")
        else:
            if reason.startswith("output"):
                warnings.warn(f"{self.dir / MANIFEST}: stage {name}: {reason}; recomputing it")
            self._compute(stage)
        return [self.dir / rel for rel in self.manifest[name]["outputs"]]

    def _compute(self, stage: Stage) -> None:
        staging = self.dir / STAGING / stage.name
        shutil.rmtree(staging, ignore_errors=True)
        staging.mkdir(parents=True)
        upstream = {s: [self.dir / rel for rel in self.manifest[s]["outputs"]] for s in stage.after}
        fingerprint = self.fingerprint(stage)   # of the inputs as the compute starts reading them
        try:
            start = time.perf_counter()
            note = stage.compute(StageContext(stage, staging, self.dir, upstream))
            seconds = time.perf_counter() - start
            written = sorted(p for p in staging.rglob("*") if p.is_file())
            outputs = {p.relative_to(staging).as_posix(): file_hash(p) for p in written}
            old = self.manifest.pop(stage.name, None)
            write_json(self.manifest, self.manifest_path)   # the old entry is void from here on
            for path in written:
                target = self.dir / path.relative_to(staging)
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(path, target)
            for rel in set(old["outputs"] if old else ()) - set(outputs):
                (self.dir / rel).unlink(missing_ok=True)
            self.manifest[stage.name] = {"fingerprint": fingerprint, "outputs": outputs,
                                         "seconds": round(seconds, 3)}
            write_json(self.manifest, self.manifest_path)
            self.log(f"[{stage.name}] {note or 'done'}")
        finally:
            shutil.rmtree(staging, ignore_errors=True)
            self._prune(staging.parent)
        self.forced.discard(stage.name)

    def _prune(self, folder: Path) -> None:
        """Remove empty staging folders up to and including ``.staging``."""
        root = self.dir / STAGING
        while folder.is_relative_to(root) and folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()
            if folder == root:
                break
            folder = folder.parent

    def clean_staging(self) -> None:
        """Remove what an interrupted run left in the staging area."""
        shutil.rmtree(self.dir / STAGING, ignore_errors=True)
