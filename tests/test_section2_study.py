"""Section 2 (rough tracks): papers/section2.py's checks pass, validation/rough_tracks.py's numbers are tight."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _load(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_section2_quick_all_checks_pass(tmp_path):
    section2 = _load(ROOT / "papers" / "section2.py", "paper_section2")
    checks = section2.main(out_dir=tmp_path, quick=True)
    failed = {name: value for name, (ok, value) in checks.items() if not ok}
    assert not failed, failed
    names = " ".join(checks)
    for needed in ("circle: E_i - E_f = friction + impacts", "turning points vs closed form",
                   "curve: H_i - H_f = friction + impacts", "single particle: transition times"):
        assert needed in names
    for fig in ("section2_circle_portrait.png", "section2_curve_portrait.png", "section2_energy.png"):
        assert (tmp_path / fig).stat().st_size > 10_000


def _section(text: str, title: str) -> str:
    start = text.index(title)
    end = text.find("\n## ", start + 1)
    return text[start:] if end < 0 else text[start:end]


def _rows(text: str) -> list[list[str]]:
    rows = [[c.strip() for c in line.strip().strip("|").split("|")] for line in text.splitlines() if line.startswith("|")]
    return rows[2:]


def test_rough_tracks_validation_quick(tmp_path):
    report = tmp_path / "rough_tracks.md"
    done = subprocess.run([sys.executable, str(ROOT / "validation" / "rough_tracks.py"), "--quick", "--output", str(report)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert report.read_text(encoding="utf-8").strip() == out.strip()
    accuracy = _rows(_section(out, "## (a)"))
    assert len(accuracy) >= 8
    cases = " ".join(r[0] for r in accuracy)
    assert "y = 0.5 x" in cases and "circle" in cases and "disk" in cases
    for case, quantity, _engine, _reference, error in accuracy:
        assert float(error) < 1e-12, (case, quantity, error)  # transition instants (s) and places (m, rad)
    balance = _rows(_section(out, "## (b)"))
    assert balance
    for _case, branches, run, closed_form in balance:
        assert int(branches) >= 3
        assert float(run) < 1e-12 and float(closed_form) < 1e-12
    cost = _rows(_section(out, "## (c)"))
    assert [r[0] for r in cost] == ["first (compilation included)", "second (compiled)"]
    assert all(float(r[2]) > 0 for r in cost)
    changes = int(re.search(r": (\d+) changes of mode", out).group(1))
    assert changes > 20  # the forced run sticks and slips again and again
