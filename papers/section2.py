"""Paper section 2: heavy particles on rough curves (Coulomb friction, limiters, collisions), from real runs.

Run:  python papers/section2.py [--out papers/figures] [--quick]

Section 2 reviews the work on heavy material points sliding along rough
curves in a fixed or a turning vertical plane: Coulomb friction, elongation
limiters, two or three particles in successive collisions, studied with
phase portraits (branches with jumps at the impacts) drawn over the curves of
constant mechanical energy, and the energy per branch. It gives no numbers;
PARAMETERS below are ours (printed, and written in the figure titles):

(a) two particles inside a rough circle (R = 1 m, mu = 0.1, mu_s = 0.2, Newton
    restitution k = 0.7), released at rest from phi = -1 and phi = 0.6: both
    slide towards the bottom, collide, turn, stick and are knocked loose again.
    Figure section2_circle_portrait.png: phi vs phi' of each particle, the
    branches coloured by mode (sliding+, sliding-, stuck), the jumps at the
    collisions, and the contours of E = 1/2 m R^2 phi'^2 + m g R (1 - cos phi).
    Checks: E_initial - E_final = friction work + impact losses; on each branch
    the drop of the body's energy equals the friction work
    (``transition_work``); every turning point and every branch time against the
    closed form (phi'^2 obeys dy/dphi + 2 s mu y = -(2 g/R)(sin phi + s mu cos phi),
    heyroll.reference.rough, mpmath); the rates at the collisions on the closed-form
    branch; a single particle's whole stick-slip sequence against the closed form;
    the final sticking band |tan phi| <= mu_s.
(b) two particles on the rough curve y = x^2, x in [-1, 1], in a plane turning at
    Omega = 2 rad/s about x = 0, limiters at x = +-1 (restitution 0.8), k = 0.7:
    the Jacobi integral H = 1/2 m (1 + 4 x^2) x'^2 + m (g - Omega^2/2) x^2 per branch,
    friction work, collision and limiter losses. Figure section2_curve_portrait.png.
(c) (not with --quick) three particles in the rough circle: the energy balance.

Figure section2_energy.png: each particle's energy (Jacobi integral) against time.
Prints a PASS/FAIL line per check; exits 1 if one fails.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import mpmath
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from heyroll.model.bodies import Body
from heyroll.model.frame import Frame
from heyroll.model.laws import make_law
from heyroll.model.scene import RunSettings, Scene
from heyroll.model.tracks import CircleTrack, CurveTrack, first_integral
from heyroll.reference import rough
from heyroll.simulation.driver import simulate

PARAMETERS = {
    "circle": dict(R=1.0, mu=0.1, mu_s=0.2, k=0.7, phi=(-1.0, 0.6), dphi=(0.0, 0.0), t_end=10.0),
    "single": dict(phi=-1.0, dphi=0.0),  # one particle alone in the same circle
    "curve": dict(y="x**2", x_min=-1.0, x_max=1.0, omega=2.0, axis_x=0.0, mu=0.1, mu_s=0.2, k=0.7, k_lim=0.8,
                  x=(-0.6, 0.5), dx=(-3.0, 3.5), t_end=10.0),
    "three": dict(phi=(-1.2, 0.3, 1.0), dphi=(0.0, -1.0, 0.0), t_end=10.0),
}
#: Relative tolerance of every energy balance (to the initial energy); absolute tolerance (rad, s) of
#: the turning points and branch times against the closed form; relative, of phi'^2 at a collision.
ENERGY_TOL, CLOSED_FORM_TOL, RATE2_TOL = 1e-12, 1e-12, 1e-10
MODE_COLOURS = {"sliding+": "tab:red", "sliding-": "tab:blue", "stuck": "black", "rolling": "tab:green"}
DPS = 40


def particle() -> Body:
    return Body.of_shape("particle", 0, mass=1.0)


def circle_scene(phi, dphi, t_end) -> Scene:
    p = PARAMETERS["circle"]
    return Scene.make(CircleTrack.of_radius(p["R"]), [particle() for _ in phi], list(phi), list(dphi),
                      law=make_law("newton", p["k"]), friction=p["mu"], static_friction=p["mu_s"],
                      run=RunSettings.make(t_end), name=f"{len(phi)} particles in a rough circle")


def curve_scene(t_end) -> Scene:
    p = PARAMETERS["curve"]
    track = CurveTrack.make(p["y"], p["x_min"], p["x_max"])
    return Scene.make(track, [particle(), particle()], list(p["x"]), list(p["dx"]), law=make_law("newton", p["k"]),
                      friction=p["mu"], static_friction=p["mu_s"], track_sides="one",
                      frame=Frame.make(p["omega"], p["axis_x"]), limiter_restitution=p["k_lim"],
                      run=RunSettings.make(t_end), name="2 particles on a rough turning parabola")


# -- events and branches -------------------------------------------------------------------------


def body_energy(scene, k, q, dq) -> float:
    """Body k's mechanical energy (Jacobi integral in a turning plane), float64."""
    return float(first_integral(scene.track, scene.bodies[k], q, dq, scene.g, scene.frame))


