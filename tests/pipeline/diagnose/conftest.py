"""Shared fixtures of the diagnose tests: the shipped X-56 deck, its model and its candidates
(read once; the model and candidates are frozen), and the frame against its own modes."""
from pathlib import Path

import pytest

from pipeline.diagnose.effects import candidates
from structures.bdf import read_model
from tests.pipeline.diagnose.perfect_frame import perfect_reference
from tests.pipeline.diagnose.truth import frame


@pytest.fixture(scope="session")
def x56_deck() -> Path:
    return Path(__file__).resolve().parents[3] / "data" / "x56_like" / "x56_efew.bdf"


@pytest.fixture(scope="session")
def x56(x56_deck):
    return read_model(x56_deck)


@pytest.fixture(scope="session")
def x56_candidates(x56):
    return candidates(x56)


@pytest.fixture(scope="module")
def frame_reference(tmp_path_factory):
    """The frame model against its own modes 7..26 at the 120 sensors (a perfect test)."""
    model = read_model(frame.write_frame(tmp_path_factory.mktemp("frame")))
    modes, ref = perfect_reference(model, model)
    return model, modes, ref
