"""``heyroll validate``: a Markdown report with figures on one scene.

Sections: the collision-time ladder (double, quad and the independent mpmath
reference, digits agreed per collision), energy jumps per collision (paper
4.2.6), phase portraits with jumps (Fig. 11), the paper's truncated series
against the exact elliptic integral, the paper's method end to end, the
predictability horizon (double vs quad) and the largest Lyapunov exponent,
and the versions and precisions used. Each section is one function returning
Markdown lines, so the report is easy to extend.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import mpmath

from ..model.scene import Scene
from ..simulation.driver import simulate
from ..simulation.result import SimulationResult
from .figures import energy_figure, phase_portrait_figure
from .outputs import atomic_write_text, versions

#: Digits the reference carries: far beyond quad, so it can judge quad runs.
REFERENCE_DPS = 50


@dataclass
class ReportContext:
    scene: Scene
    source: str
    out_dir: Path
    collisions: int
    double: SimulationResult | None = None
    long: SimulationResult | None = None
    quad: SimulationResult | None = None
    timings: dict = field(default_factory=dict)
    figures: list = field(default_factory=list)


def _timed(ctx: ReportContext, label: str, fn, *args, **kwargs):
    t0 = time.perf_counter()
    value = fn(*args, **kwargs)
    ctx.timings[label] = time.perf_counter() - t0
    return value


def digits_agreed(value, reference) -> float:
    """-log10 of the relative difference (inf when equal)."""
    with mpmath.workdps(REFERENCE_DPS):
        ref = mpmath.mpf(reference)
        diff = abs(mpmath.mpf(str(value)) - ref)
        if diff == 0:
            return math.inf
        return float(-mpmath.log10(diff / abs(ref)))


def section_collision_times(ctx: ReportContext) -> list[str]:
    from ..reference.collisions import run_reference

    n = ctx.collisions
    ctx.double = _timed(ctx, "double run", simulate, ctx.scene, max_collisions=n)
    ctx.quad = _timed(ctx, "quad run", simulate, ctx.scene, max_collisions=n, precision="quad")
    ref = _timed(ctx, "mpmath reference", run_reference, ctx.scene, n, dps=REFERENCE_DPS, t_end=ctx.scene.run.t_end)
    ref_rows = ref.collisions
    lines = [
        "## Collision times: double, quad and the exact reference",
        "",
        f"The first {n} collisions (or up to t_end). The reference is `heyroll.reference` at {REFERENCE_DPS} "
        "digits: Jacobi elliptic functions between collisions, gap roots bracketed so that none is skipped "
        "(no code shared with the heyoka engine). *Digits* = -log10 of the relative error in t.",
        "",
        "| n | pair | t (reference) | t (double) | t (quad) | digits double | digits quad |",
        "|---|---|---|---|---|---|---|",
    ]
    worst_d = worst_q = math.inf
    same_sequence = True
    dt = ctx.double.collision_table()
    m = min(len(ref_rows), ctx.double.n_collisions, ctx.quad.n_collisions)
    for k in range(m):
        c = ref_rows[k]
        pair_ok = (int(dt["i"][k]), int(dt["j"][k])) == (c.i, c.j)
        same_sequence &= pair_ok
        d = digits_agreed(ctx.double.times[k], c.t)
        q = digits_agreed(ctx.quad.times[k], c.t)
        worst_d, worst_q = min(worst_d, d), min(worst_q, q)
        lines.append(
            f"| {k + 1} | ({c.i},{c.j}){'' if pair_ok else ' ≠'} | {mpmath.nstr(c.t, 36)} | "
            f"{ctx.double.precision.format(ctx.double.times[k])} | {ctx.quad.precision.format(ctx.quad.times[k])} | "
            f"{d:.1f} | {q:.1f} |"
        )
    counts = (len(ref_rows), ctx.double.n_collisions, ctx.quad.n_collisions)
    lines += [
        "",
        f"Collisions found: reference {counts[0]}, double {counts[1]}, quad {counts[2]}; "
        f"pair sequence {'identical' if same_sequence and len(set(counts)) == 1 else 'DIFFERENT'}. "
        f"Worst digits agreed: double {worst_d:.1f} (relative error {10 ** -worst_d:.2g}), "
        f"quad {worst_q:.1f} (relative error {10 ** -worst_q:.2g}).",
        "",
    ]
    return lines


def section_precision_ladder(ctx: ReportContext) -> list[str]:
    """Any track: collision times in double and long against quad (digits agreed per collision)."""
    n = ctx.collisions
    ctx.double = _timed(ctx, "double run", simulate, ctx.scene, max_collisions=n)
    ctx.long = _timed(ctx, "long run", simulate, ctx.scene, max_collisions=n, precision="long")
    ctx.quad = _timed(ctx, "quad run", simulate, ctx.scene, max_collisions=n, precision="quad")
    runs = {"double": ctx.double, "long": ctx.long, "quad": ctx.quad}
    tables = {name: r.collision_table() for name, r in runs.items()}
    coordinate = ctx.scene.coordinate
    lines = [
        "## Collision times: double and long against quad",
        "",
        f"The first {n} collisions (or up to t_end), on the same engine in three number types: IEEE double, "
        "x87 extended (`long`) and IEEE quad (heyoka real128). Every event, law map and contact function is "
        f"evaluated in the run's own type. *Digits* = -log10 of the relative difference in t from the quad run; "
        f"{coordinate}_i is body i's coordinate at the collision.",
        "",
        f"| n | pair | t (quad) | {coordinate}_i (quad) | digits double | digits long |",
        "|---|---|---|---|---|---|",
    ]
    m = min(r.n_collisions for r in runs.values())
    worst = {"double": math.inf, "long": math.inf}
    same = True
    q = tables["quad"]
    for k in range(m):
        pair = (int(q["i"][k]), int(q["j"][k]))
        cells = []
        for name in ("double", "long"):
            same &= (int(tables[name]["i"][k]), int(tables[name]["j"][k])) == pair
            d = digits_agreed(runs[name].precision.format(runs[name].times[k]), ctx.quad.precision.format(ctx.quad.times[k]))
            worst[name] = min(worst[name], d)
            cells.append(f"{d:.1f}")
        lines.append(f"| {k + 1} | {pair} | {ctx.quad.precision.format(ctx.quad.times[k])} | "
                     f"{ctx.quad.precision.format(ctx.quad.states_before[k][pair[0] - 1])} | {cells[0]} | {cells[1]} |")
    counts = {name: r.n_collisions for name, r in runs.items()}
    passages = {name: len(r.passages) for name, r in runs.items()}
    if passages["quad"]:
        shown = min(min(passages.values()), max(n, 12))
        lines += [
            "",
            f"Junction passages and limiter impacts (the first {shown}): times against quad.",
            "",
            "| n | body | kind | t (quad) | digits double | digits long |",
            "|---|---|---|---|---|---|",
        ]
        from ..simulation.resolve.bounds import PASSAGE_KINDS

        for k in range(shown):
            tq = ctx.quad.passages[k][0]
            cells = []
            for name in ("double", "long"):
                d = digits_agreed(runs[name].precision.format(runs[name].passages[k][0]), ctx.quad.precision.format(tq))
                worst[name] = min(worst[name], d)
                cells.append(f"{d:.1f}")
            p = ctx.quad.passages[k]
            lines.append(f"| {k + 1} | {int(p[1]) + 1} | {PASSAGE_KINDS[int(p[2])]} | {ctx.quad.precision.format(tq)} | "
                         f"{cells[0]} | {cells[1]} |")
    lines += [
        "",
        f"Collisions found: {counts}; junction passages and limiter impacts: {passages}; statuses: "
        f"{ {name: r.status.value for name, r in runs.items()} }; pair sequence "
        f"{'identical' if same and len(set(counts.values())) == 1 else 'DIFFERENT'}. Worst digits agreed with quad "
        "(collisions and passages): "
        f"double {worst['double']:.1f}, long {worst['long']:.1f} (a double run can at best agree to ~16 digits, "
        "a long run to ~19; a chaotic sequence loses digits from one collision to the next).",
        "",
    ]
    return lines


#: Collisions the independent path reference computes in a report (it is mpmath: ~1-5 s per collision).
PATH_REFERENCE_COLLISIONS = 5
PATH_REFERENCE_DPS = 40


def section_path_reference(ctx: ReportContext) -> list[str]:
    """Path tracks: the first collisions against heyroll.reference.path_collisions (mpmath, no engine code).

    The reference reads the scene file itself (its own curve evaluation and arc
    geometry), so it needs the file: scenes given in Python, and scene keys it
    does not read, are reported as not checked rather than guessed.
    """
    import tomllib
    from decimal import Decimal

    from ..reference.path_collisions import run_path_reference, scene_inputs

    title = ["## Against the independent reference (path tracks)", ""]
    if ctx.scene.forcing is not None:  # (the reference reads no [forcing] table: it would compare the unforced motion)
        return title + ["Not checked: the reference has no forcing (the times above are checked across precisions).",
                        ""]
    path = Path(ctx.source)
    if not path.is_file():
        return title + ["Not checked: the scene was not given as a file (the reference reads the file's tables).", ""]
    try:
        inputs = scene_inputs(tomllib.loads(path.read_text(), parse_float=Decimal))
    except (ValueError, KeyError, TypeError) as exc:
        return title + [f"Not checked: the reference cannot read this scene ({exc}).", ""]
    n = min(ctx.collisions, PATH_REFERENCE_COLLISIONS, ctx.quad.n_collisions)
    if n == 0:
        return title + ["Not checked: the run has no collisions to compare (its junction and limiter times are "
                        "compared across precisions above).", ""]
    # The reference integrates in mpmath: only as far as the engine's n-th collision (and a little beyond).
    t_n = float(ctx.quad.times[n - 1])
    inputs["t_end"] = str(min(float(inputs.get("t_end") or t_n * 2), t_n * 1.05 + 1e-9))
    try:
        ref = _timed(ctx, "path reference", run_path_reference, n_collisions=n, dps=PATH_REFERENCE_DPS, **inputs)
    except (ValueError, ArithmeticError, RuntimeError) as exc:
        return title + [f"Not checked: the reference stopped ({exc}).", ""]
    lines = title + [
        f"The first {n} collisions from `heyroll.reference.path_collisions` at {PATH_REFERENCE_DPS} digits: each "
        "body's own Lagrangian integrated by Bulirsch-Stoer extrapolation in mpmath, every gap, junction and limiter "
        "located with steps that cannot jump a root (no code shared with the engine). *Digits* = -log10 of the "
        "relative difference in t.",
        "",
        "| n | pair | t (reference) | digits double | digits long | digits quad |",
        "|---|---|---|---|---|---|",
    ]
    runs = [ctx.double, ctx.long, ctx.quad]
    m = min([len(ref.collisions)] + [r.n_collisions for r in runs])
    worst = [math.inf] * 3
    for k in range(m):
        c = ref.collisions[k]
        cells = []
        for w, r in enumerate(runs):
            d = digits_agreed(r.precision.format(r.times[k]), c.t)
            worst[w] = min(worst[w], d)
            cells.append(f"{d:.1f}")
        lines.append(f"| {k + 1} | ({c.i},{c.j}) | {mpmath.nstr(c.t, 36)} | {' | '.join(cells)} |")
    lines += ["", f"Reference status {ref.status}, {len(ref.collisions)} collisions. Worst digits agreed: double "
              f"{worst[0]:.1f}, long {worst[1]:.1f}, quad {worst[2]:.1f}.", ""]
    return lines


def section_energy(ctx: ReportContext) -> list[str]:
    result = ctx.double
    table = result.collision_table()
    before = result.body_energies(result.states_before)
    after = result.body_energies(result.states_after)
    energy_figure(result, ctx.out_dir / "energy.png")
    ctx.figures.append("energy.png")
    nb = result.n_bodies
    head = " | ".join(f"E{k + 1} before | E{k + 1} after" for k in range(nb))
    scene = result.scene
    working = [name for name, on in (("friction", scene.rough), ("the forcing", scene.forcing is not None)) if on]
    if working:  # (the text said energy was kept on a rough track: review)
        between = ("Between collisions each body's mechanical energy changes by the work of "
                   f"{' and '.join(working)}; at a collision")
    else:
        between = "Between collisions each body keeps its own mechanical energy (eq. 26); at a collision"
    lines = [
        "## Energy jumps at collisions (paper 4.2.6)",
        "",
        f"{between} the representative points jump between phase curves and energy moves from body to body. "
        "ΔE(law) is eq. (15); ΔE(state) is the change of the total computed from the states.",
        "",
        "![energy](energy.png)",
        "",
        f"| n | t | {head} | ΔE(state) | ΔE(law, eq. 15) |",
        "|---|---|" + "---|---|" * nb + "---|---|",
    ]
    for k in range(min(result.n_collisions, 12)):
        cells = " | ".join(f"{before[k, b]:.10g} | {after[k, b]:.10g}" for b in range(nb))
        d_state = table["energy_after"][k] - table["energy_before"][k]
        lines.append(f"| {k + 1} | {table['t'][k]:.6f} | {cells} | {d_state:.3g} | {table['law_energy_change'][k]:.3g} |")
    e0, e1 = result.energy_initial, result.energy_final
    # (relative to |E0|; a scene that starts at energy 0 divided by it: ZeroDivisionError, acceptance test)
    change = f"relative change {(e1 - e0) / abs(e0):.2e}" if e0 else f"change {e1 - e0:.3g} J from 0"
    lines += ["", f"Total mechanical energy: {e0:.17g} J at t = 0, {e1:.17g} J at the end ({change}).", ""]
    return lines


def section_portrait(ctx: ReportContext) -> list[str]:
    if ctx.scene.track.linear_gap:
        phase_portrait_figure(ctx.double, ctx.out_dir / "phase_portrait.png")
    else:
        from .portrait_figures import branches_figure

        dense = simulate(ctx.scene, max_collisions=ctx.collisions, dense=True)
        branches_figure(dense, ctx.out_dir / "phase_portrait.png")
    ctx.figures.append("phase_portrait.png")
    return [
        "## Phase trajectory branches with jumps (paper Fig. 11)",
        "",
        "![phase portrait](phase_portrait.png)",
        "",
    ]


def section_versions(ctx: ReportContext) -> list[str]:
    v = versions()
    lines = ["## Versions, precisions and cost", ""]
    lines += [f"- {name}: {value}" for name, value in v.items()]
    d, q = ctx.double, ctx.quad
    lines += [
        f"- double run: tolerance {d.settings['tolerance']:.3g}, high_accuracy {d.settings['high_accuracy']}; "
        f"quad run: heyoka real128, tolerance {q.settings['tolerance']:.3g}",
    ]
    if ctx.long is not None:
        lines.append(f"- long run: x87 extended, tolerance {ctx.long.settings['tolerance']:.3g}")
    if ctx.scene.track.linear_gap and not reference_gap(ctx.scene):
        lines.append(f"- reference: mpmath at {REFERENCE_DPS} digits")
    lines += [f"- wall time, {label}: {seconds:.3g} s" for label, seconds in ctx.timings.items()]
    return lines + [""]


SECTIONS = [section_collision_times, section_energy, section_portrait]


def reference_gap(scene: Scene) -> str:
    """'' where the circle's independent reference (Jacobi elliptic functions: a smooth circle in a fixed plane,
    no forcing) describes the scene, else what it lacks: such a scene was reported against the smooth
    unforced motion, 'pair sequence DIFFERENT' (acceptance test)."""
    missing = [what for what, present in (("friction", scene.rough), ("forcing", scene.forcing is not None),
                                          ("a turning plane", scene.frame.rotating)) if present]
    return " and ".join(missing)


def section_no_reference(ctx: ReportContext) -> list[str]:
    return ["## Against the independent reference", "",
            f"Not checked: the circle's reference (Jacobi elliptic functions) has no {reference_gap(ctx.scene)}; "
            "the collision times above are checked across precisions only.", ""]


def sections_for(scene: Scene) -> list:
    """The report's sections on this scene's track (the analysis sections follow the circle's paper method)."""
    if scene.track.linear_gap:
        if reference_gap(scene):
            return [section_precision_ladder, section_no_reference, section_energy, section_portrait]
        return SECTIONS + ANALYSIS_SECTIONS
    return PATH_SECTIONS


def validate(scene: Scene, out_dir: Path, *, source: str, collisions: int = 20, extra_sections=None,
             progress=None) -> Path:
    """Write ``out_dir/report.md`` and its figures; returns the report's path.

    ``extra_sections`` (circle): replaces the analysis sections (series error, paper method, horizon).
    ``progress``: called as ``progress(done, total, stage)`` before each section and at the end.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    ctx = ReportContext(scene=scene, source=source, out_dir=out_dir, collisions=collisions)
    body = []
    sections = sections_for(scene)
    if extra_sections is not None and scene.track.linear_gap:
        sections = SECTIONS + list(extra_sections)
    for done, section in enumerate(sections):
        if progress is not None:
            progress(done, len(sections), section.__name__.removeprefix("section_").replace("_", " "))
        body += section(ctx)
    if progress is not None:
        progress(len(sections), len(sections), "done")
    body += section_versions(ctx)
    header = [
        f"# heyroll validation report: {scene.name}",
        "",
        f"Scene: {scene.describe()} (source: {source}).",
        "",
    ]
    path = out_dir / "report.md"
    atomic_write_text(path, "\n".join(header + body) + "\n")
    return path


def section_series(ctx: ReportContext) -> list[str]:
    from ..analysis.series_error import series_error_maps, series_error_table
    from .validation_figures import series_error_figure

    maps = _timed(ctx, "series error map", series_error_maps, ("printed", "corrected", 8), n_parameter=30, n_fraction=30)
    series_error_figure(maps, ctx.out_dir / "series_error.png")
    ctx.figures.append("series_error.png")
    table = series_error_table()
    return [
        "## The paper's truncated series against the exact elliptic integral",
        "",
        "The paper replaces Legendre's integral (50) by the 3 x 3 block (54)-(55) of the product of two "
        "binomial series (51)-(52): *printed* is (54) as printed, *corrected* the same block with its first-group "
        "coefficient fixed (ERRATA B6), *order N* the series truncated consistently at total degree 2N. "
        "At the turning point k^2 u^2 = 1 and no truncation converges fast.",
        "",
        "![series error](series_error.png)",
        "",
        table.to_markdown(),
    ]


def section_paper_method(ctx: ReportContext) -> list[str]:
    from ..analysis.series_error import paper_method_first_collision

    lines = [
        "## The paper's method end to end: the first collision from (56) = (57)",
        "",
        "Each ball's time to reach its collision angle is computed with the series; equating the two gives the "
        "transcendental equation (56) = (57), solved here numerically as the paper proposes. Compared with the "
        "exact first collision (reference).",
        "",
        "| series | status | t (series) | t (exact) | relative error in t | error in phi_1 (rad) |",
        "|---|---|---|---|---|---|",
    ]
    for kind in ("printed", "corrected", 8, 32):
        r = _timed(ctx, f"paper method ({kind})", paper_method_first_collision, ctx.scene, kind)
        if r.ok:
            lines.append(
                f"| {r.label} | {r.status} | {float(r.t_series):.12g} | {float(r.t_exact):.12g} | "
                f"{float(r.t_rel_error):.3g} | {float(r.phi_abs_error):.3g} |"
            )
        else:
            lines.append(f"| {r.label} | {r.status} | | | | {r.message} |")
    return lines + [""]


def section_horizon(ctx: ReportContext) -> list[str]:
    from ..analysis.horizon import lyapunov_estimate, predictability_horizon
    from .validation_figures import horizon_figure, lyapunov_figure

    horizon = _timed(
        ctx, "predictability horizon", predictability_horizon, ctx.scene, n_max=400, threshold=1e-10, t_end=1e5
    )
    horizon_figure(horizon, ctx.out_dir / "horizon.png")
    ctx.figures.append("horizon.png")
    try:
        lyap = _timed(ctx, "Lyapunov estimate", lyapunov_estimate, ctx.scene, t_end=200.0)
    except RuntimeError as exc:  # its reference run stops (a body leaves a one-sided track): a traceback, no report
        lyap = None
        lyap_line = f"- largest Lyapunov exponent: not estimated ({exc})"
    else:
        lyapunov_figure(lyap, ctx.out_dir / "lyapunov.png")
        ctx.figures.append("lyapunov.png")
        lyap_line = (f"- largest Lyapunov exponent: {lyap.exponent:.3g} 1/s (e-folding time {lyap.e_folding_time:.3g} s); "
                     f"{lyap.message}")
    first = horizon.first_disagreement
    return [
        "## Predictability horizon: where double results stop being trustworthy",
        "",
        f"A double run against a quad run of the same scene (threshold 1e-10 relative in t): {horizon.message}",
        "",
        f"- collisions agreeing: {horizon.n_agree}" + (f"; first disagreement at collision {first}" if first else " (all checked)"),
        lyap_line,
        "",
        "![horizon](horizon.png)",
        "",
    ] + (["![lyapunov](lyapunov.png)", ""] if lyap is not None else [])


#: Sections from heyroll.analysis (series error, paper method, horizon, Lyapunov).
ANALYSIS_SECTIONS: list = [section_series, section_paper_method, section_horizon]


#: Path tracks (arc chains, curves, turning planes): the precision ladder, energies, branches.
PATH_SECTIONS: list = [section_precision_ladder, section_path_reference, section_energy, section_portrait]
