"""papers/simultaneous_collisions.py runs, and its checks (momentum, energy, the order's discontinuity) pass."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_the_simultaneous_collision_study_passes_its_checks(tmp_path):
    out = subprocess.run([sys.executable, str(ROOT / "papers" / "simultaneous_collisions.py"), "--quick", "--out",
                          str(tmp_path)], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]
    assert "FAIL" not in out.stdout
    report = (tmp_path / "simultaneous_collisions.md").read_text()
    assert "(-0.333333, +0.666667, +0.666667)" in report  # the cradle under simultaneous impulses
    assert (tmp_path / "simultaneous_collisions.png").stat().st_size > 0