def body_events(result, k) -> list[dict]:
    """Body k's events in time order: start, collisions, limiter impacts, changes of mode, end.

    Each: t, q, dq_before, dq_after, E_before, E_after, W (the unit's friction work since t = 0,
    None where the run records none: a collision that changes no mode), mode (after), kinds.
    Records of one instant (a collision and the change of mode it causes) are merged.
    """
    scene = result.scene
    n = len(scene.bodies)
    q0, dq0 = float(result.initial_state[k]), float(result.initial_state[n + k])
    first = next((tr for tr in result.transitions if tr[1] == k), None)
    events = [dict(t=0.0, q=q0, dq_before=dq0, dq_after=dq0, W=0.0, mode=first[2] if first else result.final_modes[k],
                   kinds=["start"])]
    raw = []
    for row in result.collision_table():
        for side, other in (("i", "j"), ("j", "i")):
            if int(row[side]) - 1 == k:
                raw.append(dict(t=float(row["t"]), q=float(row[f"q_{side}"]), dq_before=float(row[f"dq_{side}_before"]),
                                dq_after=float(row[f"dq_{side}_after"]), W=None, mode=None,
                                kinds=[f"collision with {int(row[other])}"]))
    for row in result.passage_table():
        if row["kind"] != 0 and int(row["body"]) - 1 == k:
            raw.append(dict(t=float(row["t"]), q=float(row["q"]), dq_before=float(row["dq_before"]),
                            dq_after=float(row["dq_after"]), W=None, mode=None,
                            kinds=["limiter " + ("lower" if row["kind"] == 1 else "upper")]))
    for (t, body, old, new, q, dq), w in zip(result.transitions, result.transition_work):
        if body == k:
            raw.append(dict(t=float(t), q=float(q), dq_before=float(dq), dq_after=float(dq), W=float(w), mode=new,
                            kinds=[f"{old} -> {new}"], transition=True))
    raw.sort(key=lambda e: (e["t"], not e.get("transition", False)))
    for e in raw:
        last = events[-1]
        if abs(e["t"] - last["t"]) <= 1e-12 * max(1.0, abs(e["t"])):
            # One instant: an impact's rates (before/after) win; the change of mode brings W and the mode.
            if e.get("transition"):
                last["W"], last["mode"] = e["W"], e["mode"]
                if "start" in last["kinds"]:
                    last["dq_after"] = e["dq_after"]
            else:
                last["dq_before"], last["dq_after"], last["q"] = e["dq_before"], e["dq_after"], e["q"]
            last["kinds"] += e["kinds"]
            continue
        if e["mode"] is None:
            e["mode"] = last["mode"]
        events.append(e)
    qf, dqf = float(result.final_state[k]), float(result.final_state[n + k])
    events.append(dict(t=float(result.t_final), q=qf, dq_before=dqf, dq_after=dqf, W=float(result.friction_work[k]),
                       mode=result.final_modes[k], kinds=["end"]))
    for e in events:
        e["E_before"] = body_energy(scene, k, e["q"], e["dq_before"])
        e["E_after"] = body_energy(scene, k, e["q"], e["dq_after"])
    return events


