"""Where the rolling law's outcome is consistent: two solid balls in a circle.

    python validation/consistency_map.py [--quick]

Two homogeneous solid balls (kappa = 7/5, equal density 7850 kg/m^3) roll
inside a circle of radius R = 1 m; ball i (radius r_i) on the clockwise side
of the contact, ball j (r_j) counter-clockwise of it. Their rolling-law
(Hedrih) collision is *consistent* when the outgoing state separates them in
position, i.e. does not leave them approaching (they would overlap; heyroll
then applies its ``on_inconsistent`` policy, README "Hard cases").

Derivation (with phi' rates)
----------------------------

Write x = phi_i', y = phi_j' just before the collision. The gap
phi_j - phi_i - beta closes at the rate d = x - y: the bodies approach in
position iff d > 0. The rolling law is Newton's law in u = c phi' with
inertia M (README "Collision laws"): c = (R - r)/r (omega_P, eq. 23),
M = J_P = kappa m r^2. With w = u_i - u_j = c_i x - c_j y and
mu_i = M_i / (M_i + M_j), mu_j = 1 - mu_i, the outgoing law velocities are
u_i+ = u_i - (1 + k) mu_j w, u_j+ = u_j + (1 + k) mu_i w (eqs. 10-11), so

    x+ = x - (1 + k) mu_j w / c_i,      y+ = y + (1 + k) mu_i w / c_j,

and the outgoing closing rate is

    D+ = x+ - y+ = d - (1 + k) s w,     s = mu_j / c_i + mu_i / c_j > 0.

With alpha_i = (1 + k) s c_i and alpha_j = (1 + k) s c_j this is

    D+ = (1 - alpha_i) x - (1 - alpha_j) y.

The outcome is inconsistent iff D+ > 0, i.e. iff the law's approach rate in
omega_P is too small for the approach in position: w < d / ((1 + k) s); in
particular every state that approaches in position but recedes in omega_P
(w <= 0) is inconsistent.

**For every approaching pair of rates.** Put x = y + d with d > 0 fixed and y
free: D+ = (1 - alpha_i) d + (alpha_j - alpha_i) y. If c_i != c_j then
alpha_i != alpha_j and D+ > 0 for y of one sign and large enough: some
approaching state is inconsistent. If c_i = c_j then alpha_i = alpha_j =
(1 + k)(mu_i + mu_j) = 1 + k and D+ = -k d <= 0 for every approaching state
(k = 0: D+ = 0, a plastic outcome that neither separates nor approaches; the
engine treats it as consistent). As c = (R - r)/r is strictly decreasing in
r:

    the rolling law's outcome separates every approaching pair of rates
    iff r_i = r_j, for every k in [0, 1] (and whatever the masses, shapes or
    densities: the inertias only enter through mu, which cancels).

So the "always consistent" region of the (r_2/r_1, k) plane is the line
r_2 = r_1; off it the inconsistent states form a wedge of the (x, y) plane
between the rays x = y and (1 - alpha_i) x = (1 - alpha_j) y. Its size is
measured here by the fraction of approaching directions it holds, directions
taken uniform on the kinetic-energy ellipse (X = sqrt(G_i) x,
Y = sqrt(G_j) y, G = kappa m (R - r)^2): with normals
N1 = (1/sqrt(G_i), -1/sqrt(G_j)) (approach: N1.V > 0) and
N2 = ((1 - alpha_i)/sqrt(G_i), -(1 - alpha_j)/sqrt(G_j)) (D+ = N2.V), the
wedge {N1.V > 0, N2.V > 0} has the opening angle pi - angle(N1, N2), so

    fraction = 1 - angle(N1, N2) / pi       (0 when N2 = 0: k = 0, r_i = r_j).

It tends to 0 as r_2/r_1 -> 1 for k > 0 (N2 -> -k N1), but not at k = 0,
where about half of all directions are inconsistent however close the radii
(the outcome is then plastic in omega_P, and equal omega_P with unequal radii
means unequal phi'). A special case: one ball at rest (y = 0, or x = 0) is
hit consistently iff alpha of the moving ball is >= 1 (the dashed line on
the map).

Numerical check: at each point rates are sampled uniformly on the
kinetic-energy circle, the engine's own impulse map
(``heyroll.model.laws.impulse_map``) gives the outgoing rates, and the
outcome is classified as the engine does (inconsistent when the outgoing
separation rate is below -64 eps times the approach rate); the analytic
predicate must agree sample by sample (away from rounding distance of the
boundary), the sampled fraction must match the analytic one, and samples
drawn inside the analytic wedge must all be inconsistent.

Runs: on a coarse (r_2/r_1, k) grid, r_1 = 0.1 m, balls released from rest
at phi = -0.5 and 0.8 rad (the issue's prototype), t_end = 30 s, at most 300
collisions: the number of collisions flagged ``law_flag = 1``.

Writes validation/reports/consistency_map.png and consistency_map.md.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import mpmath
import numpy as np

HERE = Path(__file__).resolve().parent
REPORTS = HERE / "reports"

R = "1.0"
DENSITY = "7850"
R1 = 0.1
#: The engine's separation threshold (heyroll.simulation.events.SEPARATION_ULPS).
SEPARATION_ULPS = 64
EPS = float(np.finfo(float).eps)


# -- the analytic condition ---------------------------------------------------------


@dataclass(frozen=True)
class Pair:
    """Constants of two solid balls (floats): law scales c, inertias J, generalized masses G."""

    r_i: float
    r_j: float
    k: float
    c_i: float
    c_j: float
    J_i: float
    J_j: float
    G_i: float
    G_j: float

    @property
    def s(self) -> float:
        mu_i = self.J_i / (self.J_i + self.J_j)
        return (1 - mu_i) / self.c_i + mu_i / self.c_j

    @property
    def alpha_i(self) -> float:
        return (1 + self.k) * self.s * self.c_i

    @property
    def alpha_j(self) -> float:
        return (1 + self.k) * self.s * self.c_j


def _bodies(r_i, r_j):
    from heyroll import Body, CircleTrack

    track = CircleTrack.of_radius(R)
    return track, Body.of_shape("solid_sphere", str(r_i), density=DENSITY), Body.of_shape("solid_sphere", str(r_j), density=DENSITY)


def pair(r_i: float, r_j: float, k: float) -> Pair:
    track, bi, bj = _bodies(r_i, r_j)
    with mpmath.workprec(256):
        return Pair(
            r_i=r_i, r_j=r_j, k=k,
            c_i=float(track.rolling_ratio(bi)), c_j=float(track.rolling_ratio(bj)),
            J_i=float(bi.rolling_inertia()), J_j=float(bj.rolling_inertia()),
            G_i=float(track.generalized_mass(bi)), G_j=float(track.generalized_mass(bj)),
        )


def always_consistent(r_i: float, r_j: float, k: float) -> bool:
    """The analytic condition: every approaching pair of rates separates iff r_i = r_j (any k)."""
    return str(r_i) == str(r_j) or float(r_i) == float(r_j)


def outgoing_closing_rate(p: Pair, x, y):
    """D+ = (1 - alpha_i) x - (1 - alpha_j) y, the analytic outgoing closing rate."""
    return (1 - p.alpha_i) * np.asarray(x) - (1 - p.alpha_j) * np.asarray(y)


def predicted_inconsistent(p: Pair, x, y):
    """The analytic predicate: approaching (x > y) and D+ > 0."""
    x, y = np.asarray(x), np.asarray(y)
    return (x > y) & (outgoing_closing_rate(p, x, y) > 0)


def _normals(p: Pair):
    n1 = np.array([1 / math.sqrt(p.G_i), -1 / math.sqrt(p.G_j)])
    n2 = np.array([(1 - p.alpha_i) / math.sqrt(p.G_i), -(1 - p.alpha_j) / math.sqrt(p.G_j)])
    return n1, n2


def inconsistent_fraction(r_i: float, r_j: float, k: float) -> float:
    """Fraction of approaching directions (uniform in kinetic energy) whose outcome still approaches."""
    if always_consistent(r_i, r_j, k):
        return 0.0  # exactly (N2 = -k N1); in floats acos near pi would leave ~1e-8
    p = pair(r_i, r_j, k)
    n1, n2 = _normals(p)
    norm2 = float(np.linalg.norm(n2))
    if norm2 <= 1e-14 * float(np.linalg.norm(n1)):
        return 0.0
    cos = float(n1 @ n2) / (float(np.linalg.norm(n1)) * norm2)
    return 1 - math.acos(max(-1.0, min(1.0, cos))) / math.pi


def wedge_angles(r_i: float, r_j: float, k: float) -> tuple[float, float] | None:
    """The inconsistent wedge as an interval of angles theta of (X, Y) = (sqrt(G_i) x, sqrt(G_j) y)."""
    if inconsistent_fraction(r_i, r_j, k) == 0.0:
        return None
    p = pair(r_i, r_j, k)
    n1, n2 = _normals(p)
    t1 = math.atan2(n1[1], n1[0])
    t2 = math.atan2(n2[1], n2[0])
    t2 += 2 * math.pi * round((t1 - t2) / (2 * math.pi))
    return max(t1, t2) - math.pi / 2, min(t1, t2) + math.pi / 2


def hit_at_rest_consistent(r_i: float, r_j: float, k: float) -> bool:
    """A ball hitting the other at rest separates from it, whichever one moves: alpha_i, alpha_j >= 1."""
    p = pair(r_i, r_j, k)
    return p.alpha_i >= 1 and p.alpha_j >= 1


# -- the numerical check: the engine's impulse map on sampled rates -------------------------


def engine_map(r_i: float, r_j: float, k: float):
    """(q, a_i, a_j) of the rolling law for the pair, as the engine compiles it."""
    from heyroll import HedrihRollingLaw
    from heyroll.model.laws import impulse_map

    track, bi, bj = _bodies(r_i, r_j)
    m = impulse_map(HedrihRollingLaw(restitution=str(k)), bi, bj, track.path_radius(bi), track.path_radius(bj))
    return float(m.q), float(m.a_i), float(m.a_j)


def engine_inconsistent(r_i, r_j, k, x, y):
    """The engine's verdict on outgoing rates: separation rate below -64 eps times the approach rate."""
    q, a_i, a_j = engine_map(r_i, r_j, k)
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    d = x - q * y
    xo, yo = x - a_i * d, y + a_j * d
    return (x > y) & ((yo - xo) < -SEPARATION_ULPS * EPS * (x - y))


