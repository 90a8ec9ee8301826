"""structures.common.process: the program-wide collector and allocator settings."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_settle_process_freezes_objects_and_tunes_glibc_malloc():
    """Run in a child interpreter (the settings are process-wide): objects that exist leave the
    collector's scans (gc.get_freeze_count() from 0 to the ~thousands of an import), numpy's
    huge-page requests are off, and on Linux with glibc all three mallopt calls succeed (glibc
    returns 1 on success)."""
    code = ("import gc, json; "
            "from structures.common.process import _set_madvise_hugepage, settle_process; "
            "before = gc.get_freeze_count(); tuned = settle_process(); "
            "huge = _set_madvise_hugepage(False); "
            "print(json.dumps([before, gc.get_freeze_count(), tuned, huge]))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         check=True, timeout=60)
    before, after, tuned, huge = json.loads(out.stdout.strip().splitlines()[-1])
    assert before == 0 and after > 1000
    assert huge is False                 # numpy no longer asks for transparent huge pages
    if not sys.platform.startswith("linux"):
        pytest.skip("the allocator is tuned on Linux (glibc) only")
    assert tuned is True
