"""Run the ``pipeline`` command in-process for the CLI tests."""
from __future__ import annotations

from pipeline.cli import main


def cli(argv, capsys) -> tuple[int, str, str]:
    """Run ``pipeline ARGV`` in-process: (exit code, stdout, stderr)."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err