def sample_rates(p: Pair, n: int, rng, angles: tuple[float, float] | None = None):
    """Approaching rates (x, y), directions uniform on the kinetic-energy circle (or on ``angles``)."""
    if angles is None:
        theta = rng.uniform(-math.pi, math.pi, 4 * n)
    else:
        theta = rng.uniform(angles[0], angles[1], n)
    x, y = np.cos(theta) / math.sqrt(p.G_i), np.sin(theta) / math.sqrt(p.G_j)
    keep = x > y
    return x[keep][:n], y[keep][:n]


@dataclass(frozen=True)
class Check:
    r_i: float
    r_j: float
    k: float
    analytic_always: bool
    samples: int
    sampled_inconsistent: int
    analytic_fraction: float
    disagreements: int  # sample by sample, away from the boundary
    near_boundary: int
    wedge_samples: int
    wedge_consistent: int  # samples inside the analytic wedge the engine found consistent (must be 0)

    @property
    def sampled_fraction(self) -> float:
        return self.sampled_inconsistent / self.samples

    @property
    def fraction_sigma(self) -> float:
        f = self.analytic_fraction
        return math.sqrt(max(f * (1 - f), 1e-12) / self.samples)

    @property
    def ok(self) -> bool:
        always_sampled = self.sampled_inconsistent == 0 and self.wedge_samples == 0
        return (
            self.disagreements == 0
            and self.wedge_consistent == 0
            and abs(self.sampled_fraction - self.analytic_fraction) <= 5 * self.fraction_sigma + 1e-12
            and (self.analytic_always == always_sampled)
        )


