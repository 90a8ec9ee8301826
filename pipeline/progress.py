"""Progress of a run on the terminal: the stage that runs and the optimiser's iterations.

On a terminal (stderr is a TTY) a one-line live display (``rich``) shows the stage, what it is
computing (the GAFs, each flutter request) and, during tuning, the optimiser's iteration,
objective and constraint violation; it
vanishes when the stage ends, leaving the stage's log lines. When output is not a terminal (a log
file, CI) nothing but the log lines is written.
"""
from __future__ import annotations

import sys
from contextlib import contextmanager


class Display:
    """Log lines on stdout and, on a terminal, a live status line on stderr.

    Parameters
    ----------
    live : bool, optional
        Show the live status line (default: when stderr is a terminal).
    """

    def __init__(self, live: bool | None = None):
        self.live = sys.stderr.isatty() if live is None else live
        self._progress = None
        self._task = None

    def log(self, line: str) -> None:
        """One line of the run's log (always written, on stdout)."""
        if self._progress is not None:
            self._progress.console.print(line, highlight=False, markup=False)
        else:
            print(line, flush=True)

    @contextmanager
    def stage(self, name: str, position: str = ""):
        """Show ``name`` as the running stage for the block."""
        if not self.live:
            yield
            return
        from rich.console import Console
        from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        label = f"{name} {position}".strip()
        with Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
                      console=Console(stderr=True), transient=True) as progress:
            self._progress, self._task = progress, progress.add_task(label, total=None)
            self._label = label
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