def branches(events) -> list[dict]:
    """Branches between consecutive events: mode, ends, energy drop, friction work (None if unknown)."""
    out = []
    for a, b in zip(events, events[1:]):
        if b["t"] <= a["t"]:
            continue
        work = None if a["W"] is None or b["W"] is None else b["W"] - a["W"]
        out.append(dict(t0=a["t"], t1=b["t"], mode=a["mode"], q0=a["q"], dq0=a["dq_after"], q1=b["q"],
                        dq1=b["dq_before"], E0=a["E_after"], E1=b["E_before"], work=work, end=b["kinds"]))
    return out


def branch_balance(events, scale) -> float:
    """Worst |energy drop - friction work| / scale over spans between events with a known W
    (a span crosses impacts without a change of mode: their jumps are excluded)."""
    worst, drop, w_last = 0.0, 0.0, events[0]["W"]
    for a, b in zip(events, events[1:]):
        drop += a["E_after"] - b["E_before"]
        if b["W"] is not None:
            worst = max(worst, abs(drop - (b["W"] - w_last)) / scale)
            drop, w_last = 0.0, b["W"]
    return worst


def global_balance(result) -> tuple[float, float, float, float]:
    """(E_initial - E_final, friction work, collision losses, limiter losses); the relative error."""
    scene = result.scene
    ct = result.collision_table()
    impacts = float(np.sum(ct["energy_before"] - ct["energy_after"])) if len(ct) else 0.0
    limiters = 0.0
    for row in result.passage_table():
        if row["kind"] != 0:
            k = int(row["body"]) - 1
            limiters += (body_energy(scene, k, float(row["q"]), float(row["dq_before"]))
                         - body_energy(scene, k, float(row["q"]), float(row["dq_after"])))
    return result.energy_initial - result.energy_final, float(sum(result.friction_work)), impacts, limiters


# -- closed forms on the circle ------------------------------------------------------------------


def closed_form_errors(result) -> dict:
    """Turning points, branch times and collision rates of every sliding branch against the closed form."""
    p = PARAMETERS["circle"]
    g = float(result.scene.g)
    worst = dict(phi=0.0, t=0.0, rate2=0.0, turning_points=0, collisions=0)
    for k in range(len(result.scene.bodies)):
        for b in branches(body_events(result, k)):
            if not b["mode"].startswith("sliding"):
                continue
            s = 1 if b["mode"] == "sliding+" else -1
            ends_turning = any(" -> " in kind for kind in b["end"]) and b["dq1"] == 0.0 \
                and not any(kind.startswith("collision") for kind in b["end"])
            with mpmath.workdps(DPS):
                if ends_turning:
                    phi_t = rough.circle_turning_point(b["q0"], b["dq0"], p["mu"], p["R"], g, sgn=s, dps=DPS)
                    dt = rough.circle_branch_time(b["q0"], None, b["dq0"], p["mu"], p["R"], g, sgn=s, dps=DPS)
                    worst["phi"] = max(worst["phi"], float(abs(phi_t - mpmath.mpf(b["q1"]))))
                    worst["t"] = max(worst["t"], float(abs(dt - (mpmath.mpf(b["t1"]) - mpmath.mpf(b["t0"])))))
                    worst["turning_points"] += 1
                elif any(kind.startswith("collision") for kind in b["end"]):
                    y = rough.circle_branch_rate2(b["q1"], b["q0"], b["dq0"], p["mu"], p["R"], g, sgn=s, dps=DPS)
                    worst["rate2"] = max(worst["rate2"], float(abs(y - mpmath.mpf(b["dq1"]) ** 2) / max(abs(y), 1)))
                    worst["collisions"] += 1
    return worst


def single_particle(t_end) -> dict:
    """One particle from PARAMETERS['single'] against rough.circle_sliding_sequence (every transition)."""
    p, s = PARAMETERS["circle"], PARAMETERS["single"]
    result = simulate(circle_scene([s["phi"]], [s["dphi"]], t_end))
    ref = rough.circle_sliding_sequence(s["phi"], s["dphi"], p["mu"], p["mu_s"], p["R"], float(result.scene.g), dps=DPS)
    engine = [tr for tr in result.transitions if tr[0] > 0]  # the restart at t = 0 is the reference's mode0
    same = [(tr[2], tr[3]) for tr in engine] == [(x.mode_from, x.mode_to) for x in ref.transitions]
    t_err = max((abs(float(x.t - mpmath.mpf(tr[0]))) for tr, x in zip(engine, ref.transitions)), default=0.0)
    phi_err = max((abs(float(x.phi - mpmath.mpf(float(tr[4])))) for tr, x in zip(engine, ref.transitions)), default=0.0)
    return dict(result=result, reference=ref, same_modes=same, t_err=t_err, phi_err=phi_err)


