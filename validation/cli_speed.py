"""Collisions per second through the CLI, per table format, against the bare integration (issue 12).

    python validation/cli_speed.py [--t-end 200000] [--repeat 3]

Times, interleaved and side by side in one process, (a) the floor:
``heyroll.simulate(default scene, t_end=T)`` with no sink, and (b)
``heyroll run --t-end T --no-figures --progress off --table FORMAT`` for csv,
npy and parquet (the CLI's ``main`` in-process, into a temporary directory,
whole call timed: set-up, streamed table, summary). The best of ``--repeat``
rounds counts (the machine is shared and noisy). The goals: a binary table at
least 0.9 of the floor's rate, CSV at least 0.75. The JIT compilation is done
once before timing. Prints the figures and writes validation/reports/cli_speed.md.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import tempfile
import time
from pathlib import Path

import heyroll
from heyroll.interfaces.cli import main as cli_main
from heyroll.interfaces.outputs import versions

GOALS = {"csv": 0.75, "npy": 0.9, "parquet": 0.9}


def bare(t_end: float) -> tuple[int, float]:
    t0 = time.perf_counter()
    result = heyroll.simulate(heyroll.default_scene(), t_end=t_end)
    return result.n_collisions, time.perf_counter() - t0


def through_cli(t_end: float, table: str) -> tuple[int, float]:
    with tempfile.TemporaryDirectory() as out:
        args = ["run", "--out", out, "--t-end", repr(t_end), "--no-figures", "--progress", "off", "--table", table]
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):
            code = cli_main(args)
        wall = time.perf_counter() - t0
        if code != 0:
            raise SystemExit(f"heyroll {' '.join(args)} exited {code}")
        return json.loads((Path(out) / "summary.json").read_text())["collisions"], wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=2e5)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    tables = ["csv", "npy"]
    try:
        import pyarrow

        tables.append("parquet")
        arrow = f", pyarrow {pyarrow.__version__}"
    except ImportError:
        arrow = ", no pyarrow: parquet not measured"
    runs = {"floor (no sink)": bare, **{f"cli --table {t}": (lambda T, t=t: through_cli(T, t)) for t in tables}}
    bare(1.0)  # compile once (heyoka caches compiled code per scene shape)
    lines = [
        "# heyroll through the CLI: collisions/s per table format against the bare integration",
        "",
        f"default scene, t_end = {args.t_end:g} s, best of {args.repeat} interleaved rounds, one core "
        f"(cpu count {os.cpu_count()}, load average {os.getloadavg()[0]:.2f} at the start), "
        f"versions {versions()}{arrow}",
        "",
        "| round | run | collisions | wall s | coll/s |",
        "|---|---|---|---|---|",
    ]
    best, counts = {}, {}
    for k in range(1, args.repeat + 1):  # alternate, so every run sees the same machine load
        for name, run in runs.items():
            n, wall = run(args.t_end)
            counts.setdefault(name, n)
            if n != counts[name] or n != counts["floor (no sink)"]:
                raise SystemExit(f"{name}: {n} collisions, the floor had {counts['floor (no sink)']}")
            lines.append(f"| {k} | {name} | {n} | {wall:.3f} | {n / wall:.3g} |")
            best[name] = max(best.get(name, 0.0), n / wall)
    floor = best["floor (no sink)"]
    lines += ["", "| run | best coll/s | / floor | goal | met |", "|---|---|---|---|---|"]
    for name, rate in best.items():
        goal = GOALS.get(name.removeprefix("cli --table "))
        met = "" if goal is None else "yes" if rate / floor >= goal else "NO"
        lines.append(f"| {name} | {rate:.3g} | {rate / floor:.2f} | {'' if goal is None else f'>= {goal}'} | {met} |")
    text = "\n".join(lines) + "\n"
    print(text)
    out = Path(__file__).parent / "reports"
    out.mkdir(exist_ok=True)
    (out / "cli_speed.md").write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
