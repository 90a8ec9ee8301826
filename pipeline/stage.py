"""Which stage is running: named in the one-line message of an interrupted command.

Code that runs a stage wraps it in :func:`running`; a KeyboardInterrupt raised inside becomes an
:class:`Interrupted` (still a KeyboardInterrupt) that carries the innermost stage's name, which
:func:`pipeline.cli.main` prints as ``interrupted in STAGE; run the same command again to resume``.
"""
from __future__ import annotations

from contextlib import contextmanager


class Interrupted(KeyboardInterrupt):
    """Ctrl-C while ``stage`` was running."""

    def __init__(self, stage: str):
        super().__init__(stage)
        self.stage = stage


@contextmanager
def running(stage: str):
    """Mark ``stage`` as running for the block (stages nest; the innermost is named)."""
    try:
        yield
    except Interrupted:
        raise
    except KeyboardInterrupt:
        raise Interrupted(stage) from None
