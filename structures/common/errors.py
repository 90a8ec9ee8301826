"""The project's own exception hierarchy.

Every part of the project raises these, so that callers can catch one family. Messages name the
file, the card, the id and the fix, as the design requires: build them with :func:`card_message`.
"""
from __future__ import annotations


class PipelineError(Exception):
    """Base class of every error this project raises on purpose."""


class InputError(PipelineError, ValueError):
    """Bad or inconsistent input: a deck, a case file, a GVT file or an argument."""


class UnsupportedCardError(InputError):
    """A bulk-data card this project does not model."""


class MissingReferenceError(InputError, KeyError):
    """A card refers to an id (grid, property, material, set, ...) that is not defined."""

    def __str__(self) -> str:  # KeyError would otherwise quote the message
        return str(self.args[0]) if self.args else ""


class SolverError(PipelineError, RuntimeError):
    """A numerical step failed: singular matrix, no convergence, ..."""


def card_message(problem: str, *, card: str | None = None, card_id: int | str | None = None,
                 filename: str | None = None, fix: str | None = None) -> str:
    """Compose an error message that names file, card, id and the fix.

    Parameters
    ----------
    problem : str
        What is wrong, in one sentence.
    card, card_id : optional
        The bulk-data card name (``"PBAR"``) and its id.
    filename : str, optional
        The file the card came from.
    fix : str, optional
        What the user should do about it.
    """
    where = []
    if filename:
        where.append(f"file {filename}")
    if card:
        where.append(f"card {card}" + (f" {card_id}" if card_id is not None else ""))
    elif card_id is not None:
        where.append(f"id {card_id}")
    text = (", ".join(where) + ": " if where else "") + problem
    if fix:
        text += f" Fix: {fix}"
    return text
