"""Figures of a billiard run (paper section 7, Fig. 22): the table with the paths, the Birkhoff map.

* ``table_paths.png``: the cushion, the curve a ball's centre can reach
  (the inner parallel curve), each ball's path (straight while it rolls,
  parabolic arcs while it slides, drawn dashed), and, for a single particle
  in an ellipse, its caustic: the confocal conic every chord touches
  (x^2/(a^2 - l) + y^2/(b^2 - l) = 1, l = a^2 dy^2 + b^2 dx^2 - (x dy - y dx)^2
  for the unit direction d: an ellipse for l < b^2, a hyperbola for
  b^2 < l < a^2).
* ``birkhoff_map.png``: the Birkhoff coordinates of every cushion impact,
  boundary arc length s against sin of the reflection angle (the outgoing
  direction from the inward normal), coloured by ball.

Matplotlib's object API (nothing global); figures are written atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from .figures import _save

#: Pieces of motion drawn on the table (a long run's paths would fill it).
DRAWN_PIECES = 400


def table_figures(result, out_dir: Path) -> dict:
    table_paths_figure(result, out_dir / "table_paths.png")
    birkhoff_figure(result, out_dir / "birkhoff_map.png")
    return {"table_paths": "table_paths.png", "birkhoff_map": "birkhoff_map.png"}


def path_points(result, max_pieces: int = DRAWN_PIECES) -> list:
    """Per ball, a list of (x, y, sliding) polylines: one per piece of motion between events.

    A piece is (t, state, accelerations, riding balls): straight or parabolic, or, for a ball riding
    the cushion, along the curve of its centre at its mean speed (constant rolling, falling while it skids),
    on a straight wall from where it starts to where the next piece starts."""
    scene = result.scene
    n = scene.n_bodies
    pieces = result.paths[:max_pieces]
    ends = [p[0] for p in pieces[1:]] + [float(result.t_final)]
    last = [float(v) for v in result.state_final]
    following = [p[1] for p in pieces[1:]] + [last]
    curved = scene.boundary.kind in ("ellipse", "circle")  # a polygon's centre_curve is its corners' polygon
    out = [[] for _ in range(n)]
    for (t0, state, acc, riding), t1, after in zip(pieces, ends, following):
        for k in range(n):
            x, y, vx, vy = state[6 * k:6 * k + 4]
            if k in riding:
                x1, y1, vx1, vy1 = after[6 * k:6 * k + 4]
                skids = state[6 * k + 4] != 0 or state[6 * k + 5] != 0  # drawn dashed, as sliding
                if not curved:
                    out[k].append((np.array([x, x1]), np.array([y, y1]), skids))
                    continue
                mean = (np.hypot(vx, vy) + np.hypot(vx1, vy1)) / 2
                scale = mean / np.hypot(vx, vy) if np.hypot(vx, vy) > 0 else 0.0
                out[k].append((*along_cushion(scene, k, x, y, vx * scale, vy * scale, max(t1 - t0, 0)), skids))
                continue
            ax, ay = acc[2 * k], acc[2 * k + 1]
            sliding = ax != 0 or ay != 0
            tau = np.linspace(0, max(t1 - t0, 0), 40 if sliding else 2)
            out[k].append((x + vx * tau + ax * tau**2 / 2, y + vy * tau + ay * tau**2 / 2, sliding))
    return out


def along_cushion(scene, k: int, x: float, y: float, vx: float, vy: float, duration: float, samples: int = 2048):
    """(x, y) of ball k riding the cushion from (x, y) at velocity (vx, vy) for ``duration`` s: the stretch of
    the curve of its centre (the boundary's centre_curve, sampled) it covers, the whole curve after a lap."""
    theta = np.linspace(0, 2 * np.pi, samples, endpoint=False)
    cx, cy, dx, dy = scene.boundary.centre_curve(float(scene.balls[k].body.radius), theta)
    ds = np.hypot(dx, dy) * (2 * np.pi / samples)
    start = int(np.argmin((cx - x) ** 2 + (cy - y) ** 2))
    forward = dx[start] * vx + dy[start] * vy >= 0
    order = np.roll(np.arange(samples), -start)
    if not forward:
        order = np.roll(order[::-1], 1)
    covered = np.cumsum(ds[order]) - ds[order[0]]
    keep = order[covered <= np.hypot(vx, vy) * duration]
    return np.concatenate([[x], cx[keep]]), np.concatenate([[y], cy[keep]])


def caustic(result):
    """(x, y) of the caustic of a single particle in an ellipse, or None."""
    scene = result.scene
    if scene.boundary.kind != "ellipse" or scene.n_bodies != 1 or not scene.balls[0].body.is_particle:
        return None
    a, b = float(scene.boundary.a), float(scene.boundary.b)
    ball = scene.balls[0]
    x, y, vx, vy = (float(v) for v in (ball.x, ball.y, ball.vx, ball.vy))
    speed = np.hypot(vx, vy)
    if speed == 0:
        return None
    dx, dy = vx / speed, vy / speed
    lam = a * a * dy * dy + b * b * dx * dx - (x * dy - y * dx) ** 2
    if lam < b * b:
        t = np.linspace(0, 2 * np.pi, 400)
        return np.sqrt(a * a - lam) * np.cos(t), np.sqrt(b * b - lam) * np.sin(t)
    if lam < a * a:  # a confocal hyperbola, both branches inside the table
        p, q = np.sqrt(a * a - lam), np.sqrt(lam - b * b)
        s = np.linspace(-3, 3, 400)
        xs, ys = p * np.cosh(s), q * np.sinh(s)
        keep = (xs / a) ** 2 + (ys / b) ** 2 <= 1
        xs, ys = np.where(keep, xs, np.nan), np.where(keep, ys, np.nan)
        return np.concatenate([xs, [np.nan], -xs]), np.concatenate([ys, [np.nan], ys])
    return None


def table_paths_figure(result, path: Path) -> None:
    scene = result.scene
    fig = Figure(figsize=(7, 7 * _aspect(scene)), layout="constrained")  # room for the legend beside the table
    ax = fig.add_subplot()
    bx, by = scene.boundary.outline()
    ax.plot(bx, by, color="k", lw=1.5, label="cushion")
    colours = _ball_colours(scene.n_bodies)
    for k, polylines in enumerate(path_points(result)):
        for x, y, sliding in polylines:
            ax.plot(x, y, color=colours[k], lw=0.8, ls="--" if sliding else "-", alpha=0.8)
        ball = scene.balls[k]
        r = float(ball.body.radius)
        ax.plot([float(ball.x)], [float(ball.y)], "o", color=colours[k], ms=4, label=f"ball {k + 1} start")
        if r > 0:
            t = np.linspace(0, 2 * np.pi, 60)
            ax.plot(float(ball.x) + r * np.cos(t), float(ball.y) + r * np.sin(t), color=colours[k], lw=0.8)
    c = caustic(result)
    if c is not None:
        ax.plot(*c, color="0.3", lw=1.2, ls=":", label="caustic", zorder=5)  # over the paths (acceptance test)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    shown = min(len(result.paths), DRAWN_PIECES)
    ax.set_title(f"{scene.boundary.describe()}: paths of the first {shown} pieces of motion\n"
                 f"({result.n_collisions} impacts; dashed: sliding)", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the table, not over a corner
    _save(fig, path)


def birkhoff_figure(result, path: Path) -> None:
    table = result.collision_table()
    cushion = table[table["j"] == 0]
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot()
    colours = _ball_colours(result.scene.n_bodies)
    for k in range(result.scene.n_bodies):
        rows = cushion[cushion["i"] == k + 1]
        ax.plot(rows["boundary_s"], np.sin(rows["reflection_angle"]), ".", ms=2, color=colours[k],
                label=f"ball {k + 1}")
    ax.set_xlim(0, result.scene.boundary.perimeter())
    ax.set_ylim(-1, 1)
    ax.set_xlabel("boundary arc length s (m)")
    ax.set_ylabel("sin(reflection angle)")
    ax.set_title(f"Birkhoff map: {len(cushion)} cushion impacts", fontsize=9)
    if result.scene.n_bodies > 1:
        ax.legend(fontsize=7, markerscale=4)
    _save(fig, path)


def _aspect(scene) -> float:
    bx, by = scene.boundary.outline()
    width, height = np.ptp(bx), np.ptp(by)
    return float(np.clip(height / width, 0.4, 1.5)) if width > 0 else 1.0


def portrait_figure(scene, launches: list, path: Path, ball: int = 1) -> None:
    """The Birkhoff map of many launches of ball ``ball`` (from 1; heyroll.analysis.billiard_portrait), one
    colour per launch."""
    import matplotlib

    fig = Figure(figsize=(8, 5))
    ax = fig.add_subplot()
    cmap = matplotlib.colormaps["turbo"]
    for k, run in enumerate(launches):
        ax.plot(run["s"], run["sin_angle"], ".", ms=1.5, color=cmap((k + 0.5) / len(launches)))
    ax.set_xlim(0, scene.boundary.perimeter())
    ax.set_ylim(-1, 1)
    ax.set_xlabel("boundary arc length s (m)")
    ax.set_ylabel("sin(reflection angle)")
    total = sum(len(run["s"]) for run in launches)
    ax.set_title(f"Birkhoff map of {len(launches)} launches ({total} cushion impacts), one colour per launch\n"
                 f"{scene.boundary.describe()}, ball {ball} of radius {float(scene.balls[ball - 1].body.radius):.4g} m",
                 fontsize=9)
    _save(fig, path)


def _ball_colours(n: int) -> list:
    """One colour per ball: matplotlib's ten, then tab20's, then a colormap (ball 11 had ball 1's colour:
    acceptance test)."""
    import matplotlib

    if n <= 10:
        return [f"C{k}" for k in range(n)]
    if n <= 20:
        return [matplotlib.colormaps["tab20"](k) for k in range(n)]
    cmap = matplotlib.colormaps["turbo"]
    return [cmap((k + 0.5) / n) for k in range(n)]
