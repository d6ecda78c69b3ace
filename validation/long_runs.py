"""Long elastic runs: does the energy error follow Brouwer's law?

    python validation/long_runs.py [--collisions 1000000] [--long 10000000] [--quick] [--workers 2]

1. An ensemble of non-periodic elastic scenes (2-3 bodies; shapes, radii,
   masses, initial states and both energy-conserving laws, hedrih and
   newton_generalized, varied) is run to ``--collisions`` collisions each, one
   of them (the built-in default scene as committed in 224fc9e: two steel
   balls, r = 0.10 and 0.15 m) to ``--long``. Every run streams through
   :class:`energy_study.EnergySink`, which keeps E/E0 - 1 downsampled (a
   log-spaced grid of collision numbers, block ends and block maxima), never
   the whole table. Two symmetric equal-body *control* scenes, whose
   floating-point trajectories become exactly periodic, show the periodicity
   detector at work: a run whose state after a collision recurs bit for bit (or
   whose energy error is frozen) is excluded from the statistics, and the
   report says so.
2. Ensemble RMS and mean of E/E0 - 1 vs N, the growth exponent (log-log least
   squares of the RMS vs N over a stated range), per-run growth exponents from
   the mean squared increments of the error (structure function), and the split
   of the error into the collision map's part and the integration's part.
3. What ``high_accuracy=True`` and a tolerance below epsilon add (energy
   error) and cost (wall time) on one scene.
4. Peak memory (max RSS) of ``heyroll run --t-end T --table npy --no-figures
   --progress off`` for about 1e5 and 1e7 collisions (and a tiny run for the
   fixed footprint), one subprocess each, sequentially: each is measured by a
   fresh Python wrapper process that reads its own RUSAGE_CHILDREN, so the
   numbers are per run (a single parent's RUSAGE_CHILDREN would report the
   maximum over all its children so far).

Writes validation/reports/long_runs.md and long_runs.png and prints the
report. ``--quick`` (a smoke test, under a minute) uses short runs and writes
the report into a temporary folder instead.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from energy_study import (  # noqa: E402
    EnergySink,
    fit_growth_exponent,
    log_grid,
    structure_exponent,
)

HERE = Path(__file__).resolve().parent
REPORTS = HERE / "reports"

#: Two steel balls as in the default scene (paper section 4), ball 1 started higher (phi = -1.2).
BALLS = """name = "balls-10-15"
g = 9.81
[track]
type = "circle"
radius = 1.0
[[bodies]]
shape = "solid_sphere"
radius = 0.10
density = 7850.0
phi = -1.2
dphi = 0.0
[[bodies]]
shape = "solid_sphere"
radius = 0.15
density = 7850.0
phi = 0.5
dphi = 0.0
[collision]
law = "hedrih"
restitution = 1.0
"""

#: Scenes drawn by a seeded random generator (R in [0.8, 2] m, 2 or 3 bodies
#: of random shape or kappa in [1.05, 2], r in [0.04, 0.3] R, mass log-uniform
#: in [0.2, 5] kg, random gaps and rates) and kept when they reached 1e6
#: elastic collisions with neither an inconsistent collision nor a recurrence.
#: Body: (shape or "kappa=K", r, m, phi, dphi).
GENERATED = [
    ("gen1", 0.96, "newton_generalized", [('solid_sphere', 0.162, 0.85, -1.348, -2.531), ('particle', 0.0, 0.679, -0.936, 0.194)]),
    ("gen4", 1.08, "newton_generalized", [('ring', 0.087, 0.248, -0.412, 1.356), ('ring', 0.197, 0.508, 0.257, 0.526)]),
    ("gen5", 1.55, "newton_generalized", [('particle', 0.0, 4.155, -0.821, 0.478), ('particle', 0.0, 1.631, -0.346, -0.343), ('kappa=1.946', 0.074, 0.895, -0.049, -1.509)]),
    ("gen6", 1.75, "newton_generalized", [('disk', 0.087, 0.32, -0.676, -0.307), ('kappa=1.405', 0.284, 2.307, 0.21, 2.137)]),
    ("gen7", 1.19, "newton_generalized", [('particle', 0.0, 0.234, -1.342, 1.071), ('kappa=1.914', 0.077, 1.305, -1.05, 0.642)]),
    ("gen8", 1.07, "hedrih", [('hollow_sphere', 0.239, 0.263, -1.119, 1.362), ('hollow_sphere', 0.268, 1.021, -0.076, 0.262)]),
    ("gen9", 1.36, "newton_generalized", [('hollow_sphere', 0.12, 1.766, -1.503, -1.566), ('disk', 0.232, 3.604, -1.087, -0.556)]),
    ("gen10", 1.49, "newton_generalized", [('kappa=1.517', 0.065, 0.887, -0.975, -0.427), ('disk', 0.313, 0.335, 0.108, 0.804)]),
    ("gen11", 1.34, "newton_generalized", [('ring', 0.231, 1.325, -1.491, 0.675), ('hollow_sphere', 0.334, 0.925, -0.825, -1.717), ('kappa=1.338', 0.33, 0.271, 0.732, 1.705)]),
    ("gen12", 1.37, "newton_generalized", [('hollow_sphere', 0.191, 4.946, -1.327, 1.679), ('ring', 0.152, 2.715, -0.159, 0.018), ('particle', 0.0, 3.231, 0.235, -0.44)]),
    ("gen15", 1.96, "hedrih", [('hollow_sphere', 0.544, 0.432, -0.571, 0.888), ('solid_sphere', 0.527, 1.793, 0.57, -0.001)]),
    ("gen16", 1.23, "newton_generalized", [('ring', 0.122, 0.204, -1.315, 0.174), ('particle', 0.0, 1.972, -0.563, 0.992)]),
    ("gen17", 1.43, "newton_generalized", [('disk', 0.122, 1.935, -1.139, -0.021), ('kappa=1.076', 0.303, 0.285, -0.32, -0.915)]),
    ("gen18", 1.02, "newton_generalized", [('disk', 0.104, 4.283, -1.365, 0.485), ('particle', 0.0, 0.981, -0.847, -0.356), ('ring', 0.119, 3.474, -0.137, 1.436)]),
    ("gen21", 1.0, "newton_generalized", [('particle', 0.0, 0.495, -1.583, 1.157), ('hollow_sphere', 0.297, 0.922, -1.367, -0.52), ('kappa=1.799', 0.088, 1.093, -0.259, 1.626)]),
    ("gen22", 1.95, "hedrih", [('solid_sphere', 0.389, 0.844, -0.649, 0.834), ('solid_sphere', 0.453, 3.383, 0.047, 0.456)]),
    ("gen27", 1.58, "newton_generalized", [('disk', 0.144, 0.247, -0.614, -0.217), ('kappa=1.824', 0.2, 0.663, 0.251, -1.696), ('hollow_sphere', 0.165, 0.433, 1.1, -1.113)]),
    ("gen29", 1.46, "newton_generalized", [('solid_sphere', 0.252, 0.605, -0.583, -1.247), ('ring', 0.065, 0.222, -0.217, -1.768)]),
    ("gen30", 1.45, "hedrih", [('kappa=1.294', 0.304, 0.393, -1.502, 1.457), ('ring', 0.2, 0.308, -0.241, 0.07)]),
    ("gen31", 0.81, "newton_generalized", [('hollow_sphere', 0.176, 0.313, -1.432, 0.309), ('solid_sphere', 0.145, 1.976, -0.787, -0.036)]),
    ("gen32", 0.89, "hedrih", [('disk', 0.197, 0.43, -0.989, 0.806), ('solid_sphere', 0.202, 0.276, 0.453, -1.217)]),
    ("gen35", 1.46, "newton_generalized", [('hollow_sphere', 0.167, 4.476, -0.64, -1.244), ('kappa=1.87', 0.082, 1.086, 0.371, -1.779)]),
    ("gen36", 1.19, "newton_generalized", [('solid_sphere', 0.048, 1.505, -1.163, -0.055), ('hollow_sphere', 0.131, 1.633, -0.592, 0.48)]),
    ("gen38", 1.57, "hedrih", [('solid_sphere', 0.212, 0.889, -1.187, -0.114), ('solid_sphere', 0.311, 0.346, -0.11, 1.067)]),
]

#: Controls: equal bodies started symmetrically; their floating-point
#: trajectories recur exactly after a few collisions (expected to be excluded).
CONTROLS = [
    ("control-equal-balls-sym", 1.0, "hedrih", [('solid_sphere', 0.1, 1.0, -0.5, 0.0), ('solid_sphere', 0.1, 1.0, 0.5, 0.0)]),
    ("control-equal-particles-sym", 1.0, "newton_generalized", [('particle', 0.0, 1.0, -0.5, 0.0), ('particle', 0.0, 1.0, 0.5, 0.0)]),
]

#: In --quick mode: the long-run scene plus these.
QUICK = ("gen1", "gen8", "gen11", "gen17", "gen22", "gen30", "gen36")


def scene_toml(name, radius, law, bodies) -> str:
    lines = [f'name = "{name}"', "g = 9.81", "[track]", 'type = "circle"', f"radius = {radius}"]
    for shape, r, m, phi, dphi in bodies:
        lines.append("[[bodies]]")
        if shape.startswith("kappa="):
            lines += [f"kappa = {shape.split('=')[1]}", f"radius = {r}"]
        else:
            lines.append(f'shape = "{shape}"')
            if shape != "particle":
                lines.append(f"radius = {r}")
        lines += [f"mass = {m}", f"phi = {phi}", f"dphi = {dphi}"]
    lines += ["[collision]", f'law = "{law}"', "restitution = 1.0"]
    return "\n".join(lines) + "\n"


def describe(name, radius, law, bodies) -> str:
    parts = []
    for shape, r, m, _phi, _dphi in bodies:
        label = shape.replace("solid_sphere", "ball").replace("hollow_sphere", "shell").replace("kappa=", "κ=")
        parts.append(label if shape == "particle" else f"{label} r={r:g}")
        parts[-1] += f" m={m:g}"
    return f"R={radius:g}; " + ", ".join(parts)


# ---------------------------------------------------------------------------
# one run (in a worker process)


def run_energy(task: dict) -> dict:
    """Run one scene through an EnergySink; return the sink's record and the run's figures."""
    import heyroll

    scene = heyroll.parse_scene(task["toml"])
    options = task.get("options", {})
    heyroll.simulate(scene, t_end=0.5, max_collisions=None, **options)  # compile outside the timing
    sink = EnergySink(task["n"], extra=task.get("extra", ()))
    started, cpu_started = time.perf_counter(), time.process_time()
    result = heyroll.simulate(scene, t_end=1e12, max_collisions=task["n"], sink=sink, **options)
    wall, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    out = dict(task, **sink.as_dict())
    out.update(
        status=result.status.value,
        message=result.message,
        collisions=result.n_collisions,
        t_final=float(result.t_final),
        steps=int(result.steps),
        wall_s=wall,
        cpu_s=cpu,
        rate=result.n_collisions / wall if wall > 0 else float("nan"),
        success=bool(result.success),
        fallbacks=int(result.settings.get("inconsistent_collisions", 0) or 0),
    )
    steps_per = out["steps"] / max(out["collisions"], 1)
    block_err = np.array(out["block_end_err"])
    if block_err.size >= 20:
        increments = np.diff(np.concatenate(([0.0], block_err)))
        out["sigma"] = float(np.sqrt(np.mean(increments**2) / out["block"]))  # RMS error step per collision
        out["drift"] = float(np.mean(increments) / out["block"])
        out["h"] = structure_exponent(block_err, step=out["block"])
    else:
        out["sigma"] = out["drift"] = out["h"] = float("nan")
    out["sigma_step"] = out["sigma"] / math.sqrt(steps_per) if steps_per > 0 else float("nan")
    out["model_collision"] = out["rounding_sigma"] * math.sqrt(steps_per)
    return out


def run_pool(tasks: list, workers: int) -> list:
    results = []
    started = time.perf_counter()
    ctx = mp.get_context("spawn")
    with ctx.Pool(workers) as pool:
        for r in pool.imap_unordered(run_energy, tasks):
            flag = " PERIODIC" if r["periodic"] else (" FROZEN" if r["frozen"] else "")
            print(
                f"  [{time.perf_counter() - started:6.0f} s] {r['name']}: {r['status']} {r['collisions']} collisions "
                f"in {r['wall_s']:.1f} s ({r['rate']:.3g}/s), E/E0-1 = {r['last_err']:+.3g}, "
                f"max {r['max_abs_err']:.3g}{flag}",
                flush=True,
            )
            results.append(r)
    order = {t["name"]: k for k, t in enumerate(tasks)}
    return sorted(results, key=lambda r: order[r["name"]])


# ---------------------------------------------------------------------------
# statistics


def excluded_reason(r: dict, n: int) -> str:
    if r["periodic"]:
        at, period = r["recurrence"]
        return f"exactly periodic: the state after collision {at} repeats the one {period} collision(s) earlier"
    if r["frozen"]:
        return f"energy error frozen ({r['distinct_last']} distinct values in the last chunk)"
    if not r["success"] or r["collisions"] < n:
        return f"stopped early: {r['status']} after {r['collisions']} collisions ({r['message']})"
    return ""


def ensemble(runs: list, n: int) -> dict:
    """RMS, mean, max |E/E0 - 1| (and the map / integration parts) across runs, on the grid up to n."""
    grid = log_grid(n)
    err, mp_, fl = [], [], []
    for r in runs:
        table = dict(zip(r["grid_n"], zip(r["grid_err"], r["grid_map"], r["grid_flight"])))
        rows = [table[k] for k in grid.tolist()]
        err.append([x[0] for x in rows])
        mp_.append([x[1] for x in rows])
        fl.append([x[2] for x in rows])
    err, mp_, fl = np.array(err), np.array(mp_), np.array(fl)
    m = err.shape[0]
    rms = np.sqrt(np.mean(err**2, axis=0))
    mean = np.mean(err, axis=0)
    sd = np.std(err, axis=0, ddof=1) if m > 1 else np.full_like(mean, np.nan)
    return {
        "grid": grid,
        "err": err,
        "rms": rms,
        "mean": mean,
        "t": mean / (sd / math.sqrt(m)),
        "max": np.max(np.abs(err), axis=0),
        "rms_map": np.sqrt(np.mean(mp_**2, axis=0)),
        "rms_flight": np.sqrt(np.mean(fl**2, axis=0)),
        "count": m,
    }


# ---------------------------------------------------------------------------
# high_accuracy and tolerance below epsilon

ACCURACY_CONFIGS = [
    ("tol = eps (default)", {}),
    ("high_accuracy", {"high_accuracy": True}),
    ("tol = 1e-17", {"tolerance": 1e-17}),
    ("high_accuracy, tol = 1e-17", {"high_accuracy": True, "tolerance": 1e-17}),
]


def time_run(toml: str, n: int, options: dict) -> tuple[float, float, int]:
    """(wall s, CPU s, steps) of a run to n collisions without a sink (compiled beforehand)."""
    import heyroll

    scene = heyroll.parse_scene(toml)
    heyroll.simulate(scene, t_end=0.5, max_collisions=None, **options)
    started, cpu_started = time.perf_counter(), time.process_time()
    result = heyroll.simulate(scene, t_end=1e12, max_collisions=n, **options)
    return time.perf_counter() - started, time.process_time() - cpu_started, int(result.steps)


def accuracy_study(toml: str, n: int, n_time: int, rounds: int, n_quad: int = 0) -> list:
    """Energy error of each setting (one run of n collisions, with the energy sink) and its cost.

    The cost is the best of ``rounds`` interleaved timing runs of ``n_time``
    collisions without a sink, in CPU time of this process (the machine may be
    shared: CPU time is less disturbed than wall time).
    """
    rows = []
    for label, options in ACCURACY_CONFIGS:
        r = run_energy({"name": label, "toml": toml, "n": n, "options": options})
        print(
            f"  {label}: {r['collisions']} collisions, {r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} s CPU, "
            f"{r['steps'] / max(r['collisions'], 1):.2f} steps/collision, E/E0-1 = {r['last_err']:+.3g}, "
            f"sigma/collision = {r['sigma']:.3g}",
            flush=True,
        )
        r["timing"] = []
        rows.append(r)
    for _ in range(rounds):
        for r, (_label, options) in zip(rows, ACCURACY_CONFIGS):
            r["timing"].append(time_run(toml, n_time, options))
    quad = None
    if n_quad:
        wall, cpu, steps = time_run(toml, n_quad, {"precision": "quad"})
        quad = {"n": n_quad, "wall": wall, "cpu": cpu, "steps": steps}
        print(f"  quad precision: {n_quad} collisions in {cpu:.2f} s CPU ({n_quad / cpu:.3g} per CPU s)", flush=True)
    for r in rows:
        r["quad"] = quad
        r["n_time"] = n_time
        r["best_wall"] = min(t[0] for t in r["timing"])
        r["best_cpu"] = min(t[1] for t in r["timing"])
        print(f"  {r['name']}: best of {rounds} x {n_time} collisions: {r['best_wall']:.2f} s wall, "
              f"{r['best_cpu']:.2f} s CPU ({n_time / r['best_cpu']:.3g} collisions per CPU s)", flush=True)
    return rows


# ---------------------------------------------------------------------------
# peak memory of the CLI

RSS_WRAPPER = (
    "import resource, subprocess, sys, time\n"
    "t = time.perf_counter()\n"
    "rc = subprocess.run(sys.argv[1:]).returncode\n"
    "w = time.perf_counter() - t\n"
    "print(rc, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, w)\n"
)


def heyroll_command() -> list:
    exe = Path(sys.executable).with_name("heyroll")
    if exe.exists():
        return [str(exe)]
    found = shutil.which("heyroll")
    if found:
        return [found]
    return [sys.executable, "-c", "from heyroll.interfaces.cli import main; main()"]


def measure_rss(t_end: float) -> dict:
    """Peak RSS of one ``heyroll run`` (a fresh wrapper process reads its own RUSAGE_CHILDREN)."""
    out = Path(tempfile.mkdtemp(prefix="heyroll-rss-"))
    try:
        cmd = heyroll_command() + [
            "run", "--out", str(out), "--t-end", repr(float(t_end)), "--table", "npy", "--no-figures",
            "--progress", "off",
        ]
        proc = subprocess.run([sys.executable, "-c", RSS_WRAPPER, *cmd], capture_output=True, text=True)
        rc, rss_kb, wall = proc.stdout.split()[-3:]
        summary = {}
        if (out / "summary.json").exists():
            import json

            summary = json.loads((out / "summary.json").read_text())
        table = out / "collisions.npy"
        return {
            "t_end": t_end,
            "rc": int(rc),
            "rss_mb": int(rss_kb) / 1024,
            "wall_s": float(wall),
            "collisions": summary.get("collisions"),
            "status": summary.get("status"),
            "table_mb": table.stat().st_size / 2**20 if table.exists() else float("nan"),
            "energy_change": (summary["energy_final"] / summary["energy_initial"] - 1) if summary else float("nan"),
            "stderr": proc.stderr.strip()[-500:],
        }
    finally:
        shutil.rmtree(out, ignore_errors=True)


# ---------------------------------------------------------------------------
# report


def fmt(x, spec=".3g"):
    return "n/a" if x is None or (isinstance(x, float) and not math.isfinite(x)) else format(x, spec)


def source_note() -> str:
    import heyroll

    note = f"heyroll imported from {Path(heyroll.__file__).parent}"
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, capture_output=True, text=True)
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--", "heyroll"], cwd=HERE.parent, capture_output=True, text=True
        )
        if head.returncode == 0:
            changed = len([x for x in dirty.stdout.splitlines() if x.strip()])
            note += f"; repository HEAD {head.stdout.strip()}" + (
                f" with {changed} uncommitted change(s) under heyroll/" if changed else ""
            )
    except OSError:
        pass
    return note


def make_figure(ens, runs_in, long_run, fit, fit_range, n, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(15, 4.8))
    FigureCanvasAgg(fig)
    ax1, ax2, ax3 = fig.subplots(1, 3)
    g = ens["grid"]
    for row in ens["err"]:
        ax1.loglog(g, np.maximum(np.abs(row), 1e-20), color="0.8", lw=0.6)
    if long_run is not None:
        ln = np.array(long_run["grid_n"])
        ax1.loglog(ln, np.maximum(np.abs(long_run["grid_err"]), 1e-20), color="tab:orange", lw=0.9,
                   label=f"{long_run['name']}: |E/E0-1|, to {long_run['collisions']:.0e}")
    ax1.loglog(g, ens["rms"], color="k", lw=2, label=f"ensemble RMS ({ens['count']} runs)")
    ax1.loglog(g, np.maximum(np.abs(ens["mean"]), 1e-20), "k--", lw=1, label="|ensemble mean|")
    p, c = fit
    lo, hi = fit_range
    xs = np.array([lo, hi], dtype=float)
    ax1.loglog(xs, c * xs**p, color="tab:red", lw=1.5, label=f"fit N^{p:.2f} over [{lo:.0e}, {hi:.0e}]")
    ax1.axhline(1e-13, color="tab:green", lw=0.8, ls=":", label="1e-13")
    ax1.set_xlabel("collisions N")
    ax1.set_ylabel("|E/E0 - 1|")
    ax1.set_ylim(1e-18, None)
    ax1.set_title("relative energy error (grey: each run)")
    ax1.legend(fontsize=7, loc="upper left")

    ax2.loglog(g, ens["rms"], color="k", lw=2, label="total")
    ax2.loglog(g, ens["rms_map"], color="tab:blue", label="collision map part")
    ax2.loglog(g, ens["rms_flight"], color="tab:purple", label="integration part")
    ax2.loglog(g, ens["rms"][-1] * np.sqrt(g / g[-1]), color="0.5", ls=":", label="∝ √N")
    ax2.set_xlabel("collisions N")
    ax2.set_ylabel("ensemble RMS of E/E0 - 1")
    ax2.set_title("where the error comes from")
    ax2.legend(fontsize=7, loc="upper left")

    if long_run is not None and long_run["block_end_err"]:
        b = long_run["block"]
        nb = np.arange(1, len(long_run["block_end_err"]) + 1) * b
        ax3.plot(nb, long_run["block_max"], color="tab:orange", lw=0.8, label=f"max |E/E0-1| per block of {b}")
        ax3.plot(nb, long_run["block_end_err"], color="k", lw=0.8, label="E/E0-1 at block ends")
        ax3.plot(nb, 2 * long_run["sigma"] * np.sqrt(nb), color="0.5", ls=":", label="± 2σ√N (σ from increments)")
        ax3.plot(nb, -2 * long_run["sigma"] * np.sqrt(nb), color="0.5", ls=":")
        ax3.set_xlabel("collisions N")
        ax3.set_ylabel("E/E0 - 1")
        ax3.set_title(f"long run: {long_run['name']}")
        ax3.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def build_report(args, runs, controls, excluded, ens, fits, long_run, accuracy, memory, wall_total) -> str:
    n = args.collisions
    dropped = {r["name"] for r, _ in excluded}
    runs_all, runs = runs, [r for r in runs if r["name"] not in dropped]
    L = []
    L += [
        "# heyroll long elastic runs: energy error vs number of collisions",
        "",
        f"Command: `python validation/long_runs.py --collisions {n} --long {args.long}"
        + (" --quick" if args.quick else "") + f"` ({wall_total / 60:.1f} min, {args.workers} worker processes, "
        f"cpu count {os.cpu_count()}).",
        f"Code: {source_note()}.",
        "",
        "Energy error: E/E0 - 1 just after each collision, E the total mechanical energy (eq. 26) evaluated in "
        "x87 extended precision from the float64 state, E0 that of the initial state (so evaluation adds ~1e-19). "
        "Runs stream through `energy_study.EnergySink`, which keeps the error on a log-spaced grid of collision "
        "numbers (20 per decade), at the end of each of 1000 blocks and each block's maximum, never the whole table. "
        "The *map* part is the sum of the energy jumps at collisions, the *integration* part the sum of the energy "
        "changes between collisions; they add up to the total. σ is the RMS of the error's increments over one block, "
        "divided by √(block): the random-walk step per collision (Brouwer: RMS(N) = σ√N). "
        "h is a run's own growth exponent, from the slope of √⟨(err(n+L) - err(n))²⟩ vs L (random walk 0.5, drift 1).",
        "",
    ]

    # verdict
    p, _ = fits["main"]
    k_end = -1
    rms_n, mean_n = ens["rms"][k_end], ens["mean"][k_end]
    L += ["## Result", ""]
    L += [
        f"- Ensemble of {ens['count']} runs to N = {n:.0e} collisions: RMS E/E0 - 1 = **{rms_n:.3g}**, mean = "
        f"{mean_n:+.3g} (|mean|/RMS = {abs(mean_n) / rms_n:.2f}, t = {ens['t'][k_end]:+.2f}; for a zero-mean ensemble "
        f"of {ens['count']}, |mean|/RMS ≈ 0.8/√{ens['count']} = {0.8 / math.sqrt(ens['count']):.2f} on average), max |E/E0 - 1| = "
        f"{ens['max'][k_end]:.3g}.",
        f"- Growth exponent (least squares of log RMS vs log N over {fits['range'][0]:.0e} ≤ N ≤ {fits['range'][1]:.0e}): "
        f"**{p:.3f}** (other ranges: "
        + ", ".join(f"[{a:.0e}, {b:.0e}]: {q:.3f}" for (a, b), (q, _) in fits["others"])
        + f"); median per-run exponent h = {np.nanmedian([r['h'] for r in runs]):.3f}.",
        f"- Split at N = {n:.0e}: RMS of the collision-map part {ens['rms_map'][k_end]:.3g}, of the integration "
        f"part {ens['rms_flight'][k_end]:.3g}.",
        f"- Source: one rounding of the state to double per integration step. Measured random-walk step per "
        f"integration step σ/step: median {np.nanmedian([r['sigma_step'] for r in runs]):.3g} (range "
        f"{np.nanmin([r['sigma_step'] for r in runs]):.3g}-{np.nanmax([r['sigma_step'] for r in runs]):.3g}); the "
        f"model 'each state component rounded to nearest once per step' (√Σ(∂E/∂x·ulp(x))²/12 / E0 over the "
        f"collision states) gives median {np.nanmedian([r['rounding_sigma'] for r in runs]):.3g} "
        f"(measured/model median {np.nanmedian([r['sigma_step'] / r['rounding_sigma'] for r in runs]):.2f}). "
        f"Predicted ensemble RMS at {n:.0e} from the model and each run's steps: "
        f"{math.sqrt(np.mean([r['model_collision'] ** 2 for r in runs])) * math.sqrt(n):.3g} (measured {rms_n:.3g}).",
    ]
    if long_run is not None:
        g = dict(zip(long_run["grid_n"], long_run["grid_err"]))
        at_n = g.get(n, float("nan"))
        L.append(
            f"- Long run ({long_run['name']}, {long_run['collisions']:.3g} collisions, status {long_run['status']}): "
            f"E/E0 - 1 = {at_n:+.3g} at {n:.0e}, **{long_run['last_err']:+.3g}** at {long_run['collisions']:.0e}, "
            f"max |E/E0 - 1| = {long_run['max_abs_err']:.3g}; its own exponent h = {long_run['h']:.3f}; "
            f"σ = {long_run['sigma']:.3g}/collision, so σ√N = {long_run['sigma'] * math.sqrt(long_run['collisions']):.3g}; "
            f"ensemble RMS at {n:.0e} × √(N/{n:.0e}) = {rms_n * math.sqrt(long_run['collisions'] / n):.3g}."
        )
    goal_rms = rms_n <= 1e-13
    L += [
        "",
        f"Goals: RMS |dE/E| ≤ 1e-13 at N = {n:.0e} collisions (the brief: at 1e6): "
        + (f"met (RMS {rms_n:.3g})" if goal_rms else f"**not met** (RMS {rms_n:.3g})")
        + f"; exponent ≤ 0.6: {'met' if p <= 0.6 else '**not met**'} ({p:.3f}); |mean| ≪ RMS: "
        + ("yes" if abs(ens["t"][k_end]) < 2 else "**no**")
        + f" (|mean|/RMS = {abs(mean_n) / rms_n:.2f}, |t| = {abs(ens['t'][k_end]):.2f}).",
        "",
    ]

    # excluded
    L += ["## Excluded runs", ""]
    if excluded:
        for r, why in excluded:
            L.append(f"- {r['name']} ({r['law']}; {r['desc']}): {why}.")
    else:
        L.append("- none")
    L.append("")

    # ensemble vs N
    L += [
        "## Ensemble vs N",
        "",
        "| N | runs | RMS E/E0-1 | mean | mean/RMS | t | max abs | RMS map part | RMS integration part |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for k, N in enumerate(ens["grid"].tolist()):
        if N in (1, 10, 100, 1000, 10**4, 10**5, 10**6, 10**7) or N == ens["grid"][-1]:
            L.append(
                f"| {N:.0e} | {ens['count']} | {ens['rms'][k]:.3g} | {ens['mean'][k]:+.3g} | "
                f"{ens['mean'][k] / ens['rms'][k]:+.2f} | {ens['t'][k]:+.2f} | {ens['max'][k]:.3g} | "
                f"{ens['rms_map'][k]:.3g} | {ens['rms_flight'][k]:.3g} |"
            )
    L.append("")

    # per run
    L += [
        "## Runs",
        "",
        "| run | law | bodies | status | collisions | t_final s | CPU s | coll per CPU s | steps/coll | E/E0-1 at end "
        "| max abs | map part | integration part | σ/collision | σ/step | rounding model/step | h | fallbacks | recurrence |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs_all + controls:
        rec = "none" if r["recurrence"] is None else f"at {r['recurrence'][0]}, period {r['recurrence'][1]}"
        L.append(
            f"| {r['name']} | {r['law']} | {r['desc']} | {r['status']} | {r['collisions']} | {r['t_final']:.3g} | "
            f"{r['cpu_s']:.1f} | {r['collisions'] / r['cpu_s']:.3g} | {r['steps'] / max(r['collisions'], 1):.1f} | "
            f"{r['last_err']:+.3g} | {r['max_abs_err']:.3g} | {r['map_total']:+.3g} | {r['flight_total']:+.3g} | "
            f"{fmt(r['sigma'])} | {fmt(r['sigma_step'])} | {fmt(r['rounding_sigma'])} | {fmt(r['h'], '.2f')} | "
            f"{r['fallbacks']} | {rec} |"
        )
    L.append("")

    # accuracy
    if accuracy:
        base = accuracy[0]
        L += [
            f"## high_accuracy and tolerance below epsilon ({base['scene_name']}, {accuracy[0]['n']:.0e} collisions)",
            "",
            "One trajectory per setting, so E/E0 - 1 at the end is one draw of a random walk; σ (from 1000 block "
            "increments, about ±5 %) is the comparable number. Cost: best of "
            f"{len(base['timing'])} interleaved runs of {base['n_time']} collisions without a sink, in CPU seconds "
            "(the machine was shared with other jobs, so wall times of the long runs are only indicative).",
            "",
            "| setting | coll per CPU s | cost vs default | steps/coll | E/E0-1 at end | max abs | σ/collision | σ√N "
            "| σ/step | h |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in accuracy:
            L.append(
                f"| {r['name']} | {r['n_time'] / r['best_cpu']:.3g} | {r['best_cpu'] / base['best_cpu']:.2f}× | "
                f"{r['steps'] / max(r['collisions'], 1):.2f} | {r['last_err']:+.3g} | {r['max_abs_err']:.3g} | "
                f"{fmt(r['sigma'])} | {fmt(r['sigma'] * math.sqrt(r['collisions']))} | {fmt(r['sigma_step'])} | "
                f"{fmt(r['h'], '.2f')} |"
            )
        quad = base.get("quad")
        if quad:
            L += [
                "",
                f"For scale: the whole integration in quad precision (`precision=\"quad\"`, the step that removes "
                f"the rounding floor) runs {quad['n'] / quad['cpu']:.3g} collisions per CPU s "
                f"({quad['cpu'] / quad['n'] / (base['best_cpu'] / base['n_time']):.0f}× the default's cost; "
                f"{quad['n']} collisions timed, {quad['steps'] / quad['n']:.2f} steps/collision), i.e. "
                f"{1e6 * quad['cpu'] / quad['n'] / 60:.0f} CPU min per 1e6 collisions.",
            ]
        L.append("")

    # memory
    if memory:
        L += [
            "## Peak memory of `heyroll run --t-end T --table npy --no-figures --progress off` (default scene)",
            "",
            "| T s | collisions | status | wall s | peak RSS MB | table MB | E/E0-1 (summary) |",
            "|---|---|---|---|---|---|---|",
        ]
        for m in memory:
            L.append(
                f"| {m['t_end']:.3g} | {m['collisions']} | {m['status']} (rc {m['rc']}) | {m['wall_s']:.1f} | "
                f"{m['rss_mb']:.1f} | {m['table_mb']:.1f} | {fmt(m['energy_change'], '+.3g')} |"
            )
        runs_m = [m for m in memory if m["collisions"]]
        if len(runs_m) >= 2:
            small, big = runs_m[-2], runs_m[-1]
            growth = big["rss_mb"] - small["rss_mb"]
            flat = abs(growth) < max(20.0, 0.1 * small["rss_mb"])
            L += [
                "",
                f"From {small['collisions']} to {big['collisions']} collisions the peak RSS changes by {growth:+.1f} MB "
                f"({small['rss_mb']:.0f} → {big['rss_mb']:.0f} MB) while the table grows to {big['table_mb']:.0f} MB: "
                + ("memory is flat." if flat else "**memory is not flat**.")
                + " (The run holds up to one chunk of 65536 collision records plus the first chunk, kept for the "
                "figures, so the RSS grows until about 1.3e5 collisions and should stay flat after.)",
            ]
        for m in memory:
            if m["rc"] != 0:
                L += ["", f"T = {m['t_end']:.3g}: exit code {m['rc']}: {m['stderr']}"]
        L.append("")
    L += ["![energy error vs collisions](long_runs.png)", ""]
    return "\n".join(L)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--collisions", type=int, default=1_000_000, help="collisions per ensemble run")
    parser.add_argument("--long", type=int, default=10_000_000, help="collisions of the long run")
    parser.add_argument("--accuracy-collisions", type=int, default=None, help="default: --collisions")
    parser.add_argument(
        "--memory-collisions", default=None,
        help="comma-separated collision counts for the RSS runs (default 100000,LONG; quick 10000,100000)",
    )
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--timing-rounds", type=int, default=3, help="interleaved timing rounds per setting")
    parser.add_argument("--quick", action="store_true", help="a short smoke run (< 1 min), report in a temp folder")
    parser.add_argument("--skip-accuracy", action="store_true")
    parser.add_argument("--skip-memory", action="store_true")
    parser.add_argument("--out", type=Path, default=None, help="report folder (default validation/reports)")
    args = parser.parse_args()
    if args.quick:
        args.collisions = min(args.collisions, 20_000)
        args.long = min(args.long, 100_000)
    args.long = max(args.long, args.collisions)
    n_acc = args.accuracy_collisions or (min(args.collisions, 20_000) if args.quick else args.collisions)
    if args.memory_collisions:
        mem_counts = [int(float(x)) for x in args.memory_collisions.split(",")]
    else:
        mem_counts = [10_000, 100_000] if args.quick else [100_000, args.long]
    out_dir = args.out or (Path(tempfile.mkdtemp(prefix="long-runs-quick-")) if args.quick else REPORTS)
    out_dir.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()

    specs = [("balls-10-15", 1.0, "hedrih", [("solid_sphere", 0.10, 32.882, -1.2, 0.0),
                                              ("solid_sphere", 0.15, 110.977, 0.5, 0.0)])] + GENERATED
    if args.quick:
        specs = [s for s in specs if s[0] == "balls-10-15" or s[0] in QUICK]
    tasks = []
    for k, (name, radius, law, bodies) in enumerate(specs):
        toml = BALLS if name == "balls-10-15" else scene_toml(name, radius, law, bodies)
        n = args.long if k == 0 else args.collisions
        tasks.append({"name": name, "law": law, "desc": describe(name, radius, law, bodies), "toml": toml, "n": n,
                      "extra": (args.collisions,)})
    control_tasks = [
        {"name": name, "law": law, "desc": describe(name, radius, law, bodies),
         "toml": scene_toml(name, radius, law, bodies), "n": args.collisions}
        for name, radius, law, bodies in CONTROLS
    ]
    print(f"1. ensemble: {len(tasks)} scenes to {args.collisions} collisions ({tasks[0]['name']} to {args.long}), "
          f"{len(control_tasks)} controls, {args.workers} workers", flush=True)
    done = run_pool(tasks + control_tasks, args.workers)
    by_name = {r["name"]: r for r in done}
    runs = [by_name[t["name"]] for t in tasks]
    controls = [by_name[t["name"]] for t in control_tasks]

    n = args.collisions
    excluded = [(r, excluded_reason(r, n)) for r in runs + controls if excluded_reason(r, n)]
    included = [r for r in runs if not excluded_reason(r, n)]
    if not included:
        raise SystemExit("no run is left for the statistics")
    ens = ensemble(included, n)
    lo = min(1000, max(10, n // 100))
    main_fit = fit_growth_exponent(ens["grid"], ens["rms"], lo, n)
    others = []
    for a in (100, 10_000):
        if a < n // 10:
            others.append(((a, n), fit_growth_exponent(ens["grid"], ens["rms"], a, n)))
    fits = {"main": main_fit, "range": (lo, n), "others": others}
    long_run = runs[0] if runs[0] in included else None

    accuracy = []
    if not args.skip_accuracy:
        print(f"2. high_accuracy / tolerance on {tasks[0]['name']}, {n_acc} collisions each", flush=True)
        accuracy = accuracy_study(
            tasks[0]["toml"], n_acc, min(n_acc, 200_000), args.timing_rounds, max(500, min(n_acc // 200, 5000))
        )
        for r in accuracy:
            r["scene_name"] = tasks[0]["name"]

    memory = []
    if not args.skip_memory:
        print("3. peak RSS of heyroll run (default scene, ~0.9 collisions per simulated second)", flush=True)
        for count in [100] + mem_counts:
            t_end = 100.0 if count == 100 else round(count / 0.9, -2)
            m = measure_rss(t_end)
            print(f"  T = {t_end:.3g}: {m['collisions']} collisions, {m['wall_s']:.1f} s, peak RSS {m['rss_mb']:.1f} MB, "
                  f"table {m['table_mb']:.1f} MB, rc {m['rc']}", flush=True)
            memory.append(m)

    wall_total = time.perf_counter() - started
    make_figure(ens, included, long_run, main_fit, fits["range"], n, out_dir / "long_runs.png")
    text = build_report(args, runs, controls, excluded, ens, fits, long_run, accuracy, memory, wall_total)
    (out_dir / "long_runs.md").write_text(text, encoding="utf-8")
    print()
    print(text)
    print(f"wrote {out_dir / 'long_runs.md'} and {out_dir / 'long_runs.png'}")


if __name__ == "__main__":
    main()
