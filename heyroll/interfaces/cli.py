"""The ``heyroll`` command line: a thin layer over the Python API.

Exit codes: 0 success; 1 the run ended without success (its status and
message are in summary.json); 2 bad input (one line on stderr, nothing
written).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import math
import signal
import re
import sys
from pathlib import Path

from ..errors import SceneError
from ..model.scene import Scene
from ..model.table import is_table
from ..simulation.driver import signal_handled, simulate
from ..simulation.precision import Precision
from ..simulation.result import counted
from .scene_file import default_scene, default_scene_text, load_scene

EXIT_OK, EXIT_RUN_FAILED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130


class BadInput(SceneError):
    """A command-line value breaks a rule."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, like every other bad input
        self.exit(EXIT_BAD_INPUT, f"heyroll: error: {message}\n")


def _positive_time(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise BadInput("--t-end", f"must be a number, got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise BadInput("--t-end", f"must be a finite number > 0, got {text}")
    return value


def _tolerance(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise BadInput("--tolerance", f"must be a number, got {text!r}") from None
    if not math.isfinite(value) or not 0 < value < 1:
        raise BadInput("--tolerance", f"must be a number > 0 and < 1, got {text}")
    return value


def _collision_count(text: str, field: str = "--max-collisions", least: int = 0) -> int:
    try:
        value = int(text)
    except ValueError:
        raise BadInput(field, f"must be a whole number, got {text!r}") from None
    if value < least:
        raise BadInput(field, f"must be >= {least}, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="heyroll", description="Collisions of bodies in rolling, solved exactly with heyoka.")
    from .._version import __version__

    parser.add_argument("--version", action="version", version=f"heyroll {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    run = sub.add_parser("run", help="integrate a scene and write its collision table, summary and figures")
    run.add_argument("scene", nargs="?", help="scene file (TOML); the built-in default scene if omitted")
    run.add_argument("--out", default="heyroll-out", help="output directory (default: heyroll-out)")
    run.add_argument("--t-end", dest="t_end", help="end time in s (overrides [run] t_end)")
    run.add_argument("--max-collisions", dest="max_collisions", help="stop after N collisions")
    run.add_argument("--max-events", dest="max_events",
                     help="stop after N events of every kind together: collisions, junction passages, limiter "
                          "impacts, contact mode changes, friction mode changes, stroboscopic samples (default 2000000; 'none' "
                          "for no limit)")
    run.add_argument(
        "--precision", default="double",
        help="double | long (x87 extended) | quad | mp:BITS: the whole integration, every event and collision "
             "map in that type (default: double)"
    )
    run.add_argument("--tolerance", help="heyoka's error tolerance (default: the precision's epsilon; larger is faster and "
                     "less accurate: validation/reports/work_precision.md)")
    run.add_argument("--fast", action="store_true",
                     help="heyoka's fast-math flags: faster steps, results no longer reproducible to the last bit "
                          "(validation/reports/work_precision.md)")
    run.add_argument("--high-accuracy", action="store_true", help="heyoka's compensated summation (measured: no gain on collision times or energy, ~1%% cost)")
    run.add_argument("--no-figures", action="store_true", help="skip the figures (every .png of the run)")
    run.add_argument(
        "--table", choices=("csv", "npy", "parquet"), default="csv",
        help="collision table format: csv (default), npy (float64 columns, for long runs; numpy.load reads it) "
             "or parquet (the same columns; needs pyarrow: pip install 'heyroll[parquet]')",
    )
    run.add_argument("--progress", choices=("auto", "on", "off"), default="auto", help="progress bar on stderr (auto: if a terminal)")
    val = sub.add_parser("validate", help="write a validation report: engine vs exact reference, series error, horizon")
    val.add_argument("scene", nargs="?", help="scene file (TOML); the built-in default scene if omitted")
    val.add_argument("--out", default="heyroll-validation", help="output directory (default: heyroll-validation)")
    val.add_argument("--collisions", default="20", help="collisions compared with the reference (default: 20)")
    _add_progress(val, "the report's sections")
    eq = sub.add_parser("equilibria", help="relative equilibria of a body on its track, in a fixed or turning plane (centres, saddles)")
    eq.add_argument("scene", help="scene file (TOML): a circle, a curve y = f(x) or an arc chain")
    eq.add_argument("--json", action="store_true", help="print a JSON array of {x, type} sorted by x")
    eq.add_argument("--body", default="1", help="which body (1..N; default 1): equilibria depend on its radius")
    por = sub.add_parser("portrait", help="phase portrait, energy surface and bifurcation diagram of one body of a scene")
    por.add_argument("scene", help="scene file (TOML): a circle, a curve y = f(x) or an arc chain")
    por.add_argument("--out", default="heyroll-portrait", help="output directory (default: heyroll-portrait)")
    por.add_argument("--body", default="1", help="which body (1..N; default 1)")
    por.add_argument("--omega-max", dest="omega_max", help="bifurcation diagram from 0 to this Omega (rad/s)")
    _add_progress(por, "the portrait's pieces")
    bil = sub.add_parser("billiard", help="billiard tables (paper section 7): periodic orbits and their stability")
    bsub = bil.add_subparsers(dest="billiard_command", required=True, parser_class=_Parser)
    orb = bsub.add_parser("orbits", help="periodic orbits of a table scene's ball: perimeter, stability (trace)")
    orb.add_argument("scene", help="table scene file (TOML, track type = \"table\")")
    orb.add_argument("--period", required=True, help="number of cushion impacts per period (>= 2)")
    orb.add_argument("--rotation", default=None,
                     help="rotation number p of p/period (default 1; on a polygonal table every p)")
    orb.add_argument("--ball", default="1", help="which ball's radius sets the curve of its centre (default 1)")
    orb.add_argument("--json", action="store_true", help="print a JSON array of orbits")
    _add_progress(orb, "the orbit searches")
    bpo = bsub.add_parser("portrait", help="the Birkhoff map of many launches of one ball, coloured by launch")
    bpo.add_argument("scene", help="table scene file (TOML, track type = \"table\")")
    bpo.add_argument("--runs", default="12", help="launches (default 12), spread over the cushion and the angle")
    bpo.add_argument("--impacts", default="300", help="cushion impacts per launch (default 300)")
    bpo.add_argument("--ball", default="1", help="which ball (alone on the table; default 1)")
    bpo.add_argument("--out", default="heyroll-birkhoff", help="output directory (default: heyroll-birkhoff)")
    _add_progress(bpo, "launches")
    _add_sweep_parsers(sub)
    show = sub.add_parser("default-scene", help="print the built-in default scene as TOML")
    show.set_defaults()
    return parser


#: A negative number with an exponent (argparse's own test takes only -1 and -0.5 for numbers).
_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")


def _negative_values(argv: list[str]) -> list[str]:
    """``--option -1e-10`` as ``--option=-1e-10``: argparse took '-1e-10' for an option and said 'expected one
    argument' instead of the option's own one-line rule (acceptance test)."""
    out: list[str] = []
    for token in argv:
        if out and out[-1].startswith("--") and "=" not in out[-1] and _NEGATIVE_NUMBER.match(token):
            out[-1] = f"{out[-1]}={token}"
        else:
            out.append(token)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = _negative_values(sys.argv[1:] if argv is None else list(argv))
    if not argv:  # no command: the usage and the commands, then the one-line error
        parser.print_help(sys.stderr)
        print("heyroll: error: a command is required", file=sys.stderr)
        return EXIT_BAD_INPUT
    args = parser.parse_args(argv)
    _CREATED.clear()
    try:
        return _command(args, argv)
    finally:
        _unlock()


def _command(args, argv) -> int:
    try:
        if args.command == "default-scene":
            sys.stdout.write(default_scene_text())
            return EXIT_OK
        if args.command == "validate":
            return _validate(args)
        if args.command == "equilibria":
            return _equilibria(args)
        if args.command == "portrait":
            return _portrait(args)
        if args.command == "sweep":
            return _sweep(args, argv)
        if args.command == "plot":
            return _plot(args)
        if args.command == "billiard":
            return _billiard_orbits(args) if args.billiard_command == "orbits" else _billiard_portrait(args)
        return _run(args)
    except SceneError as exc:
        _unlock()
        for created in _CREATED:  # nothing half-written: output directories made for nothing go, innermost first
            try:
                created.rmdir()  # (only if empty)
            except OSError:
                pass
        print(f"heyroll: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:  # a Ctrl-C outside a run's own handling (loading, compiling, printing): one line
        print(f"heyroll: {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def _run(args) -> int:
    # Every input is checked before anything is written.
    t_end = _positive_time(args.t_end) if args.t_end is not None else None
    max_collisions = _collision_count(args.max_collisions) if args.max_collisions is not None else ...
    max_events = _max_events(args.max_events)
    scene = load_scene(args.scene) if args.scene else default_scene()
    out = _out_dir(args.out)
    precision = Precision.parse(args.precision, "--precision")
    tolerance = _tolerance(args.tolerance) if args.tolerance is not None else None
    if args.table in ("npy", "parquet") and precision.name != "double":
        raise BadInput("--table", f"{args.table} holds float64 columns: use csv for long, quad and MPFR runs")
    if args.table == "parquet":
        try:
            import pyarrow.parquet  # noqa: F401  (the parquet sink's writer)
        except ImportError:
            raise BadInput("--table", "parquet needs pyarrow: pip install 'heyroll[parquet]'") from None
    from .outputs import FiguresInterrupted, prepare_run_directory, remove_run_files, table_sink, write_run

    _writable(out)
    prepare_run_directory(out)
    try:
        sink = table_sink(out, args.table)
        with _progress_bar(args.progress, scene, t_end) as progress, _sigterm_as_interrupt(), _heyoka_messages():
            result = simulate(
                scene, t_end=t_end, max_collisions=max_collisions, max_events=max_events, precision=precision,
                high_accuracy=args.high_accuracy, tolerance=tolerance, fast_math=args.fast, sink=sink,
                progress=progress,
            )
        if result.status.value == "interrupted" and not args.no_figures:
            # the figures of a long run take a while (14 s for 60,000 impacts): say how to skip them
            print("interrupted: writing the table and summary.json, then the figures (Ctrl-C again to skip them)",
                  file=sys.stderr, flush=True)
        with _sigterm_as_interrupt():
            written = write_run(result, out, scene_source=args.scene or "<default scene>",
                                figures=not args.no_figures, sink=sink)
    except FiguresInterrupted:
        print(f"{result.status.value}: {result.message}")
        print(f"interrupted while drawing the figures: {out}/ holds the whole table and summary.json, no figures")
        return EXIT_INTERRUPTED
    except OSError as exc:
        # A full disk or a directory that went away: no half-written set of outputs.
        try:
            remove_run_files(out)
        except OSError:
            pass
        raise BadInput("--out", f"writing the run's outputs to {out} failed: {exc.strerror or exc}; nothing kept") from None
    rate = result.n_collisions / result.wall_time_s if result.wall_time_s > 0 else float("nan")
    print(f"{scene.describe()}")
    print(f"{result.status.value}: {result.message}")
    if str(written["files"].get("figures", "")).startswith("none:"):
        print(f"no figures: {written['files']['figures'][len('none: '):]}")
    for warning in result.settings.get("warnings", []):
        print(f"warning: {warning}")
    if is_table(result):
        print(f"{counted(result.n_collisions, 'impact')} ({result.n_cushion} on the cushion), t_final = "
              f"{float(result.t_final):.17g} s, energy {result.energy_initial:.17g} -> {result.energy_final:.17g} J, "
              f"{result.wall_time_s:.3g} s wall ({rate:.3g} impacts/s incl. set-up)")
        print(f"wrote {out}/")
        return result.status.exit_code
    passages = result.summary()
    print(
        f"{counted(result.n_collisions, 'collision')}, {counted(passages['limiter_impacts'], 'limiter impact')}, "
        f"{counted(passages['junction_passages'], 'junction passage')}, t_final = {float(result.t_final):.17g} s, "
        f"energy {result.energy_initial:.17g} -> {result.energy_final:.17g} J, "
        f"{result.wall_time_s:.3g} s wall ({rate:.3g} collisions/s incl. set-up)"
    )
    print(f"wrote {out}/")
    return result.status.exit_code


@contextlib.contextmanager
def _heyoka_messages():
    """heyoka's C++ logger writes its warnings on stdout, into heyroll's own output: while the
    engine runs, file descriptor 1 goes to a temporary file; its lines are then repeated on
    stderr as 'heyroll: heyoka: ...' (stdout keeps only heyroll's report)."""
    import tempfile

    sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:  # no real stdout (embedded): nothing to route
        yield
        return
    with tempfile.TemporaryFile() as captured:
        os.dup2(captured.fileno(), 1)
        try:
            yield
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
            captured.seek(0)
            for line in captured.read().decode(errors="replace").splitlines():
                if line.strip():
                    print(f"heyroll: heyoka: {line.strip()}", file=sys.stderr)


@contextlib.contextmanager
def _progress_bar(mode: str, scene, t_end):
    """A tqdm bar over simulated time, or None (no bar)."""
    import tqdm

    disable = {"on": False, "off": True, "auto": None}[mode]  # tqdm: None = only on a terminal
    total = float(scene.run.t_end if t_end is None else t_end)
    bar = tqdm.tqdm(total=total, unit="s", desc="heyroll", disable=disable, file=sys.stderr,
                    bar_format="{desc}: {percentage:3.0f}%|{bar}| t = {n:.4g}/{total:.4g} s {postfix}")
    if bar.disable:
        yield None
        return

    def progress(t, collisions):
        bar.n = min(t, total)
        bar.set_postfix_str(counted(collisions, "collision"), refresh=False)
        bar.refresh()

    try:
        yield progress
    finally:
        bar.close()


@contextlib.contextmanager
def _count_bar(mode: str, desc: str, unit: str):
    """A tqdm bar over counted pieces of work (a report's sections, a portrait's launches, orbit searches),
    or None (no bar). It yields ``progress(done, total, stage=None)``: the bar learns its total from the first
    call, and ``stage`` names what comes next."""
    import tqdm

    disable = {"on": False, "off": True, "auto": None}[mode]  # tqdm: None = only on a terminal
    bar = tqdm.tqdm(total=None, unit=unit, desc=desc, disable=disable, file=sys.stderr, miniters=1)
    if bar.disable:
        yield None
        return

    def progress(done, total, stage=None):
        bar.total = total
        bar.n = done
        if stage is not None:
            bar.set_postfix_str(stage, refresh=False)
        bar.refresh()

    try:
        yield progress
    finally:
        bar.close()


def _add_progress(parser, what: str) -> None:
    parser.add_argument("--progress", choices=("auto", "on", "off"), default="auto",
                        help=f"progress bar over {what} on stderr (auto: if a terminal)")


def _sigterm_as_interrupt():
    """SIGTERM ends a run like Ctrl-C: the table up to the last collision, status interrupted."""

    def handler(signum, frame):
        raise KeyboardInterrupt

    return signal_handled(signal.SIGTERM, handler)


def _max_events(text):
    if text is None:
        return ...
    if text.strip().lower() == "none":
        return None
    try:
        n = int(text)
    except ValueError:
        n = None
    if n is None or n < 1:
        raise BadInput("--max-events", f"must be a whole number >= 1 (or 'none'), got {text!r}")
    return n


def _out_dir(text: str) -> Path:
    """--out: a directory path (created if missing)."""
    if not text or not text.strip():
        raise BadInput("--out", "must name a directory, got an empty string")
    out = Path(text)
    if out.exists() and not out.is_dir():
        raise BadInput("--out", f"{out} exists and is not a directory")
    return out


#: Output directories this command created: removed again where bad input stops it before anything is written
#: (an empty --out left behind by `billiard portrait --ball 5`: acceptance test).
_CREATED: list = []


def _writable(out: Path) -> None:
    """Create ``out`` and check that files can be written in it (after every other input is checked)."""
    from .outputs import writable_problem

    missing = out
    while not missing.exists() and missing != missing.parent:  # the directories it will make, innermost first
        _CREATED.append(missing)
        missing = missing.parent
    problem = writable_problem(out)
    if problem:
        raise BadInput("--out", problem)
    _lock(out)


#: The --out locks this command holds (outputs.hold_directory): (directory, open lock file).
_LOCKS: list = []


def _lock(out: Path) -> None:
    """Hold ``out`` while this command writes there (outputs.hold_directory)."""
    from .outputs import busy_message, hold_directory

    if any(held == out for held, _ in _LOCKS):
        return
    handle = hold_directory(out)
    if handle is None:
        raise BadInput("--out", busy_message(out))
    _LOCKS.append((out, handle))


def _unlock() -> None:
    """Let the locks go."""
    while _LOCKS:
        _out, handle = _LOCKS.pop()
        handle.close()


def _path_scene(path: str, command: str) -> Scene:
    """The scene of ``heyroll equilibria`` / ``portrait``: any track (on a circle the
    coordinate is phi in [-pi, pi), periodic, with no limiters)."""
    return _not_a_table(load_scene(path), command)


def _not_a_table(scene, command: str):
    """A scene for a command of the vertical-plane tracks: a billiard table is refused in one line."""
    if is_table(scene):
        hint = ("its impacts are checked against the mpmath reference in tests/test_billiards.py and "
                "validation/billiards.py" if command == "validate" else "try: heyroll billiard orbits")
        raise BadInput("scene", f"heyroll {command} works on tracks in a vertical plane, not on a billiard table "
                                f"({hint})")
    return scene


def _body_number(text: str, scene: Scene) -> int:
    n = _collision_count(text, "--body")
    if not 1 <= n <= len(scene.bodies):
        raise BadInput("--body", f"must be in 1..{len(scene.bodies)}, got {n}")
    return n - 1


def _table_scene(path: str, command: str):
    """The scene of ``heyroll billiard COMMAND``: a billiard table, or one line and exit 2."""
    scene = load_scene(path)
    if not is_table(scene):
        raise BadInput("scene", f'billiard {command} needs a table scene ([track] type = "table")')
    return scene


def _billiard_portrait(args) -> int:
    from ..analysis.billiard_portrait import birkhoff_portrait
    from .outputs import atomic_write_text
    from .table_figures import portrait_figure

    runs = _collision_count(args.runs, "--runs")
    impacts = _collision_count(args.impacts, "--impacts")
    ball = _collision_count(args.ball, "--ball")
    scene = _table_scene(args.scene, "portrait")
    out = _out_dir(args.out)
    _writable(out)
    with _count_bar(args.progress, "birkhoff", "launch") as progress, _sigterm_as_interrupt():
        launches = birkhoff_portrait(scene, runs, impacts, ball, progress=progress)
    lines = ["run,theta,p,n,boundary_s,sin_reflection_angle"]
    for k, run in enumerate(launches, start=1):
        lines += [f"{k},{run['theta']:.17g},{run['p']:.17g},{n},{s:.17g},{q:.17g}"
                  for n, (s, q) in enumerate(zip(run["s"], run["sin_angle"]), start=1)]
    atomic_write_text(out / "birkhoff_portrait.csv", "\n".join(lines) + "\n")
    portrait_figure(scene, launches, out / "birkhoff_portrait.png", ball=ball)
    stopped = [f"{k}: {run['status']}" for k, run in enumerate(launches, start=1)
               if run["status"] not in ("max_collisions", "completed")]
    print(f"{len(launches)} launches of ball {ball}, {sum(len(r['s']) for r in launches)} cushion impacts"
          + (f"; stopped early: {', '.join(stopped)}" if stopped else ""))
    print(f"wrote {out}/birkhoff_portrait.png, {out}/birkhoff_portrait.csv")
    return EXIT_INTERRUPTED if launches and launches[-1]["status"] == "interrupted" else EXIT_OK


def _billiard_orbits(args) -> int:
    import json

    from ..analysis.billiard_orbits import periodic_orbits

    period = _collision_count(args.period, "--period")
    rotation = None if args.rotation is None else _collision_count(args.rotation, "--rotation")
    ball = _collision_count(args.ball, "--ball")
    scene = _table_scene(args.scene, "orbits")
    with _count_bar(args.progress, "orbits", "search") as progress, _sigterm_as_interrupt():
        orbits = periodic_orbits(scene, period, rotation, ball, progress=progress)
    if args.json:
        print(json.dumps([o.as_dict() for o in orbits], indent=2))
        return EXIT_OK
    polygon = hasattr(scene.boundary, "centre_polygon")
    rotations = f"rotation {rotation}/{period}" if rotation is not None else \
        "every rotation p/period" if polygon else f"rotation 1/{period}"
    print(f"{scene.boundary.describe()}, ball {ball} (R = {float(scene.balls[ball - 1].body.radius):.6g} m): "
          f"periodic orbits of period {period}, {rotations}")
    print(f"{'kind':>8} {'p':>3} {'perimeter (m)':>22} {'trace':>22} stability   vertices (centre)")
    for o in orbits:
        vertices = " ".join(f"({x:.6f}, {y:.6f})" for x, y in o.points)
        print(f"{o.kind:>8} {o.rotation:>3} {o.perimeter:22.17g} {o.trace:22.15g} {o.stability:<11} {vertices}")
    if not orbits:
        print("none found")
    return EXIT_OK


def _equilibria(args) -> int:
    import json

    from .portrait import equilibria_list

    scene = _path_scene(args.scene, "equilibria")
    body = _body_number(args.body, scene)
    eq = equilibria_list(scene, body)
    if args.json:
        print(json.dumps([e.as_json() for e in eq]))
        return EXIT_OK
    print(f"{scene.name}: body {body + 1}, Omega = {float(scene.frame.omega):.17g} rad/s, "
          f"axis x = {float(scene.frame.axis_x):.17g} m")
    print(f"{'x':>24} {'type':>7} {scene.coordinate:>24} {'stiffness h_q':>24} {'V/m (J/kg)':>24}")
    for e in eq:
        print(f"{e.x:24.17g} {e.type:>7} {e.q:24.17g} {e.stiffness:24.17g} {e.potential:24.17g}"
              + (f"  (a neutral stretch to x = {e.x_end:.17g})" if e.x_end is not None else ""))
    return EXIT_OK


def _portrait(args) -> int:
    import numpy as np

    from .portrait import default_omegas, write_portrait

    scene = _path_scene(args.scene, "portrait")
    body = _body_number(args.body, scene)
    omegas = default_omegas(scene)
    if args.omega_max is not None:
        top = _positive_number(args.omega_max, "--omega-max")
        omegas = np.linspace(0.0, top, 121)
    out = _out_dir(args.out)
    _writable(out)
    with _count_bar(args.progress, "portrait", "piece") as progress, _sigterm_as_interrupt():
        data = write_portrait(scene, out, scene_source=args.scene, body=body, omegas=omegas, progress=progress)
    for e in data["equilibria"]:
        print(f"{e['type']:>7} at x = {e['x']:.17g} ({data['coordinate']} = {e['q']:.17g})"
              + (f" to x = {e['x_end']:.17g}" if e.get("x_end") is not None else ""))
    for b in data["bifurcations"]:
        print(f"bifurcation at Omega = {b['omega']:.17g} rad/s near x = {b['x']:.6g} "
              f"({data['coordinate']} = {b['q']:.6g}): "
              f"{b['equilibria_before']} -> {b['equilibria_after']} equilibria")
    print(f"portrait checked against {data['check']['integrated_trajectories']} integrated trajectories: "
          f"first integral drift {data['check']['worst_relative_first_integral_drift']:.2g} (relative)")
    print(f"wrote {out}/")
    return EXIT_OK


def _positive_number(text: str, field: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise BadInput(field, f"must be a number, got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise BadInput(field, f"must be a finite number > 0, got {text}")
    return value


def _validate(args) -> int:
    collisions = _collision_count(args.collisions, "--collisions")
    if collisions < 1:
        raise BadInput("--collisions", "must be >= 1")
    scene = _not_a_table(load_scene(args.scene) if args.scene else default_scene(), "validate")
    out = _out_dir(args.out)
    _writable(out)
    from .outputs import prepare_run_directory, remove_run_files
    from .report import validate

    prepare_run_directory(out)
    try:
        with _count_bar(args.progress, "validate", "section") as progress, _sigterm_as_interrupt():
            path = validate(scene, out, source=args.scene or "<default scene>", collisions=collisions,
                            progress=progress)
    except (OSError, KeyboardInterrupt) as exc:
        remove_run_files(out)  # a report is written last: its figures alone are not kept
        if isinstance(exc, KeyboardInterrupt):
            raise
        raise BadInput("--out", f"writing the report to {out} failed: {exc.strerror or exc}; nothing kept") from None
    print(f"wrote {path}")
    return EXIT_OK


class _GridAxis(argparse.Action):
    """--vary and --values append to one list, so that the dimensions keep the command line's order."""

    def __call__(self, parser, namespace, values, option_string=None):
        namespace.grid = [*(namespace.grid or []), (option_string.lstrip("-"), values)]


def _add_sweep_parsers(sub) -> None:
    sweep = sub.add_parser("sweep", help="run a scene over a grid, lists or a random sample of parameter values "
                                         "(Dask), into DIR/sweep.zarr")
    sweep.add_argument("scene", nargs="?", help="scene file (TOML), may hold a [sweep] table; the built-in default "
                                                "scene if omitted")
    sweep.add_argument("--vary", dest="grid", action=_GridAxis, default=[], metavar="KEY=START:STOP:N",
                       help="a dimension: N values from START to STOP; KEY as in the scene file, e.g. "
                            "collision.restitution, bodies[2].mass, frame.omega (repeatable)")
    sweep.add_argument("--values", dest="grid", action=_GridAxis, metavar="KEY=v1,v2,...",
                       help="a dimension of listed values (repeatable)")
    sweep.add_argument("--random", action="append", default=[], metavar="KEY=LO:HI",
                       help="random points, uniform in [LO, HI) for each KEY (with --samples, --seed)")
    sweep.add_argument("--samples", help="number of random points")
    sweep.add_argument("--seed", help="seed of the random points (default 0)")
    sweep.add_argument("--keep", action="append", help="what each point keeps, a comma list (or --keep repeated): "
                                                         "summary (default), impacts:M (the last "
                                      "M impacts), first:M, strobe:M (forced scenes: the last M stroboscopic "
                                      "samples), period, lyapunov, rotation (per-point estimates; see README)")
    sweep.add_argument("--precision", help="double (default), long, quad or mp:BITS for every point")
    sweep.add_argument("--batch", action="store_true", default=None,
                       help="points of one shape through heyoka's batch (SIMD) integrator: faster, collision "
                            "times within a few ulps of a scalar run's, not its last bits (README, Sweeps)")
    sweep.add_argument("--out", default="heyroll-sweep", help="output directory (default: heyroll-sweep)")
    sweep.add_argument("--workers", help="worker processes of a local Dask cluster (default: all cores; 1 runs "
                                         "in this process, without Dask)")
    sweep.add_argument("--scheduler", metavar="ADDRESS", help="a running dask.distributed scheduler, "
                                                              "e.g. tcp://host:8786")
    sweep.add_argument("--t-end", dest="t_end", help="end time in s of every point (overrides [run] t_end)")
    sweep.add_argument("--max-collisions", dest="max_collisions", help="stop every point after N collisions")
    sweep.add_argument("--progress", choices=("auto", "on", "off"), default="auto",
                       help="progress bar over points on stderr (auto: if a terminal)")
    sweep.add_argument("--no-figures", action="store_true", help="skip the figures")
    plot = sub.add_parser("plot", help="draw a sweep's figures: bifurcation diagram (one KEY), maps (two KEYs)")
    plot.add_argument("store", help="a sweep store, DIR/sweep.zarr")
    plot.add_argument("--out", help="directory of the figures (default: the store's directory)")
    plot.add_argument("--scalar", help="the per-point scalar of the maps: energy_loss, collisions, t_final, "
                                       "relative_energy_change, and period, period_time, lyapunov, rotation "
                                       "when kept (default: energy_loss, collisions and the estimates kept)")
    plot.add_argument("--points", help="flat point numbers (C order, as in the store), comma list: the points "
                                       "whose Poincare section is drawn (with strobe:M kept)")


def _sweep_extra() -> None:
    try:
        import xarray  # noqa: F401  (the store's Dataset)
        import zarr  # noqa: F401  (the store)
    except ImportError:
        raise BadInput("sweep", "needs the sweep extra: pip install 'heyroll[sweep]'") from None


def _sweep(args, argv: list) -> int:
    import shlex

    from ..sweep.plan import make_plan
    from ..sweep.run import execute
    from ..sweep.store import check_spec, store_path, stored_mask
    from .outputs import versions

    _sweep_extra()
    t_end = _positive_time(args.t_end) if args.t_end is not None else None
    max_collisions = _collision_count(args.max_collisions) if args.max_collisions is not None else ...
    workers = _collision_count(args.workers, "--workers", least=1) if args.workers is not None else None
    if workers is not None and args.scheduler is not None:
        raise BadInput("--workers", "a --scheduler's cluster has its own workers: give one or the other")
    out = _out_dir(args.out)
    plan = make_plan(args.scene, grid=args.grid, random=args.random, samples=args.samples, seed=args.seed,
                     keep=None if args.keep is None else ",".join(args.keep), t_end=t_end, max_collisions=max_collisions, precision=args.precision,
                     batch=args.batch)
    if store_path(out).exists():  # a store of another sweep: its one line alone (the header came first: review)
        check_spec(store_path(out), plan, versions())
    print(f"{plan.n_points} points: " + " x ".join(f"{d} ({n})" for d, n in zip(plan.dims, plan.shape))
          + (f" over {', '.join(k.text for k in plan.keys)}" if plan.sample is not None else ""))
    try:
        with _sigterm_as_interrupt():
            outcome = execute(plan, out, workers=workers, scheduler=args.scheduler, progress=args.progress,
                              command=shlex.join(["heyroll", *argv]), report=print)
    except KeyboardInterrupt:
        path = store_path(out)
        if not path.exists():  # stopped before the store was made (connecting to a scheduler, review)
            print("interrupted: no point stored yet; the same command starts the sweep")
            return EXIT_INTERRUPTED
        stored = int(stored_mask(path).sum())
        print(f"interrupted: {stored} of {plan.n_points} points stored in {path}; the same command continues")
        return EXIT_INTERRUPTED
    except OSError as exc:
        raise BadInput("--out", f"writing the sweep to {out} failed: {exc.strerror or exc}") from None
    if outcome.stored_before:
        print(f"resumed: {outcome.stored_before} points were stored already")
    print(outcome.summary_line())
    print(f"wrote {outcome.path}")
    if not args.no_figures:
        _lock(out)  # (the sweep held it while it wrote the store)
        try:
            with _sigterm_as_interrupt():
                _write_sweep_figures(outcome.path, out, None)
        except KeyboardInterrupt:  # (acceptance test: it said the store was written, then "interrupted")
            print(f"interrupted while drawing the figures: {outcome.path} is whole; heyroll plot {outcome.path} "
                  "draws them")
            return EXIT_INTERRUPTED
    return EXIT_OK


def _write_sweep_figures(store: Path, out: Path, scalar, points=None) -> None:
    from ..sweep.figures import sweep_figures

    paths = sweep_figures(store, out, scalar, points)
    for path in paths:
        print(f"wrote {path}")
    if not paths:
        print("no figure: figures are drawn for one or two varied KEYs")


def _plot(args) -> int:
    from ..sweep.errors import SweepStoreError
    from ..sweep.store import SPEC_ATTR

    _sweep_extra()
    import zarr

    store = Path(args.store)
    try:
        attrs = zarr.open_group(str(store), mode="r").attrs
    except Exception as exc:  # a missing path or not a Zarr group: whatever zarr raises, one line
        raise SweepStoreError("store", f"{store} is not a sweep store ({exc.__class__.__name__})") from None
    if SPEC_ATTR not in attrs:
        raise SweepStoreError("store", f"{store} is not a heyroll sweep store")
    out = _out_dir(args.out) if args.out is not None else store.parent
    _writable(out)
    points = None
    if args.points is not None:
        try:
            points = [int(x) for x in args.points.split(",") if x.strip()]
        except ValueError:
            raise BadInput("--points", f"must be whole point numbers, comma separated, got {args.points!r}") from None
        if not points or min(points) < 0:
            raise BadInput("--points", f"must be point numbers >= 0, got {args.points!r}")
    _write_sweep_figures(store, out, args.scalar, points)
    return EXIT_OK


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
