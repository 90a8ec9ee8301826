"""The stage graph (pipeline.graph) on toy stages: tiny computes that write text files, no physics.

References are by construction: a stage's output is a known function of its settings, input file
and upstream output, and each compute counts its calls, so "rerun" and "not rerun" are observed,
not inferred. The kill in the manifest-writing window is a real process exit (``os._exit``, no
``finally`` runs) between the manifest write and the renames of the staged outputs.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from collections import Counter
from pathlib import Path

import pytest

from pipeline.graph import MANIFEST, STAGING, Graph, Stage, file_hash
from structures.common.errors import InputError

ROOT = Path(__file__).resolve().parents[2]


def _quiet(line: str) -> None:
    """Graph log sink."""


class Toy:
    """Three toy stages ``s0/a`` -> ``s0/b`` -> ``s1/c`` and an independent ``other``.

    ``s0/a`` writes ``a.txt`` = its settings' ``text`` + the input file's content; ``s0/b`` writes
    ``b.txt`` = upper-cased ``a.txt``; ``s1/c`` writes ``c.txt`` = ``b.txt`` reversed; ``other``
    writes ``other.txt`` from its settings. ``calls`` counts the computes per stage.
    """

    def __init__(self, folder: Path):
        self.run_dir = folder / "run"
        self.input = folder / "input.dat"
        self.input.write_text("data-1\n")
        self.settings = {"a": {"text": "alpha"}, "other": {"text": "x"}}
        self.calls: Counter = Counter()
        self.fail: set[str] = set()

    def _a(self, ctx):
        self.calls["s0/a"] += 1
        text = ctx.stage.settings["text"] + ":" + self.input.read_text()
        ctx.output("a.txt").write_text(text)
        if "s0/a" in self.fail:
            ctx.output("partial.txt").write_text("half")
            raise RuntimeError("toy failure in s0/a")
        return "a written"

    def _b(self, ctx):
        self.calls["s0/b"] += 1
        (a,) = ctx.input("s0/a")
        ctx.output("b.txt").write_text(a.read_text().upper())

    def _c(self, ctx):
        self.calls["s1/c"] += 1
        (b,) = ctx.input("s0/b")
        ctx.output("sub/c.txt").write_text(b.read_text()[::-1])

    def _other(self, ctx):
        self.calls["other"] += 1
        ctx.output("other.txt").write_text(ctx.stage.settings["text"])

    def stages(self) -> list[Stage]:
        return [Stage("s0/a", self._a, settings=self.settings["a"], files=(self.input,)),
                Stage("s0/b", self._b, after=("s0/a",)),
                Stage("s1/c", self._c, after=("s0/b",)),
                Stage("other", self._other, settings=self.settings["other"])]

    def graph(self, force: str | None = None, valid=None) -> Graph:
        """A fresh Graph on the run folder (as a new process would build it)."""
        graph = Graph(self.run_dir, log=_quiet)
        if force is not None:   # as pipeline.run does: before the stages are registered
            graph.force(force, valid=valid or [s.name for s in self.stages()])
        for stage in self.stages():
            graph.add(stage)
        return graph

    def run(self, force: str | None = None) -> Graph:
        graph = self.graph(force)
        for name in graph.stages:
            graph.run(name)
        return graph


@pytest.fixture
def toy(tmp_path) -> Toy:
    return Toy(tmp_path)


def _fingerprints(toy: Toy) -> dict[str, str]:
    """Fingerprint of every stage, computed by a fresh Graph on the current manifest."""
    graph = toy.graph()
    return {name: graph.fingerprint(stage) for name, stage in graph.stages.items()}


def _manifest(run_dir: Path) -> dict:
    return json.loads((run_dir / MANIFEST).read_text())


# ------------------------------------------------------------------------------- fingerprints
def test_outputs_and_manifest_of_a_first_run(toy):
    toy.run()
    assert (toy.run_dir / "a.txt").read_text() == "alpha:data-1\n"
    assert (toy.run_dir / "b.txt").read_text() == "ALPHA:DATA-1\n"
    assert (toy.run_dir / "sub" / "c.txt").read_text() == "\n1-ATAD:AHPLA"
    manifest = _manifest(toy.run_dir)
    assert list(manifest) == ["s0/a", "s0/b", "s1/c", "other"]
    assert manifest["s1/c"]["outputs"] == {"sub/c.txt": file_hash(toy.run_dir / "sub" / "c.txt")}
    assert all(entry["seconds"] >= 0.0 for entry in manifest.values())
    assert not (toy.run_dir / STAGING).exists()
    assert toy.calls == Counter({"s0/a": 1, "s0/b": 1, "s1/c": 1, "other": 1})
    toy.run()
    assert toy.calls == Counter({"s0/a": 1, "s0/b": 1, "s1/c": 1, "other": 1})


def test_fingerprint_follows_settings_not_unrelated_stages(toy):
    toy.run()
    before = _fingerprints(toy)
    toy.settings["other"] = {"text": "y"}
    after = _fingerprints(toy)
    assert after["other"] != before["other"]
    assert {n: after[n] for n in ("s0/a", "s0/b", "s1/c")} == \
           {n: before[n] for n in ("s0/a", "s0/b", "s1/c")}
    toy.settings["a"] = {"text": "beta"}
    assert _fingerprints(toy)["s0/a"] != before["s0/a"]
    toy.settings["a"] = {"text": "alpha"}
    assert _fingerprints(toy)["s0/a"] == before["s0/a"]


def test_fingerprint_follows_input_file_content_not_its_time_or_neighbours(toy):
    toy.run()
    before = _fingerprints(toy)
    (toy.input.parent / "unrelated.dat").write_text("not an input")
    os.utime(toy.input, (1.0e9, 1.0e9))
    assert _fingerprints(toy) == before
    toy.input.write_text("data-2\n")
    after = _fingerprints(toy)
    assert after["s0/a"] != before["s0/a"]
    assert after["other"] == before["other"]
    graph = toy.graph()
    assert graph.status()[0] == ("s0/a", "stale", "an input changed")
    toy.run()
    assert (toy.run_dir / "sub" / "c.txt").read_text() == "\n2-ATAD:AHPLA"
    assert toy.calls == Counter({"s0/a": 2, "s0/b": 2, "s1/c": 2, "other": 1})


def test_fingerprint_follows_upstream_output_content(toy):
    toy.run()
    before = _fingerprints(toy)
    toy.settings["a"] = {"text": "beta"}
    graph = toy.graph()
    graph.run("s0/a")
    after = _fingerprints(toy)
    assert after["s0/b"] != before["s0/b"]
    assert after["s1/c"] == before["s1/c"]          # b.txt itself has not changed yet
    assert graph.state("s0/b", {"s0/a"}) == ("stale", "an input changed")


def test_upstream_recomputed_to_identical_bytes_does_not_rerun_downstream(toy):
    toy.run()
    toy.settings["a"] = {"text": "alpha", "unused": 1}  # a new fingerprint, the same a.txt
    toy.run()
    assert toy.calls == Counter({"s0/a": 2, "s0/b": 1, "s1/c": 1, "other": 1})
    assert _manifest(toy.run_dir)["s0/a"]["fingerprint"] == _fingerprints(toy)["s0/a"]


def test_input_edited_while_its_stage_computes_leaves_the_stage_stale(toy):
    def edit_during_compute(ctx):
        text = toy.input.read_text()
        toy.input.write_text("data-2\n")       # the user saves the input mid-stage
        ctx.output("a.txt").write_text(text)

    graph = Graph(toy.run_dir, [Stage("s0/a", edit_during_compute, files=(toy.input,))],
                  log=_quiet)
    graph.run("s0/a")
    assert (toy.run_dir / "a.txt").read_text() == "data-1\n"
    assert graph.status() == [("s0/a", "stale", "an input changed")]


# ------------------------------------------------------------------------------- damaged outputs
@pytest.mark.parametrize("damage", ["truncated", "edited", "deleted"])
def test_damaged_output_is_recomputed_with_a_warning_naming_it(toy, damage):
    toy.run()
    path = toy.run_dir / "b.txt"
    good = path.read_bytes()
    if damage == "truncated":
        path.write_bytes(good[: len(good) // 2])
    elif damage == "edited":
        path.write_bytes(good.replace(b"ALPHA", b"ALPHB"))
    else:
        path.unlink()
    graph = toy.graph()
    assert graph.status()[1] == ("s0/b", "stale", "output b.txt is missing or damaged")
    with pytest.warns(UserWarning, match=r"stage s0/b: output b\.txt is missing or damaged"):
        for name in graph.stages:
            graph.run(name)
    assert path.read_bytes() == good
    # b.txt came back byte for byte: s1/c (which reads it) is not rerun
    assert toy.calls == Counter({"s0/a": 1, "s0/b": 2, "s1/c": 1, "other": 1})


# ------------------------------------------------------------------------------- --from
@pytest.mark.parametrize("pattern, rerun", [
    ("s0/b", {"s0/b", "s1/c"}),
    ("s0", {"s0/a", "s0/b", "s1/c"}),
    ("s0/", {"s0/a", "s0/b", "s1/c"}),
    ("s1", {"s1/c"}),
    ("*/b", {"s0/b", "s1/c"}),
    ("oth*", {"other"}),
])
def test_force_reruns_the_match_and_everything_after_it(toy, pattern, rerun):
    toy.run()
    toy.run(force=pattern)
    assert {n for n, c in toy.calls.items() if c == 2} == rerun
    assert all(c in (1, 2) for c in toy.calls.values())
    toy.run()
    assert {n for n, c in toy.calls.items() if c == 2} == rerun


def test_force_before_registration_reaches_stages_added_later(toy):
    toy.run()
    valid = ["s0/a", "s0/b", "s1/c", "other"]
    graph = toy.graph(force="s0/b", valid=valid)
    assert [(n, s) for n, s, _ in graph.status()] == [
        ("s0/a", "done"), ("s0/b", "stale"), ("s1/c", "stale"), ("other", "done")]
    assert graph.status()[1][2] == "forced by --from"


def test_force_reaches_stages_registered_after_the_forced_ones_ran(toy):
    toy.run()
    graph = Graph(toy.run_dir, log=_quiet)
    graph.force("s0/a", valid=["s0/a", "s0/b", "s1/c", "other"])
    for stage in toy.stages():      # as pipeline.run registers a loop stage once the last one ran
        graph.add(stage)
        graph.run(stage.name)
    assert toy.calls == Counter({"s0/a": 2, "s0/b": 2, "s1/c": 2, "other": 1})
    assert [s for _, s, _ in graph.status()] == ["done"] * 4


def test_force_unknown_stage_lists_the_valid_ones(toy):
    graph = toy.graph()
    with pytest.raises(InputError, match=r"--from s2: no such stage; valid: s0/a, s0/b, s1/c, "
                                         r"other\."):
        graph.force("s2")
    with pytest.raises(InputError, match="valid: x, y"):
        graph.force("s0", valid=["x", "y"])


# ------------------------------------------------------------------------------- status
def test_status_done_stale_missing_with_reasons(toy):
    assert toy.graph().status() == [(n, "missing", "never computed")
                                    for n in ("s0/a", "s0/b", "s1/c", "other")]
    graph = toy.graph()
    graph.run("s0/a")
    graph.run("other")
    assert toy.graph().status() == [("s0/a", "done", ""), ("s0/b", "missing", "never computed"),
                                    ("s1/c", "missing", "never computed"), ("other", "done", "")]
    toy.run()
    toy.settings["a"] = {"text": "beta"}
    (toy.run_dir / "other.txt").unlink()
    assert toy.graph().status() == [
        ("s0/a", "stale", "an input changed"),
        ("s0/b", "stale", "upstream s0/a is not done"),
        ("s1/c", "stale", "upstream s0/b is not done"),
        ("other", "stale", "output other.txt is missing or damaged")]


# ------------------------------------------------------------------------------- failures
def test_failed_compute_leaves_no_output_no_staging_and_no_valid_entry(toy):
    toy.run()
    old = _manifest(toy.run_dir)["s0/a"]
    toy.settings["a"] = {"text": "beta"}
    toy.fail.add("s0/a")
    graph = toy.graph()
    with pytest.raises(RuntimeError, match="toy failure"):
        graph.run("s0/a")
    assert not (toy.run_dir / STAGING).exists()
    assert not (toy.run_dir / "partial.txt").exists()
    assert (toy.run_dir / "a.txt").read_text() == "alpha:data-1\n"    # the old output, untouched
    entry = _manifest(toy.run_dir).get("s0/a")
    assert entry is None or entry == old                    # never an entry for the failed run
    assert toy.graph().status()[0] == ("s0/a", "stale", "an input changed")
    toy.fail.clear()
    toy.run()
    assert (toy.run_dir / "sub" / "c.txt").read_text() == "\n1-ATAD:ATEB"
    assert not (toy.run_dir / "partial.txt").exists()


_KILL_SCRIPT = textwrap.dedent("""
    import os, sys
    from pathlib import Path
    from pipeline.graph import Graph, Stage, STAGING

    run_dir, text = Path(sys.argv[1]), sys.argv[2]

    def write(ctx):
        for name in ("one.txt", "two.txt", "three.txt"):
            ctx.output(name).write_text(text + name)

    real = os.replace
    staged = []

    def replace(src, dst):   # the process dies after moving the first staged output into place
        if STAGING in Path(src).parts:
            if staged:
                os._exit(9)
            staged.append(src)
        return real(src, dst)

    graph = Graph(run_dir, [Stage("s", write, settings=text)], log=lambda line: None)
    if text == "new":
        os.replace = replace
    graph.run("s")
