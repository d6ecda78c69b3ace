"""papers/section5.py and section6.py run, check their own results, and write their figures."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

PAPERS = Path(__file__).resolve().parents[1] / "papers"


def load(name):
    spec = importlib.util.spec_from_file_location(name, PAPERS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("name, figures", [
    ("section5", ["fig14_three_arcs_beta0.png", "fig15_three_arcs_beta.png", "fig16b_energy_surface.png",
                  "fig19_rotating_curve_portrait.png", "bifurcation_curve1.png", "bifurcation_curve2.png",
                  "bifurcation_curve3.png"]),
    ("section6", ["fig20_phase_branches.png", "fig20_energy_transfer.png"]),
])
def test_paper_script_checks_pass_and_figures_are_written(tmp_path, capsys, name, figures):
    assert load(name).main(["--out", str(tmp_path)]) == 0
    assert all((tmp_path / f).stat().st_size > 10_000 for f in figures)
    out = capsys.readouterr().out
    if name == "section5":
        assert "Omega = 3.21345854018" in out and "pitchfork at the minimum" in out