# -- figures -------------------------------------------------------------------------------------


def _save(fig, path: Path) -> Path:
    FigureCanvasAgg(fig)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.png")
    fig.savefig(tmp, format="png", dpi=110)
    os.replace(tmp, path)
    return path


def _branch_points(t, states, k, n, b):
    inside = (t > b["t0"]) & (t < b["t1"])
    q = np.concatenate([[b["q0"]], states[inside, k], [b["q1"]]])
    dq = np.concatenate([[b["dq0"]], states[inside, n + k], [b["dq1"]]])
    return q, dq


def portrait_figure(result, all_events, path, qname, contour_energy, q_range, title, n_samples):
    n = len(result.scene.bodies)
    t, states = result.sample(n_samples)
    fig = Figure(figsize=(6.5, 3.6 * n))
    for k in range(n):
        ax = fig.add_subplot(n, 1, n - k)  # body 1 below, as in the paper's Fig. 11
        events = all_events[k]
        dmax = 1.15 * max(max(abs(e["dq_before"]), abs(e["dq_after"])) for e in events) + 0.2
        qq, vv = np.meshgrid(np.linspace(*q_range, 300), np.linspace(-dmax, dmax, 300))
        levels = sorted({round(e["E_after"], 9) for e in events} | {round(e["E_before"], 9) for e in events})
        ax.contour(qq, vv, contour_energy(k, qq, vv), levels=40, colors="0.85", linewidths=0.5)
        ax.contour(qq, vv, contour_energy(k, qq, vv), levels=levels, colors="0.55", linewidths=0.6, linestyles=":")
        seen = set()
        for b in branches(events):
            q, dq = _branch_points(t, states, k, n, b)
            label = b["mode"] if b["mode"] not in seen else None
            seen.add(b["mode"])
            ax.plot(q, dq, color=MODE_COLOURS[b["mode"]], lw=1.4, label=label)
            if b["mode"] == "stuck":
                ax.plot([b["q0"]], [0.0], "s", color="black", ms=4)
        for e in events:
            if e["dq_before"] != e["dq_after"]:
                ax.plot([e["q"], e["q"]], [e["dq_before"], e["dq_after"]], "--", color="tab:purple", lw=1)
                ax.plot([e["q"]], [e["dq_after"]], "o", color="tab:purple", ms=3)
        ax.plot([events[0]["q"]], [events[0]["dq_after"]], "*", color="tab:orange", ms=9, label="start")
        ax.set_xlim(*q_range)
        ax.set_ylim(-dmax, dmax)
        ax.set_xlabel(qname)
        ax.set_ylabel(f"d{qname}/dt")
        ax.set_title(f"particle {k + 1}", fontsize=9)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return _save(fig, path)


def energy_figure(runs, path, n_samples):
    fig = Figure(figsize=(7, 3.2 * len(runs)))
    for r, (label, result) in enumerate(runs):
        ax = fig.add_subplot(len(runs), 1, r + 1)
        n = len(result.scene.bodies)
        t, states = result.sample(n_samples)
        for k in range(n):
            e = first_integral(result.scene.track, result.scene.bodies[k], states[:, k], states[:, n + k],
                               result.scene.g, result.scene.frame)
            ax.plot(t, e, lw=1, label=f"particle {k + 1}")
        for row in result.collision_table():
            ax.axvline(row["t"], color="0.7", lw=0.6, ls="--")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("E (J)")
        ax.set_title(label, fontsize=9)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, path)


# -- main ----------------------------------------------------------------------------------------


