"""Shared fixtures of the diagnose tests: the shipped X-56 deck, its model and its candidates
(read once; the model and candidates are frozen)."""
from pathlib import Path

import pytest

from pipeline.diagnose.effects import candidates
from structures.bdf import read_model


@pytest.fixture(scope="session")
def x56_deck() -> Path:
    return Path(__file__).resolve().parents[3] / "data" / "x56_like" / "x56_efew.bdf"


@pytest.fixture(scope="session")
def x56(x56_deck):
    return read_model(x56_deck)


@pytest.fixture(scope="session")
def x56_candidates(x56):
    return candidates(x56)
