"""The validation scripts run against the current package, on a tiny workload.

Each script runs as a user runs it (``python validation/NAME.py ...``, in a
fresh process: validation/many_bodies.py turns heyoka's on-disk cache off for
its process), writing its report into a temporary directory; the printed
table must be the report, and its figures must agree with heyroll itself.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import heyroll

VALIDATION = Path(__file__).resolve().parents[1] / "validation"


def run_script(name: str, *args: str) -> str:
    """stdout of ``python validation/NAME.py ARGS`` (which must succeed)."""
    done = subprocess.run([sys.executable, str(VALIDATION / name), *args], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout


def table_rows(text: str) -> list[list[str]]:
    """Cells of a markdown table's data rows (header and rule dropped)."""
    rows = [[c.strip() for c in line.strip().strip("|").split("|")] for line in text.splitlines() if line.startswith("|")]
    return rows[2:]


def test_profile_collision_path_runs_and_prints_its_breakdown(tmp_path):
    # The script built its event integrator with the system's whole parameter vector, longer
    # than what its equations and events read (heyoka refused it): it now builds the events
    # as simulate does and hands heyoka the parameters it keeps.
    report = tmp_path / "profile.md"
    out = run_script("profile_collision_path.py", "--t-end", "30", "--repeat", "1", "--output", str(report))
    assert report.read_text(encoding="utf-8").strip() == out.strip()
    rows = table_rows(out)
    assert [r[0].split(" (")[0] for r in rows] == [
        "Taylor steps alone", "+ event detection", "+ collision law, checks, records", "total",
    ]
    result = heyroll.simulate(heyroll.default_scene(), t_end=30.0)  # what the profile's full run does
    assert result.n_collisions > 0
    assert f"t_end = 30 s, {result.n_collisions} collisions, {result.steps} steps in the full run" in out
    assert float(rows[-1][2]) > 0  # total us per collision


def test_many_bodies_study_runs_and_states_its_goals(tmp_path):
    report = tmp_path / "many_bodies.md"
    out = run_script("many_bodies.py", "--sizes", "2", "8", "--collisions", "200", "--repeat", "1",
                     "--output", str(report))
    assert report.read_text(encoding="utf-8").strip() == out.strip()
    rows = table_rows(out)
    assert [(r[0], r[1]) for r in rows] == [("2", "1"), ("2", "0.9"), ("8", "1"), ("8", "0.9")]
    elastic = [r for r in rows if r[1] == "1"]
    assert all(r[4] == "200" for r in elastic)  # the elastic runs stop at the collision count
    assert elastic[0][11] == "1.00"  # the 2-body elastic cost is the ratios' reference
    assert all(abs(float(r[12])) < 1e-12 for r in elastic)  # elastic: the energy is kept
    assert "- cost per collision at 8 bodies (k = 1): " in out


def test_random_scenes_all_end_in_a_success_status_quick(tmp_path):
    report = tmp_path / "random.md"
    out = run_script("random_scenes.py", "--seed", "7", "--scenes", "6", "--output", str(report))
    assert "Runs not ending in completed, max_collisions, max_events: 0" in out
    assert report.read_text(encoding="utf-8").strip() in out


@pytest.mark.slow
def test_random_scenes_all_end_in_a_success_status(tmp_path):
    # The sweep that found four engine bugs in issue 12's session (see the script's docstring).
    for seed in (3, 5):
        done = subprocess.run([sys.executable, str(VALIDATION / "random_scenes.py"), "--seed", str(seed),
                               "--scenes", "150", "--output", str(tmp_path / f"r{seed}.md")],
                              capture_output=True, text=True, timeout=1800)
        assert done.returncode == 0, done.stderr
        assert "Runs not ending in completed, max_collisions, max_events: 0" in done.stdout, done.stdout[-3000:]


def test_ellipse_limit_study_counts_every_launch(tmp_path):
    report = tmp_path / "ellipse_limit.md"
    out = run_script("ellipse_limit.py", "--fractions", "0.9", "--launches", "1", "--t-end", "0.5",
                     "--output", str(report))
    assert report.read_text(encoding="utf-8").strip() == out.strip()
    rows = table_rows(out)
    assert [(r[2], r[3]) for r in rows] == [("rolling", "1"), ("rolling", "0"), ("slide", "1"), ("slide", "0")]
    for r in rows:  # runs = success + overlap + failed; far from the limit every launch succeeds
        assert int(r[4]) == int(r[5]) + int(r[6]) + int(r[7]) == 1
        assert r[5] == "1"