def _print_branches(result, all_events):
    print(f"  {'body':>4} {'t0':>9} {'t1':>9} {'mode':>9} {'E0':>12} {'E1':>12} {'E0 - E1':>12} "
          f"{'friction W':>12}  end")
    for k, events in enumerate(all_events):
        for b in branches(events):
            w = "" if b["work"] is None else f"{b['work']:12.9f}"
            print(f"  {k + 1:>4} {b['t0']:9.5f} {b['t1']:9.5f} {b['mode']:>9} {b['E0']:12.9f} {b['E1']:12.9f} "
                  f"{b['E0'] - b['E1']:12.9f} {w:>12}  {', '.join(b['end'])}")


def energy_account(check, result, label: str, what: str, n_bodies: int) -> list:
    """Check one run's energy account: the whole run (fall = friction work + impacts' losses) and
    branch by branch (fall = friction work); prints the totals; returns each body's events."""
    check(f"{label} run succeeds", result.message, result.success)
    d_e, w, imp, lim = global_balance(result)
    print(f"  {what}_initial - {what}_final = {d_e:.15g} J; friction work {w:.15g} J + collision losses {imp:.15g} J "
          f"({result.n_collisions} collisions) + limiter losses {lim:.15g} J ({len(result.limiter_impacts)} impacts); "
          f"final modes {result.final_modes}")
    scale = abs(result.energy_initial)
    check(f"{label}: {what}_i - {what}_f = friction + impacts (relative)", abs(d_e - w - imp - lim) / scale,
          abs(d_e - w - imp - lim) <= ENERGY_TOL * scale)
    events = [body_events(result, k) for k in range(n_bodies)]
    worst = max(branch_balance(ev, scale) for ev in events)
    check(f"{label}: {what} drop = friction work per branch (relative)", worst, worst <= ENERGY_TOL)
    return events


