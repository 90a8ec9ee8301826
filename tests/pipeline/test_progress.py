"""pipeline.progress: the live line only when both stdout and stderr are terminals, otherwise
every log line on stdout (a run redirected to a log file keeps its stage lines)."""
from __future__ import annotations

import io
import sys

import pytest

from pipeline.progress import Display


class _Stream(io.StringIO):
    def __init__(self, tty: bool):
        super().__init__()
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty


@pytest.mark.parametrize("out_tty, err_tty, live", [(True, True, True), (False, True, False),
                                                    (True, False, False), (False, False, False)])
def test_live_only_when_stdout_and_stderr_are_terminals(monkeypatch, out_tty, err_tty, live):
    monkeypatch.setattr(sys, "stdout", _Stream(out_tty))
    monkeypatch.setattr(sys, "stderr", _Stream(err_tty))
    assert Display().live is live


def test_without_live_line_every_log_line_goes_to_stdout(capsys):
    display = Display(live=False)
    with display.stage("stage0/modes/baseline"):
        display.note("GAFs: 2 Mach x 8 k")            # no live line: nothing written
        display.iteration(3, 1.5e-3, 0.0, 2.0)
        display.log("[stage0/modes/baseline] 10 modes")
    display.log("report: runs/x/report.html")
    out = capsys.readouterr()
    assert out.out == "[stage0/modes/baseline] 10 modes\nreport: runs/x/report.html\n"
    assert out.err == ""


def test_live_line_names_the_stage_and_keeps_the_log_lines(monkeypatch):
    out, err = _Stream(True), _Stream(True)
    monkeypatch.setattr(sys, "stdout", out)
    monkeypatch.setattr(sys, "stderr", err)
    display = Display()
    with display.stage("stage1/tuning"):
        display.iteration(3, 1.5e-3, 0.0, 2.0)
        assert display._progress.tasks[0].description == \
            "stage1/tuning: iteration 3, objective 1.5000e-03, max violation 0.00e+00"
        display.log("[stage1/tuning] converged")
    assert display._progress is None
    assert "[stage1/tuning] converged" in err.getvalue()   # printed above the live line
    display.log("report: runs/x/report.html")              # no stage running: plain stdout
    assert out.getvalue() == "report: runs/x/report.html\n"
