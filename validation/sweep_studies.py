"""Two sweeps of the paper's natural parameters (issue 16), with `heyroll.sweep`.

    python validation/sweep_studies.py [--workers 2] [--output validation/reports/sweep_studies.md]

1. Two balls in a circle (paper section 4, the default scene): the mass of
   ball 2 at k = 1 as a bifurcation diagram (ball 1's position and the
   closing rate at the last 60 of 300 impacts, against m2), and the map of k
   against m2 (collisions and energy lost in 30 s).
2. Two disks on the rotating three-arc track (paper section 6,
   examples/two_disks_rotating_arcs.toml, k = 0.9): the map of the plane's
   rotation Omega against the axis position a (collisions and loss of the
   first integral, eq. 92, in 20 s), and Omega alone as a bifurcation diagram.

Each sweep's store is written under a temporary directory; the figures and
this report go to validation/reports/ (figures named sweep_studies_*.png).
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from heyroll.interfaces.outputs import versions
from heyroll.sweep import run_sweep

ROOT = Path(__file__).resolve().parent.parent
ROTATING = ROOT / "examples" / "two_disks_rotating_arcs.toml"

#: (name, scene, sweep arguments, what it shows). Ball 1 of the default scene is 32.88 kg (steel, r = 0.1 m).
STUDIES = [
    ("mass_bifurcation", None,
     dict(vary={"bodies[2].mass": (5, 200, 400)}, keep="impacts:60", max_collisions=300, t_end=1e4),
     "two balls in a circle, k = 1: the last 60 of 300 impacts against the mass of ball 2"),
    ("k_mass_map", None,
     dict(vary={"collision.restitution": (0.5, 1.0, 21), "bodies[2].mass": (10, 130, 25)}, t_end=30.0),
     "two balls in a circle: k against the mass of ball 2, 30 s each"),
    ("omega_axis_map", ROTATING,
     dict(vary={"frame.omega": (0, 3, 31), "frame.axis_x": (-0.3, 0.3, 25)}, t_end=20.0),
     "two disks on the rotating three-arc track, k = 0.9: Omega against the axis position, 20 s each"),
    ("omega_bifurcation", ROTATING,
     dict(vary={"frame.omega": (0, 2, 201)}, keep="impacts:20", t_end=60.0),
     "two disks on the rotating three-arc track, k = 0.9: the last 20 impacts in 60 s against Omega"),
]


def facts(name: str, ds) -> list:
    """A few numbers read off each store (what the figure shows, in words)."""
    status = ds["status"].values
    counts = {s: int((status == s).sum()) for s in np.unique(status)}
    lines = [f"statuses: {counts}"]
    collisions = ds["collisions"].values
    if name == "mass_bifurcation":
        e0, e1 = ds["energy_initial"].values, ds["energy_final"].values
        lines.append(f"elastic: largest |E/E0 - 1| over the 300 collisions of a point {np.max(np.abs(e1 / e0 - 1)):.2g}")
        spread = ds["impact_q_i"].max("impact") - ds["impact_q_i"].min("impact")
        narrow = ds["bodies[2].mass"].values[spread.values < 0.05]
        lines.append(f"points whose last 60 impacts lie within 0.05 rad of each other (a near-periodic impact "
                     f"sequence): {narrow.size} of {spread.size}" +
                     (f", m2 in [{narrow.min():.4g}, {narrow.max():.4g}] kg" if narrow.size else ""))
    elif name.endswith("_map"):
        first, second = ds["status"].dims
        per_first = (ds["collisions"].where(ds["collisions"] >= 0)).mean(second)
        lines.append(f"collisions per point: {collisions.min()} to {collisions.max()}; mean over {second} "
                     f"largest at {first} = {float(per_first.idxmax()):.4g}, smallest at "
                     f"{float(per_first.idxmin()):.4g}")
        loss = ds["energy_initial"] - ds["energy_final"]
        energy = "first integral (eq. 92)" if name == "omega_axis_map" else "mechanical energy"
        lines.append(f"{energy} lost: {float(loss.min()):.3g} to "
                     f"{float(loss.max()):.3g} J, of E0 = {float(ds['energy_initial'].min()):.4g} to "
                     f"{float(ds['energy_initial'].max()):.4g} J")
        if name == "omega_axis_map":
            none = ds["frame.omega"].values[(ds["collisions"] == 0).all("frame.axis_x").values]
            lines.append(f"no collision in 20 s at any axis position for Omega >= {none.min():.4g} rad/s"
                         if none.size else "a collision at every Omega for some axis position")
    else:
        none = ds["frame.omega"].values[collisions == 0]
        lines.append(f"collisions per point: {collisions.min()} to {collisions.max()}; {none.size} points without "
                     "a collision in 60 s" + (f", Omega from {none.min():.4g} to {none.max():.4g} rad/s"
                                              if none.size else ""))
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--output", default=str(ROOT / "validation" / "reports" / "sweep_studies.md"))
    args = parser.parse_args()
    output = Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    lines = ["# Sweeps of the paper's natural parameters (heyroll sweep)", "",
             f"{args.workers} worker processes (Dask LocalCluster); versions {versions()}", ""]
    with tempfile.TemporaryDirectory(prefix="heyroll-sweep-studies-") as tmp:
        work = Path(tmp)
        for name, scene, spec, what in STUDIES:
            t0 = time.perf_counter()
            ds = run_sweep(scene, out=work / name, workers=args.workers, figures=True, **spec)
            wall = time.perf_counter() - t0
            command = ds.attrs["command"].replace(f"{ROOT}/", "")  # the repository's paths, not this machine's
            lines += [f"## {what}", "", f"`{command}`", "",
                      f"{ds['status'].size} points in {wall:.3g} s wall (cluster start-up included).", ""]
            lines += [f"- {fact}" for fact in facts(name, ds)]
            lines.append("")
            for figure in sorted((work / name).glob("*.png")):
                target = output.parent / f"sweep_studies_{name}_{figure.name}"
                shutil.copyfile(figure, target)
                lines += [f"![{name} {figure.stem}]({target.name})", ""]
    text = "\n".join(lines)
    print(text)
    output.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