def main(out_dir=None, quick=False) -> dict:
    """Run the study; returns {check name: (passed, value)}; figures into ``out_dir``."""
    out = Path(out_dir) if out_dir is not None else Path(__file__).resolve().parent / "figures"
    n_samples = 1500 if quick else 6000
    checks: dict = {}

    def check(name, value, ok):
        checks[name] = (bool(ok), value)
        print(f"  [{'PASS' if ok else 'FAIL'}] {name}: {value:.3g}" if isinstance(value, float)
              else f"  [{'PASS' if ok else 'FAIL'}] {name}: {value}")

    # (a) two particles in the rough circle -------------------------------------------------
    p = PARAMETERS["circle"]
    print(f"(a) two particles in a rough circle: R = {p['R']} m, mu = {p['mu']}, mu_s = {p['mu_s']}, Newton k = {p['k']}, "
          f"phi0 = {p['phi']}, dphi0 = {p['dphi']}, t_end = {p['t_end']} s")
    res_a = simulate(circle_scene(p["phi"], p["dphi"], p["t_end"]), dense=True)
    ev_a = energy_account(check, res_a, "circle", "E", 2)
    _print_branches(res_a, ev_a)
    cf = closed_form_errors(res_a)
    check(f"circle: {cf['turning_points']} turning points vs closed form (rad)", cf["phi"],
          cf["turning_points"] > 0 and cf["phi"] <= CLOSED_FORM_TOL)
    check("circle: branch times to the turning points vs closed form (s)", cf["t"], cf["t"] <= CLOSED_FORM_TOL)
    check(f"circle: phi'^2 at {cf['collisions']} collision arrivals vs closed form (relative)", cf["rate2"],
          cf["rate2"] <= RATE2_TOL)
    band = float(np.arctan(p["mu_s"]))
    final = [float(res_a.final_state[k]) for k in range(2)]
    print(f"  final: modes {res_a.final_modes}, phi = {final} (sticking band |phi| <= atan(mu_s) = {band:.6f})")
    check("circle: both stuck at the end, inside |tan phi| <= mu_s",
          max(abs(np.tan(x)) for x in final),
          all(m == "stuck" for m in res_a.final_modes) and all(abs(np.tan(x)) <= p["mu_s"] for x in final))
    sticks = [(float(tr[4]), tr[3] == "stuck") for tr in res_a.transitions if tr[0] > 0 and float(tr[5]) == 0.0
              and tr[2].startswith("sliding")]
    ok = all((abs(np.tan(q)) <= p["mu_s"]) == stuck for q, stuck in sticks)
    check(f"circle: {len(sticks)} turning points stick iff |tan phi| <= mu_s", "consistent" if ok else "inconsistent", ok)
    single = single_particle(p["t_end"])
    ref = single["reference"]
    print(f"  single particle from phi = {PARAMETERS['single']['phi']} at rest: {len(ref.transitions)} transitions "
          f"(closed form), sticks at phi = {float(ref.phi):.15f} at t = {float(ref.t):.15f} s")
    check("single particle: modes sequence as the closed form", str(single["same_modes"]), single["same_modes"])
    check("single particle: transition times vs closed form (s)", single["t_err"], single["t_err"] <= CLOSED_FORM_TOL)
    check("single particle: turning points vs closed form (rad)", single["phi_err"], single["phi_err"] <= CLOSED_FORM_TOL)

    def circle_energy(k, q, dq):
        return 0.5 * p["R"] ** 2 * dq**2 + float(res_a.scene.g) * p["R"] * (1 - np.cos(q))

    # The body energies of the events are first_integral's (zero at the circle's centre height): shift them.
    shift = float(res_a.scene.g) * p["R"]
    shifted = [[dict(e, E_before=e["E_before"] + shift, E_after=e["E_after"] + shift) for e in ev] for ev in ev_a]
    portrait_figure(res_a, shifted, out / "section2_circle_portrait.png", "phi", circle_energy, (-1.15, 1.15),
                    f"rough circle R = {p['R']} m, mu = {p['mu']}, mu_s = {p['mu_s']}, k = {p['k']}: "
                    f"phi0 = {p['phi']}, at rest", n_samples)

    # (b) the turning parabola with limiters -------------------------------------------------
    c = PARAMETERS["curve"]
    print(f"\n(b) two particles on the rough curve y = {c['y']}, x in [{c['x_min']}, {c['x_max']}], Omega = {c['omega']} "
          f"rad/s about x = {c['axis_x']}, mu = {c['mu']}, mu_s = {c['mu_s']}, k = {c['k']}, limiters k = {c['k_lim']}, "
          f"x0 = {c['x']}, dx0 = {c['dx']}")
    res_b = simulate(curve_scene(c["t_end"]), dense=True)
    ev_b = energy_account(check, res_b, "curve", "H", 2)
    _print_branches(res_b, ev_b)
    check("curve: limiter impacts occur", len(res_b.limiter_impacts), len(res_b.limiter_impacts) > 0)

    def curve_energy(k, q, dq):
        return first_integral(res_b.scene.track, res_b.scene.bodies[k], q, dq, res_b.scene.g, res_b.scene.frame)

    portrait_figure(res_b, ev_b, out / "section2_curve_portrait.png", "x", curve_energy, (c["x_min"], c["x_max"]),
                    f"y = {c['y']}, Omega = {c['omega']} rad/s, mu = {c['mu']}, mu_s = {c['mu_s']}, k = {c['k']}, "
                    f"limiters {c['k_lim']} (Jacobi integral contours)", n_samples)
    runs = [("(a) rough circle", res_a), ("(b) rough turning parabola (Jacobi integral)", res_b)]

    # (c) three particles ---------------------------------------------------------------------
    if not quick:
        t3 = PARAMETERS["three"]
        print(f"\n(c) three particles in the rough circle: phi0 = {t3['phi']}, dphi0 = {t3['dphi']}")
        res_c = simulate(circle_scene(t3["phi"], t3["dphi"], t3["t_end"]), dense=True)
        energy_account(check, res_c, "three particles", "E", 3)
        runs.append(("(c) three particles in the rough circle", res_c))
    energy_figure(runs, out / "section2_energy.png", n_samples)
    passed = sum(ok for ok, _ in checks.values())
    print(f"\nwrote {out}/section2_*.png; {passed}/{len(checks)} checks passed")
    return checks


def cli(argv=None) -> int:
    from _study import study_cli  # papers/_study.py: run as a script, papers/ is on the path

    return study_cli(main, __doc__, "fewer samples, no three-particle run", argv)


if __name__ == "__main__":
    sys.exit(cli())
