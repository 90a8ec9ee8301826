"""Progress of a run on the terminal: the stage that runs and the optimiser's iterations.

On a terminal (stdout and stderr both TTYs) a one-line live display (``rich``, on stderr) shows the
stage, what it is computing (the GAFs, each flutter request) and, during tuning, the optimiser's
iteration, objective and constraint violation; it vanishes when the stage ends, leaving the stage's
log lines. When either is not a terminal (``pipeline run > log``, CI) there is no live line and
the log lines go to stdout.
"""
from __future__ import annotations

import sys
from contextlib import contextmanager


class Display:
    """Log lines on stdout and, on a terminal, a live status line on stderr.

    Parameters
    ----------
    live : bool, optional
        Show the live status line (default: when stdout and stderr are terminals; while it shows,
        rich routes the log lines through its console, so a redirected stdout would lose them).
    """

    def __init__(self, live: bool | None = None):
        self.live = sys.stdout.isatty() and sys.stderr.isatty() if live is None else live
        self._progress = None
        self._task = None

    def log(self, line: str) -> None:
        """One line of the run's log: on stdout, or above the live line while it shows."""
        if self._progress is not None:
            self._progress.console.print(line, highlight=False, markup=False)
        else:
            print(line, flush=True)

    @contextmanager
    def stage(self, name: str):
        """Show ``name`` as the running stage for the block."""
        if not self.live:
            yield
            return
        from rich.console import Console
        from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
                      console=Console(stderr=True), transient=True) as progress:
            self._progress, self._task = progress, progress.add_task(name, total=None)
            self._label = name
            try:
                yield
            finally:
                self._progress = self._task = None

    def note(self, text: str) -> None:
        """What the running stage is doing now (e.g. a flutter request), on the live line."""
        if self._progress is not None:
            self._progress.update(self._task, description=f"{self._label}: {text}")

    def iteration(self, iteration: int, objective: float, violation: float, seconds: float) -> None:
        """An optimiser iteration (structures.tuning.tune's ``progress`` callback)."""
        self.note(f"iteration {iteration}, objective {objective:.4e}, max violation "
                  f"{violation:.2e}")