def check_point(r_i: float, r_j: float, k: float, samples: int = 20000, seed: int = 0) -> Check:
    """Compare the analytic condition with the engine's impulse map on sampled rates."""
    rng = np.random.default_rng(seed)
    p = pair(r_i, r_j, k)
    x, y = sample_rates(p, samples, rng)
    engine = engine_inconsistent(r_i, r_j, k, x, y)
    predicted = predicted_inconsistent(p, x, y)
    scale = np.hypot(x * math.sqrt(p.G_i), y * math.sqrt(p.G_j)) / math.sqrt(min(p.G_i, p.G_j))
    near = np.abs(outgoing_closing_rate(p, x, y)) <= 1e-9 * scale
    wedge = wedge_angles(r_i, r_j, k)
    wedge_n = wedge_bad = 0
    if wedge is not None:
        lo, hi = wedge
        margin = 1e-6 * (hi - lo)
        wx, wy = sample_rates(p, max(200, samples // 20), rng, (lo + margin, hi - margin))
        wedge_n = wx.size
        wedge_bad = int(np.count_nonzero(~engine_inconsistent(r_i, r_j, k, wx, wy)))
    return Check(
        r_i=r_i, r_j=r_j, k=k, analytic_always=always_consistent(r_i, r_j, k), samples=int(x.size),
        sampled_inconsistent=int(np.count_nonzero(engine)), analytic_fraction=inconsistent_fraction(r_i, r_j, k),
        disagreements=int(np.count_nonzero((engine != predicted) & ~near)), near_boundary=int(np.count_nonzero(near)),
        wedge_samples=wedge_n, wedge_consistent=wedge_bad,
    )


# -- runs ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class RunCount:
    ratio: float
    k: float
    collisions: int
    flagged: int
    first_flagged: int | None
    contact_at: float | None
    status: str
    wall_s: float


def run_count(ratio: float, k: float, t_end: float = 30.0, max_collisions: int = 300) -> RunCount:
    import heyroll

    r2 = round(R1 * ratio, 12)
    text = (
        f'[track]\ntype = "circle"\nradius = {R}\n'
        f'[[bodies]]\nshape = "solid_sphere"\nradius = {R1}\ndensity = {DENSITY}\nphi = -0.5\ndphi = 0.0\n'
        f'[[bodies]]\nshape = "solid_sphere"\nradius = {r2}\ndensity = {DENSITY}\nphi = 0.8\ndphi = 0.0\n'
        f'[collision]\nlaw = "hedrih"\nrestitution = {k}\n[run]\nt_end = {t_end}\nmax_collisions = {max_collisions}\n'
    )
    result = heyroll.simulate(heyroll.parse_scene(text))
    flags = result.collision_table()["law_flag"]
    first = int(np.argmax(flags == 1)) + 1 if np.any(flags == 1) else None
    contact = result.contact_intervals[0]["t_start"] if result.contact_intervals else None
    return RunCount(ratio, k, result.n_collisions, int(np.count_nonzero(flags == 1)), first, contact,
                    result.status.value, result.wall_time_s)


# -- the map, the figure, the report ---------------------------------------------------------


def fraction_map(ratios, ks) -> np.ndarray:
    return np.array([[inconsistent_fraction(R1, R1 * q, k) for q in ratios] for k in ks])


def rest_map(ratios, ks) -> np.ndarray:
    return np.array([[min(pair(R1, R1 * q, k).alpha_i, pair(R1, R1 * q, k).alpha_j) for q in ratios] for k in ks])


def figure(path: Path, ratios, ks, fractions, rest, radii, k_pair, pair_fractions, runs, run_ratios, run_ks) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(16, 5.2), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)

    ax = axes[0]
    mesh = ax.pcolormesh(ratios, ks, fractions, shading="auto", cmap="viridis", vmin=0, vmax=max(0.6, fractions.max()))
    ax.axvline(1.0, color="white", lw=2, label="always consistent: $r_2 = r_1$")
    ax.contour(ratios, ks, rest, levels=[1.0], colors="orange", linestyles="--", linewidths=1.5)
    ax.plot([], [], "--", color="orange", label="between: a ball at rest is hit consistently")
    ax.set_xscale("log")
    ax.set_xticks([0.25, 0.5, 1, 2, 4], ["0.25", "0.5", "1", "2", "4"])
    ax.set_xticks([], minor=True)
    ax.set_xlabel("$r_2 / r_1$  ($r_1$ = 0.1 m, R = 1 m, equal density)")
    ax.set_ylabel("restitution k")
    ax.set_title("inconsistent fraction of approaching directions")
    ax.legend(loc="upper right", fontsize=8)
    fig.colorbar(mesh, ax=ax, label="share of approaching directions")

    ax = axes[1]
    mesh = ax.pcolormesh(radii, radii, pair_fractions, shading="auto", cmap="viridis", vmin=0)
    ax.plot(radii, radii, color="white", lw=2)
    ax.set_xlabel("$r_1$ (m), clockwise ball")
    ax.set_ylabel("$r_2$ (m)")
    ax.set_title(f"inconsistent fraction at k = {k_pair} (white: $r_1 = r_2$)")
    fig.colorbar(mesh, ax=ax, label="share of approaching directions")

    ax = axes[2]
    grid = np.full((len(run_ks), len(run_ratios)), np.nan)
    for r in runs:
        grid[run_ks.index(r.k), run_ratios.index(r.ratio)] = r.flagged / r.collisions if r.collisions else 0.0
    mesh = ax.imshow(grid, origin="lower", aspect="auto", cmap="magma", vmin=0, vmax=1)
    for r in runs:
        ax.text(run_ratios.index(r.ratio), run_ks.index(r.k), f"{r.flagged}/{r.collisions}", ha="center",
                va="center", fontsize=8, color="white" if (r.flagged / max(r.collisions, 1)) < 0.5 else "black")
    ax.set_xticks(range(len(run_ratios)), [f"{q:g}" for q in run_ratios])
    ax.set_yticks(range(len(run_ks)), [f"{k:g}" for k in run_ks])
    ax.set_xlabel("$r_2 / r_1$")
    ax.set_ylabel("k")
    ax.set_title("runs: flagged / collisions (from rest, 30 s)")
    fig.colorbar(mesh, ax=ax, label="flagged fraction")
    fig.savefig(path, dpi=110)


def report(path: Path, checks, runs, fractions_summary, prototype, elapsed, quick) -> None:
    lines = [
        "# Consistency map of the rolling law (two solid balls, R = 1 m)",
        "",
        f"`python validation/consistency_map.py{' --quick' if quick else ''}` ({elapsed:.1f} s). "
        "Derivation in the module docstring.",
        "",
        "## Result",
        "",
        "The rolling law's outcome separates **every** approaching pair of rates iff **r_i = r_j**, for every "
        "k in [0, 1] (and any masses): with x = phi_i', y = phi_j', the outgoing closing rate is "
        "D+ = (1 - alpha_i) x - (1 - alpha_j) y with alpha = (1 + k) s c, c = (R - r)/r; for c_i = c_j it is "
        "-k (x - y) <= 0, otherwise it is positive on a wedge of approaching states. "
        "The always-consistent region of the (r_2/r_1, k) plane is the line r_2/r_1 = 1.",
        "",
        "Off that line the inconsistent share of approaching directions (uniform in kinetic energy):",
        "",
        "| r_2/r_1 | " + " | ".join(f"k = {k:g}" for k in fractions_summary["ks"]) + " |",
        "|---|" + "---|" * len(fractions_summary["ks"]),
    ]
    for q, row in zip(fractions_summary["ratios"], fractions_summary["rows"]):
        lines.append(f"| {q:g} | " + " | ".join(f"{f:.3f}" for f in row) + " |")
    p = prototype
    lines += [
        "",
        f"Prototype of the issue (r = 0.10 / 0.15, k = 0.8): alpha_i = {p['alpha_i']:.4f}, alpha_j = {p['alpha_j']:.4f}; "
        f"inconsistent iff x < {p['t_star']:.4f} y with x > y, i.e. both balls move clockwise, the larger "
        f"(counter-clockwise) one catching up, and the smaller one moves at more than {p['t_star']:.3f} of the "
        f"larger one's rate: {100 * p['fraction']:.1f} % of approaching directions. At k = 1: "
        f"x < {p['t_star_1']:.4f} y, {100 * p['fraction_1']:.1f} %.",
        "",
        "## Check of the condition against the engine's impulse map",
        "",
        "Rates sampled uniformly on the kinetic-energy circle (approaching only), outgoing rates from "
        "`heyroll.model.laws.impulse_map`, classified as the engine does; 'disagree' counts samples where the "
        "analytic predicate and the engine differ (away from rounding distance of the boundary); 'wedge' samples "
        "are drawn inside the analytic wedge and must all be inconsistent.",
        "",
        "| r_1 | r_2 | k | always consistent (analytic) | samples | inconsistent | fraction sampled | analytic | disagree | wedge samples (consistent) | ok |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in checks:
        lines.append(
            f"| {c.r_i:g} | {c.r_j:g} | {c.k:g} | {'yes' if c.analytic_always else 'no'} | {c.samples} | "
            f"{c.sampled_inconsistent} | {c.sampled_fraction:.4f} | {c.analytic_fraction:.4f} | {c.disagreements} | "
            f"{c.wedge_samples} ({c.wedge_consistent}) | {'yes' if c.ok else '**NO**'} |"
        )
    lines += [
        "",
        "## Runs",
        "",
        "r_1 = 0.1 m, balls released from rest at phi = -0.5 and 0.8 rad, t_end = 30 s, at most 300 collisions; "
        "flagged = collisions resolved by the fallback law (`law_flag = 1`); contact = start of persistent contact.",
        "",
        "| r_2/r_1 | k | collisions | flagged | first flagged | contact at (s) | status |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        lines.append(
            f"| {r.ratio:g} | {r.k:g} | {r.collisions} | {r.flagged} | {r.first_flagged or '-'} | "
            f"{'-' if r.contact_at is None else f'{r.contact_at:.4g}'} | {r.status} |"
        )
    equal = [r for r in runs if r.ratio == 1.0]
    lines += [
        "",
        f"Equal radii: {sum(r.flagged for r in equal)} flagged in {sum(r.collisions for r in equal)} collisions, as the "
        "condition says. Unequal radii: flags depend on the states the run visits; released from rest with little "
        "energy, the elastic runs (k = 1) rarely enter the wedge (both balls moving the same way with comparable "
        "rates), while inelastic runs, whose bounces shrink toward common motion, enter it often.",
        "",
        "![consistency map](consistency_map.png)",
        "",
    ]
    path.write_text("\n".join(lines), encoding="utf-8")


CHECK_POINTS = [
    (0.1, 0.1, 0.0), (0.1, 0.1, 0.5), (0.1, 0.1, 1.0), (0.2, 0.2, 0.8),
    (0.1, 0.15, 0.8), (0.1, 0.15, 1.0), (0.1, 0.15, 0.0), (0.15, 0.1, 0.8),
    (0.1, 0.101, 0.9), (0.2, 0.05, 0.3), (0.05, 0.3, 1.0), (0.3, 0.45, 0.5),
]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="coarse maps, few samples and runs")
    args = parser.parse_args(argv)
    quick = args.quick
    started = time.perf_counter()

    checks = [check_point(*pt, samples=4000 if quick else 40000) for pt in CHECK_POINTS]
    ratios = np.geomspace(0.25, 4.0, 41 if quick else 161)
    ks = np.linspace(0.0, 1.0, 21 if quick else 81)
    fractions = fraction_map(ratios, ks)
    rest = rest_map(ratios, ks)
    radii = np.linspace(0.02, 0.45, 25 if quick else 87)
    k_pair = 0.8
    pair_fractions = np.array([[inconsistent_fraction(a, b, k_pair) if a + b < 0.95 else np.nan for a in radii] for b in radii])
    run_ratios = [0.5, 1.0, 1.5] if quick else [0.5, 0.75, 1.0, 1.25, 1.5, 2.0, 3.0]
    run_ks = [0.5, 1.0] if quick else [0.0, 0.3, 0.6, 0.8, 1.0]
    runs = [run_count(q, k) for k in run_ks for q in run_ratios]

    summary_ratios, summary_ks = [0.5, 0.9, 0.99, 1.01, 1.1, 1.5, 2.0], [0.0, 0.5, 0.8, 1.0]
    summary = {
        "ratios": summary_ratios, "ks": summary_ks,
        "rows": [[inconsistent_fraction(R1, R1 * q, k) for k in summary_ks] for q in summary_ratios],
    }
    proto, proto1 = pair(0.1, 0.15, 0.8), pair(0.1, 0.15, 1.0)
    prototype = {
        "alpha_i": proto.alpha_i, "alpha_j": proto.alpha_j,
        "t_star": (1 - proto.alpha_j) / (1 - proto.alpha_i), "fraction": inconsistent_fraction(0.1, 0.15, 0.8),
        "t_star_1": (1 - proto1.alpha_j) / (1 - proto1.alpha_i), "fraction_1": inconsistent_fraction(0.1, 0.15, 1.0),
    }

    REPORTS.mkdir(parents=True, exist_ok=True)
    figure(REPORTS / "consistency_map.png", ratios, ks, fractions, rest, radii, k_pair, pair_fractions, runs, run_ratios, run_ks)
    elapsed = time.perf_counter() - started
    report(REPORTS / "consistency_map.md", checks, runs, summary, prototype, elapsed, quick)

    print("rolling law consistent for every approaching pair of rates iff r_i = r_j (any k)")
    print(f"checks against the engine's impulse map: {sum(c.ok for c in checks)}/{len(checks)} ok "
          f"({sum(c.samples for c in checks)} sampled states)")
    for c in checks:
        print(f"  r = {c.r_i:g}/{c.r_j:g} k = {c.k:g}: analytic fraction {c.analytic_fraction:.4f}, sampled "
              f"{c.sampled_fraction:.4f}, disagreements {c.disagreements}, wedge {c.wedge_samples} "
              f"({c.wedge_consistent} consistent){'' if c.ok else '  FAILED'}")
    print(f"prototype r = 0.10/0.15: inconsistent fraction {prototype['fraction']:.3f} at k = 0.8, "
          f"{prototype['fraction_1']:.3f} at k = 1")
    print("runs (flagged/collisions):")
    for k in run_ks:
        print(f"  k = {k:g}: " + ", ".join(f"{r.ratio:g}: {r.flagged}/{r.collisions}" for r in runs if r.k == k))
    print(f"wrote {REPORTS / 'consistency_map.md'} and consistency_map.png ({elapsed:.1f} s)")
    return 0 if all(c.ok for c in checks) else 1


if __name__ == "__main__":
    sys.exit(main())