""")


def test_kill_between_manifest_write_and_renames_is_recomputed(tmp_path):
    run_dir = tmp_path / "run"
    script = tmp_path / "kill.py"
    script.write_text(_KILL_SCRIPT)
    env = dict(os.environ, PYTHONPATH=str(ROOT))

    def run(text: str) -> int:
        return subprocess.run([sys.executable, str(script), str(run_dir), text], env=env,
                              cwd=tmp_path).returncode

    assert run("old") == 0
    assert run("new") == 9
    manifest = _manifest(run_dir)
    assert "s" not in manifest                       # the old entry was voided before the renames
    assert (run_dir / "one.txt").read_text() == "newone.txt"     # renamed before the kill
    assert (run_dir / "two.txt").read_text() == "oldtwo.txt"     # not yet
    assert (run_dir / STAGING / "s").is_dir()                    # what the kill left behind

    graph = Graph(run_dir, log=_quiet)
    calls = []

    def write(ctx):
        calls.append(1)
        for name in ("one.txt", "two.txt", "three.txt"):
            ctx.output(name).write_text("new" + name)

    graph.add(Stage("s", write, settings="new"))
    assert graph.status() == [("s", "missing", "never computed")]
    graph.clean_staging()
    graph.run("s")
    assert calls == [1]
    assert [(run_dir / n).read_text() for n in ("one.txt", "two.txt", "three.txt")] == \
           ["newone.txt", "newtwo.txt", "newthree.txt"]
    assert not (run_dir / STAGING).exists()
    assert Graph(run_dir, [Stage("s", write, settings="new")], log=_quiet).status() == \
           [("s", "done", "")]


@pytest.mark.parametrize("content", ['{"s0/a": {"fingerprint": "f", "outp', "[1, 2]",
                                     '{"s0/a": {"fingerprint": 3, "outputs": {}}}', "\udcff"])
def test_damaged_manifest_names_the_file_and_the_fix(toy, content):
    toy.run_dir.mkdir()
    (toy.run_dir / MANIFEST).write_bytes(content.encode("utf-8", "surrogateescape"))
    with pytest.raises(InputError) as err:
        toy.graph()
    message = str(err.value)
    assert str(toy.run_dir / MANIFEST) in message
    assert "damaged" in message and "Fix: delete it" in message and "--out" in message
