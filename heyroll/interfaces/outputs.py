"""Files a run writes: collisions.csv, summary.json (figures: see figures.py).

Every file is written under a temporary name and renamed into place, so an
interrupted or failed write never leaves a half-written file behind.
"""

from __future__ import annotations

import json
import os
import platform
from pathlib import Path

import heyoka
import mpmath
import numpy as np

from .._version import __version__
from ..simulation.result import INTEGER_COLUMNS, SimulationResult


def versions() -> dict:
    return {
        "heyroll": __version__,
        "heyoka": heyoka.__version__,
        "numpy": np.__version__,
        "mpmath": mpmath.__version__,
        "python": platform.python_version(),
    }


def atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


def collisions_csv(table: np.ndarray, digits: int = 17, format_value=None) -> str:
    """The collision table as CSV text.

    Float columns get ``digits`` significant digits (17 round-trips a double);
    object columns (quad / MPFR runs) are written by ``format_value``.
    """
    names = table.dtype.names
    float_fmt = f"%.{digits}g"
    lines = [",".join(names)]
    if table.size:
        formatters = []
        for name in names:
            if name in INTEGER_COLUMNS:
                formatters.append(str)
            elif table.dtype[name] == object:
                formatters.append(format_value)
            else:
                formatters.append(lambda x, f=float_fmt: f % x)
        columns = [table[name].tolist() for name in names]
        lines.extend(",".join(f(v) for f, v in zip(formatters, values)) for values in zip(*columns))
    return "\n".join(lines) + "\n"


def summary_dict(result: SimulationResult, *, scene_source: str, files: dict) -> dict:
    data = result.summary()
    data["scene"] = {"name": result.scene.name, "source": scene_source, "description": result.scene.describe()}
    data["files"] = files
    data["versions"] = versions()
    return data


def write_run(result: SimulationResult, out_dir: Path, *, scene_source: str, figures: bool = True) -> dict:
    """Write collisions.csv, summary.json and (optionally) the figures into ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    files = {"collisions": "collisions.csv", "summary": "summary.json"}
    precision = result.precision
    table = result.collision_table(native=True)
    atomic_write_text(out_dir / "collisions.csv", collisions_csv(table, precision.digits, precision.format))
    if figures:
        from .figures import energy_figure, phase_portrait_figure

        phase_portrait_figure(result, out_dir / "phase_portrait.png")
        energy_figure(result, out_dir / "energy.png")
        files.update(phase_portrait="phase_portrait.png", energy="energy.png")
    summary = summary_dict(result, scene_source=scene_source, files=files)
    atomic_write_text(out_dir / "summary.json", json.dumps(summary, indent=2, allow_nan=True) + "\n")
    return summary
