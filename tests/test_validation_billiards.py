"""validation/billiards.py runs as a user runs it (``--tiny``: every section on a small workload), in a fresh
process, writing its report and figure into a temporary directory; the printed report is the written one,
every section is there, and its accuracy numbers are tight."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

VALIDATION = Path(__file__).resolve().parents[1] / "validation"


def section(text: str, heading: str) -> str:
    start = text.index(heading)
    rest = text[start + len(heading):]
    ends = [rest.index(h) for h in ("\n## ", "\n### ") if h in rest]
    return rest[:min(ends)] if ends else rest


def table_rows(text: str) -> list[list[str]]:
    """Cells of the data rows of the markdown tables in ``text`` (header and rule dropped)."""
    rows, block = [], []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            block.append([c.strip() for c in line.strip().strip("|").split("|")])
        elif block:
            rows += block[2:]
            block = []
    return rows


@pytest.mark.slow  # 40 s of CPU (46-100 s of wall in CI and on a loaded machine): the suite's largest test
def test_billiards_study_tiny(tmp_path):
    report = tmp_path / "billiards.md"
    done = subprocess.run([sys.executable, str(VALIDATION / "billiards.py"), "--tiny", "--output", str(report)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    # heyoka logs its warnings to stdout (the long-step probe provokes one): not part of the report
    out = "\n".join(line for line in done.stdout.splitlines() if "[heyoka-" not in line)
    assert report.read_text(encoding="utf-8").strip() == out.strip()
    assert (tmp_path / "billiards_birkhoff_R.png").stat().st_size > 10_000
    assert out.startswith("# Billiards") and "`python validation/billiards.py --tiny`" in out
    assert "shared and noisy" in out
    for heading in ("## 1. Impact-time accuracy against mpmath", "## 2. Speed", "## 3. Drift of the integrals",
                    "## 4. A finite ball in the ellipse: which integrals are lost"):
        assert heading in out

    # 1. local errors: every boundary, double and quad
    local = table_rows(section(out, "### Local"))
    cases = [r[0].split(" (")[0] for r in local]
    assert cases == ["particle, ellipse", "R = 0.1, ellipse", "R = 0.01, ellipse", "R = 0.1, rectangle 2 x 1",
                     "R = 0.1, regular hexagon", "R = 0.1, circle", "R = 0.1, ellipse"]
    for case, precision, compared, _t_last, t_max, t_median, floor, ulps, place_max, place_median in local:
        assert int(compared) >= 10, case
        if precision == "double":
            # the recorded time is within a few ulps; relative to the flight it sits at the clock's rounding
            assert float(ulps) < 4, (case, ulps)
            assert float(t_max) < max(1e-14, 4 * float(floor)), (case, t_max, floor)
            assert float(t_median) < 1e-14, (case, t_median)
            assert float(place_max) < 1e-14 and float(place_median) < 1e-15, (case, place_max)
        else:
            assert precision == "quad"
            assert float(t_max) < 1e-30 and float(place_max) < 1e-31, (case, t_max, place_max)

    # 1. global errors of the 2-ball scene: the same impacts as the reference, round-off sized early on
    glob = table_rows(section(out, "### Global"))
    assert len(glob) >= 8 and all(r[2] == "yes" for r in glob)
    assert all(float(r[4]) < 1e-13 for r in glob)  # double: grows through the dynamics, still small
    assert all(r[5] == "-" for r in glob)  # quad: not run by --tiny (its local errors are checked above)

    # 2. speed: a row per scene, positive rates
    speed = table_rows(section(out, "## 2. Speed"))
    assert [r[0] for r in speed][:3] == ["1 particle, ellipse", "1 ball R = 0.1, ellipse", "4 balls in the rectangle"]
    assert all(float(r[6]) > 100 for r in speed)

    # 3. drift: round-off sized after 1e4 impacts
    drift = table_rows(section(out, "## 3. Drift"))
    assert {(r[0], r[1]) for r in drift} >= {("lambda", "engine"), ("speed", "engine"), ("energy", "engine")}
    for name, run, _value, impacts, max_drift, *_ in drift:
        assert float(max_drift) < 1e-12, (name, run, impacts, max_drift)

    # 4. the finite ball: lambda lost for R > 0, speed and energy kept for every R
    finite = table_rows(section(out, "## 4."))
    assert [r[0] for r in finite] == ["0", "0.05", "0.2", "0.4"]
    for radius, _n, _mean, lam, lam_r, speed_spread, energy_spread, *_ in finite:
        assert float(speed_spread) < 1e-13 and float(energy_spread) < 1e-13, radius
        if radius == "0":
            assert float(lam) < 1e-12 and float(lam_r) < 1e-12
        else:
            assert float(lam) > 1e-3 and float(lam_r) > 1e-3, radius
    spreads = [float(r[3]) for r in finite]
    assert spreads == sorted(spreads)  # lost the more the larger the ball

    # 5. riding the cushion: every case settles, rides, and ends on its curve where the reference puts it
    riding = table_rows(section(out, "## 5."))
    assert [r[0] for r in riding] == ["ball R = 0.1, circle", "particle, ellipse", "ball R = 0.1, ellipse",
                                      "ball R = 0.01, ellipse"]
    for label, impacts, _t, loss, _laps, error, speed, distance, _wall, status in riding:
        assert status == "completed" and int(impacts) > 5 and float(loss) < 1e-10, label
        assert float(error) < 1e-9 and abs(float(speed)) < 1e-11 and abs(float(distance)) < 1e-13, label
