"""papers/section7.py --quick runs, every check passes (exit 0), and the figures of Figs. 22-27 are written."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ("fig22_elliptical_billiard.png", "fig23_great_circle_velocities.png", "fig24_oblique_decomposition.png",
           "fig25_collision_point_velocities.png", "fig26_paths_angular_velocities.png", "fig27_track_legs.png",
           "sec722_feasibility.png")


def test_section7_quick_passes_and_writes_its_figures(tmp_path):
    done = subprocess.run([sys.executable, str(ROOT / "papers" / "section7.py"), "--quick", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    out = done.stdout
    assert "[FAIL]" not in out and out.count("[PASS]") >= 40
    for needed in ("impact centres at distance R from the ellipse", "hedrih k=1: sum J_P omega_P (vector) conserved",
                   "mirror k=1: sum J_P omega_P NOT conserved", "energy loss = eq. (15)",
                   "the oblique collision's normal parts = the central collision's outcome",
                   "7.2.2 case A", "7.2.2 case D2"):
        assert needed in out, needed
    for name in FIGURES:
        assert (tmp_path / name).stat().st_size > 10_000, name
