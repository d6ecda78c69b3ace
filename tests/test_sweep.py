"""Sweeps (issue 16): grid, list and random points, the store, resume, bad input, Dask, figures."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest

xr = pytest.importorskip("xarray")
pytest.importorskip("zarr")

import heyroll
from heyroll.interfaces.cli import main
from heyroll.interfaces.scene_file import default_scene_text, load_scene
from heyroll.sweep import SweepError, SweepKeyError, SweepStoreError, open_sweep, run_sweep
from heyroll.sweep import run as sweep_run
from heyroll.sweep.plan import make_plan

ROOT = Path(__file__).resolve().parents[1]
#: Short runs of the default scene: a few collisions each, well under a second for a whole sweep.
T_END = 10.0


def scene_with(text: str, **fields) -> str:
    """The default scene's text with top-level-table lines ``field = value`` replaced (value as written)."""
    lines = []
    table = ""
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("["):
            table = stripped.strip("[]")
        name = stripped.split("=")[0].strip()
        if f"{table}.{name}" in fields:
            line = f"{name} = {fields[f'{table}.{name}']}"
        lines.append(line)
    return "\n".join(lines) + "\n"


def test_a_grid_point_is_what_simulate_gives_for_that_scene_alone_to_the_last_bit(tmp_path):
    ds = run_sweep(vary={"collision.restitution": "0.8:1:3"}, keep="impacts:4", t_end=T_END, workers=1,
                   out=tmp_path)
    assert ds["collision.restitution"].values.tolist() == [0.8, 0.9, 1.0]
    for k, text in enumerate(["0.8", "0.9", "1.0"]):  # the decimal a scene file would hold
        scene = heyroll.parse_scene(scene_with(default_scene_text(), **{"collision.restitution": text}))
        result = heyroll.simulate(scene, t_end=T_END)
        point = ds.isel({"collision.restitution": k})
        assert str(point["status"].values) == result.status.value
        assert str(point["message"].values) == result.message
        assert int(point["collisions"]) == result.n_collisions > 4
        assert float(point["t_final"]) == float(result.t_final)
        assert float(point["energy_initial"]) == result.energy_initial
        assert float(point["energy_final"]) == result.energy_final
        assert np.array_equal(point["final_state"].values, result.final_state)
        last = result.collision_table()[-4:]
        for column in ("n", "t", "i", "j", "q_i", "q_j", "dq_i_before", "dq_j_before", "dq_i_after", "dq_j_after"):
            assert np.array_equal(point[f"impact_{column}"].values, last[column]), column


def test_grid_values_are_the_decimals_start_to_stop():
    plan = make_plan(grid=[("vary", "collision.restitution=0.5:1:6"), ("vary", "g=9:10:3")])
    assert plan.axes[0].values == tuple(Decimal(v) for v in ("0.5", "0.6", "0.7", "0.8", "0.9", "1.0"))
    assert plan.axes[1].values == (Decimal(9), Decimal("9.5"), Decimal(10))
    assert plan.dims == ("collision.restitution", "g") and plan.shape == (6, 3) and plan.n_points == 18


def test_two_dimensions_in_command_line_order_with_units(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["sweep", "--values", "bodies[2].mass=50,100", "--vary", "bodies[1].dphi=0:1:3",
                 "--t-end", "2", "--workers", "1", "--out", str(out), "--progress", "off"]) == 0
    ds = open_sweep(out / "sweep.zarr")
    assert ds["status"].dims == ("bodies[2].mass", "bodies[1].dphi")
    assert ds["bodies[2].mass"].values.tolist() == [50.0, 100.0]
    assert ds["bodies[1].dphi"].values.tolist() == [0.0, 0.5, 1.0]
    assert ds["bodies[2].mass"].attrs["units"] == "kg" and ds["bodies[1].dphi"].attrs["units"] == "rad/s"
    assert ds["final_state"].dims[-1] == "state" and ds["state"].values.tolist() == ["phi1", "phi2", "dphi1", "dphi2"]
    assert set(ds["status"].values.ravel()) == {"completed"}
    # A body given by density takes the point's mass instead (mass and density are one quantity).
    alone = heyroll.parse_scene(default_scene_text().replace("radius = 0.15\ndensity = 7850.0", "radius = 0.15\nmass = 100"))
    assert float(alone.bodies[1].mass) == 100.0
    assert float(ds["energy_initial"].sel({"bodies[2].mass": 100.0, "bodies[1].dphi": 0.0})) == \
        heyroll.simulate(alone, t_end=0.1).energy_initial
    printed = capsys.readouterr().out
    assert "6 points: bodies[2].mass (2) x bodies[1].dphi (3)" in printed
    assert "6 points: 6 completed" in printed
    assert (out / "map_energy_loss.png").read_bytes()[:4] == b"\x89PNG"
    assert (out / "map_collisions.png").is_file()


def test_random_points_from_the_seed(tmp_path):
    ds = run_sweep(random={"bodies[1].phi": (-1.2, -0.8), "collision.restitution": "0.5:1"}, samples=5, seed=3,
                   t_end=1.0, workers=1, out=tmp_path)
    draws = np.random.default_rng(3)
    assert ds["status"].dims == ("point",) and ds["point"].values.tolist() == [0, 1, 2, 3, 4]
    assert np.array_equal(ds["bodies[1].phi"].values, draws.uniform(-1.2, -0.8, 5))
    assert np.array_equal(ds["collision.restitution"].values, draws.uniform(0.5, 1.0, 5))
    assert ds["bodies[1].phi"].attrs["units"] == "rad"
    assert set(ds["status"].values) == {"completed"}


def test_a_sweep_table_in_the_scene_file_and_run_ignores_it(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(default_scene_text() + '\n[sweep]\nvalues = ["collision.restitution=0.5,1"]\nkeep = "impacts:2"\n')
    assert main(["sweep", str(scene), "--t-end", "1", "--workers", "1", "--out", str(tmp_path / "s"),
                 "--no-figures", "--progress", "off"]) == 0
    ds = open_sweep(tmp_path / "s" / "sweep.zarr")
    assert ds["collision.restitution"].values.tolist() == [0.5, 1.0] and ds.sizes["impact"] == 2
    assert main(["run", str(scene), "--t-end", "1", "--out", str(tmp_path / "r"), "--no-figures"]) == 0


def test_invalid_points_are_recorded_and_the_sweep_goes_on(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["sweep", "--values", "bodies[1].radius=0.1,1.5", "--values", "collision.restitution=0.5,1.5",
                 "--t-end", "1", "--workers", "1", "--out", str(out), "--progress", "off", "--no-figures"]) == 0
    ds = open_sweep(out / "sweep.zarr")
    status = ds["status"].values
    assert status[0, 0] == "completed"
    assert status[0, 1] == status[1, 0] == status[1, 1] == "invalid_scene"
    assert str(ds["message"].values[1, 0]).startswith("bodies[1].radius:")
    assert str(ds["message"].values[0, 1]).startswith("collision.restitution:")
    assert int(ds["collisions"].values[1, 0]) == -1 and np.isnan(ds["t_final"].values[1, 0])
    assert "4 points: 3 invalid_scene, 1 completed" in capsys.readouterr().out
    # xarray's idioms on the text variables (Zarr's StringDType made where() raise, acceptance test)
    kept = ds.where(ds["status"] == "completed")
    assert int(kept["collisions"].count()) == 1 and ds["status"].dtype.kind == "U"


def test_a_base_scene_refused_for_what_the_sweep_does_not_vary_is_refused(tmp_path, capsys):
    """Acceptance test: a typo in [track] (or k = 1.5) while sweeping g wrote a store of 3 invalid_scene points,
    exit 0. Now: one line, exit 2, nothing written; a base scene refused on a varied KEY is swept."""
    typo = tmp_path / "typo.toml"
    typo.write_text(default_scene_text().replace("radius = 1.0", "raduis = 1.0", 1))
    out = tmp_path / "out"
    assert main(["sweep", str(typo), "--vary", "g=9:10:3", "--workers", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("heyroll: error: track.raduis: unknown key")
    assert not out.exists()
    strong = tmp_path / "strong.toml"
    strong.write_text(scene_with(default_scene_text(), **{"collision.restitution": "1.5"}))
    assert main(["sweep", str(strong), "--vary", "g=9:10:3", "--workers", "1", "--out", str(out)]) == 2
    assert capsys.readouterr().err.startswith("heyroll: error: collision.restitution: must be in [0, 1]")
    assert not out.exists()
    ds = run_sweep(strong, vary={"collision.restitution": "0.5:1:2"}, t_end=1.0, workers=1, out=out)
    assert ds["status"].values.tolist() == ["completed", "completed"]
    # A base scene refused on a field that the varied values change (body 2 placed onto body 1, its radius
    # varied) is swept in either order (review: one point decided, so the order did).
    near = tmp_path / "near.toml"
    near.write_text(default_scene_text().replace("phi = 0.5", "phi = -0.75"))
    for spec in ("0.15:0.05:3", "0.05:0.15:3"):
        ds = run_sweep(near, vary={"bodies[2].radius": spec}, t_end=0.5, workers=1, out=tmp_path / spec)
        assert "invalid_scene" in ds["status"].values.tolist() and "completed" in ds["status"].values.tolist()


@pytest.mark.parametrize("key, says", [
    ("bodies[3].mass", "the scene has 2 bodies"),
    ("collision.law", "no numeric field 'law'"),
    ("frame.omga", "no numeric field 'omga'"),
    ("track.hump_radius", "no numeric field 'hump_radius'"),
    ("bodies.mass", "name a body"),
])
def test_an_unknown_key_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, key, says):
    out = tmp_path / "out"
    assert main(["sweep", "--vary", f"{key}=0:1:3", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"heyroll: error: {key}: unknown sweep key") and says in err
    assert not out.exists()
    with pytest.raises(SweepKeyError) as caught:
        make_plan(grid=[("vary", f"{key}=0:1:3")])
    assert isinstance(caught.value, ValueError) and caught.value.field == key


def test_a_table_key_of_another_boundary_is_refused(tmp_path, capsys):
    """track.radius on an elliptical table was accepted and every point recorded as an invalid scene (acceptance
    test): a field of another boundary is now an unknown key, one line, exit 2, nothing written."""
    from pathlib import Path

    scene = Path(__file__).parents[1] / "examples" / "elliptical_billiard.toml"
    out = tmp_path / "out"
    assert main(["sweep", str(scene), "--vary", "track.radius=0.5:1.5:3", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "track.radius: unknown sweep key" in err and "a, b," in err
    assert not out.exists()


@pytest.mark.parametrize("args, says", [
    (["--vary", "g=1:2"], "expected START:STOP:N"),
    (["--vary", "g=1:2:0"], "N in START:STOP:N"),
    (["--values", "g=1,x"], "'x' is not a number"),
    (["--values", "g=1,1.0"], "repeated"),
    (["--random", "g=2:1", "--samples", "3"], "LO < HI"),
    (["--random", "g=1:2"], "the number of random points"),
    (["--vary", "g=1:2:3", "--random", "g=1:2", "--samples", "2"], "not both"),
    (["--vary", "g=1:2:3", "--keep", "impacts:0"], "M in impacts:M"),
    (["--vary", "g=1:2:3", "--vary", "g=3:4:2"], "varied twice"),
    (["--values", "run.max_collisions=1.5,2"], "whole numbers"),
    ([], "nothing to sweep"),
])
def test_bad_sweep_specs_are_one_line_exit_2(tmp_path, capsys, args, says):
    out = tmp_path / "out"
    assert main(["sweep", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err
    assert not out.exists()


def test_resume_after_an_interruption_gives_the_identical_store(tmp_path):
    plan = make_plan(grid=[("vary", "collision.restitution=0.6:1.0:5"), ("values", "bodies[1].dphi=0,0.5")],
                     keep="impacts:3", t_end=T_END, chunk_points=2)
    assert plan.chunks == (1, 2) and len(plan.regions()) == 5
    sweep_run.execute(plan, tmp_path / "whole", workers=1, command="sweep")

    def stop_after_two_chunks(n):
        if n == 2:
            raise KeyboardInterrupt  # as Ctrl-C between two chunks

    with pytest.raises(KeyboardInterrupt):
        sweep_run.execute(plan, tmp_path / "part", workers=1, command="sweep", after_chunk=stop_after_two_chunks)
    partial = open_sweep(tmp_path / "part" / "sweep.zarr")
    assert (partial["status"].values != "").sum() == 4  # two chunks of two points
    outcome = sweep_run.execute(plan, tmp_path / "part", workers=1, command="sweep")
    assert outcome.stored_before == 4 and outcome.statuses == {"completed": 10}
    assert open_sweep(tmp_path / "part" / "sweep.zarr").identical(open_sweep(tmp_path / "whole" / "sweep.zarr"))


def _cli(args: list, cwd: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "heyroll.interfaces.cli", *args], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _stored(store: Path) -> int:
    """Points stored so far (0 while the store does not exist yet)."""
    import zarr

    try:
        return int((zarr.open_array(str(store / "status"), mode="r")[...] != "").sum())
    except Exception:  # not created yet (zarr's error type for a missing array varies by version)
        return 0


ARGS = ["sweep", "--vary", "bodies[1].phi=-1.2:-0.8:48", "--t-end", "1500", "--keep", "impacts:2", "--workers", "1",
        "--out", "out", "--no-figures", "--progress", "off"]


def _stop_when_a_chunk_is_stored(process: subprocess.Popen, store: Path, sig) -> tuple:
    deadline = time.monotonic() + 60
    while _stored(store) == 0 and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    process.send_signal(sig)
    stdout, _ = process.communicate(timeout=60)
    assert 0 < _stored(store) < 48, "the sweep ended before the signal: make its points longer"
    return process.returncode, stdout


def test_a_sigkilled_cli_sweep_resumed_by_the_same_command_gives_the_identical_store(tmp_path):
    # The same relative --out in two directories: the recorded command is the same text.
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    reference = _cli(ARGS, tmp_path / "a")
    store = tmp_path / "b" / "out" / "sweep.zarr"
    code, _ = _stop_when_a_chunk_is_stored(_cli(ARGS, tmp_path / "b"), store, signal.SIGKILL)
    assert code == -signal.SIGKILL
    resumed = _cli(ARGS, tmp_path / "b")
    assert resumed.wait(timeout=120) == 0 and reference.wait(timeout=120) == 0
    assert "resumed:" in resumed.stdout.read()
    assert open_sweep(store).identical(open_sweep(tmp_path / "a" / "out" / "sweep.zarr"))
    assert not list(store.rglob("*.partial"))


def test_ctrl_c_stops_a_cli_sweep_with_exit_130_and_whole_chunks(tmp_path):
    store = tmp_path / "out" / "sweep.zarr"
    code, stdout = _stop_when_a_chunk_is_stored(_cli(ARGS, tmp_path), store, signal.SIGINT)
    assert code == 130 and "interrupted:" in stdout and "the same command continues" in stdout
    status = open_sweep(store)["status"].values
    stored = status != ""
    assert stored.sum() % 3 == 0  # chunks of 3 points (48 / 16), each stored whole or not at all
    assert set(status[stored]) == {"completed"}


def test_a_store_of_another_sweep_is_refused_and_left_as_it_was(tmp_path, capsys):
    out = tmp_path / "out"
    common = ["--t-end", "1", "--workers", "1", "--out", str(out), "--no-figures", "--progress", "off"]
    assert main(["sweep", "--values", "collision.restitution=0.5,1", *common]) == 0
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    capsys.readouterr()
    # the same points written otherwise resume the store (review: 0.50:1.2:8 refused 0.5:1.2:8's store)
    assert main(["sweep", "--values", "collision.restitution=0.50,1.0", *common]) == 0
    assert "resumed: 2 points were stored already" in capsys.readouterr().out
    assert main(["sweep", "--values", "collision.restitution=0.5,0.9", *common]) == 2
    printed = capsys.readouterr()
    assert printed.err.count("\n") == 1 and "belongs to a different sweep (grid differ)" in printed.err
    assert printed.out == ""  # (the plan's header was printed before the refusal: review)
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*")} == before
    (tmp_path / "other" / "sweep.zarr").mkdir(parents=True)
    with pytest.raises(SweepStoreError, match="not a heyroll sweep store"):
        run_sweep(values={"g": [9, 10]}, out=tmp_path / "other", workers=1)


def test_an_unreachable_scheduler_is_one_line_exit_2(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sweep_run, "SCHEDULER_TIMEOUT", 1)
    out = tmp_path / "out"
    assert main(["sweep", "--vary", "g=9:10:2", "--scheduler", "tcp://127.0.0.1:9", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("heyroll: error: --scheduler: cannot reach the dask scheduler")
    assert not out.exists()


def test_a_scheduler_with_no_worker_is_one_line_exit_2(tmp_path, capsys, monkeypatch):
    """Review: a reachable scheduler with no worker took the tasks and ran none; the sweep waited in silence."""
    from distributed import LocalCluster

    monkeypatch.setattr(sweep_run, "WORKER_WAIT", 1)
    out = tmp_path / "out"
    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        code = main(["sweep", "--vary", "g=9:10:2", "--scheduler", cluster.scheduler_address, "--out", str(out),
                     "--progress", "off"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and "has no worker" in err and "dask worker" in err
    assert not out.exists()


@pytest.mark.parametrize("answer", [b"SSH-2.0-OpenSSH_9.6\r\nHTTP/1.1 400 Bad Request\r\n\r\n", None],
                         ids=["a_banner", "silence"])
def test_a_service_that_is_not_a_scheduler_is_one_line_exit_2(tmp_path, capsys, monkeypatch, answer):
    """Review: a text banner made Dask fail with a MemoryError (a traceback, exit 1); a service that accepts
    and says nothing (an HTTP server) held the sweep past Dask's timeout for minutes."""
    import socket
    import threading

    monkeypatch.setattr(sweep_run, "SCHEDULER_TIMEOUT", 1)
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    server.settimeout(0.2)
    accepted, stop = [], threading.Event()

    def serve():
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                continue
            accepted.append(conn)
            if answer is not None:
                conn.sendall(answer)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    out = tmp_path / "out"
    started = time.monotonic()
    try:
        code = main(["sweep", "--vary", "g=9:10:2", "--scheduler", f"tcp://127.0.0.1:{server.getsockname()[1]}",
                     "--out", str(out)])
    finally:
        stop.set()
        thread.join()
        for conn in accepted:
            conn.close()
        server.close()
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith("heyroll: error: --scheduler: cannot reach the dask scheduler")
    assert time.monotonic() - started < 10 and accepted and not out.exists()


def test_a_local_two_worker_cluster_gives_the_in_process_store(tmp_path, capsys):
    spec = dict(vary={"collision.restitution": (0.5, 1.0, 12)}, keep="impacts:3", t_end=T_END)
    alone = run_sweep(out=tmp_path / "alone", workers=1, **spec)
    assert len(make_plan(grid=[("vary", "collision.restitution=0.5:1.0:12")]).regions()) == 12  # a task each
    cluster = run_sweep(out=tmp_path / "cluster", workers=2, **spec)
    assert cluster.identical(alone)


def test_plot_draws_the_bifurcation_diagram_of_one_key(tmp_path, capsys):
    run_sweep(vary={"collision.restitution": (0.7, 1.0, 4)}, keep="impacts:5", t_end=T_END, workers=1, out=tmp_path)
    figures = tmp_path / "figures"
    assert main(["plot", str(tmp_path / "sweep.zarr"), "--out", str(figures)]) == 0
    assert (figures / "bifurcation.png").read_bytes()[:4] == b"\x89PNG"
    assert f"wrote {figures / 'bifurcation.png'}" in capsys.readouterr().out
    assert main(["plot", str(tmp_path / "nothing.zarr")]) == 2
    assert "is not a sweep store" in capsys.readouterr().err
    with pytest.raises(SweepError, match="--scalar"):
        from heyroll.sweep.figures import sweep_figures

        sweep_figures(tmp_path / "sweep.zarr", figures, "speed")


def test_sweep_speed_study_runs_and_prints_its_report(tmp_path):
    report = tmp_path / "sweep_speed.md"
    done = subprocess.run([sys.executable, str(ROOT / "validation" / "sweep_speed.py"), "--points", "64",
                           "--ensemble-points", "16", "--ensemble-collisions", "20", "--output", str(report)],
                          capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, done.stderr
    assert report.read_text(encoding="utf-8").strip() == done.stdout.strip()
    throughput, setup = done.stdout.split("## Set-up before the first step")
    throughput = throughput.split("## Batch")[0]
    rows = [line for line in throughput.splitlines() if line.startswith("| ") and "---" not in line][1:]
    assert [r.split("|")[1].strip() for r in rows][:2] == ["loop: load + simulate", "loop: simulate only"]
    assert all(float(r.split("|")[4]) > 0 for r in rows)  # points per second
    assert [r.split("|")[7].strip() for r in rows[2:] if "batch" not in r] == ["yes"] * 3  # to the last bit
    assert [r.split("|")[7].strip().startswith("within") for r in rows if "--batch" in r] == [True]
    cases = [line.split("|") for line in setup.splitlines() if line.startswith("| ") and "---" not in line][1:]
    assert [c[1].strip() for c in cases] == ["new points (Scene.with_state)", "new points (the loader)",
                                              "one scene run again"]
    assert all(float(c[2]) > 0 for c in cases)


# ----------------------------------------------------------------------------- --keep lists and the estimates

#: Two equal balls (k = 1) released at rest symmetrically about the bottom of a circle: they meet
#: at -phi_c, +phi_c with opposite rates, swap them, climb back to -+0.5 and return: every impact is
#: the same, a period-1 impact sequence of period 2 x the fall from 0.5 to phi_c.
SYMMETRIC = """name = "symmetric"
g = 9.81
[track]
type = "circle"
radius = 1.0
[[bodies]]
shape = "solid_sphere"
radius = 0.1
mass = 1.0
phi = -0.5
dphi = 0.0
[[bodies]]
shape = "solid_sphere"
radius = 0.1
mass = 1.0
phi = 0.5
dphi = 0.0
[collision]
law = "hedrih"
restitution = 1.0
[run]
t_end = 20.0
"""


def test_keep_is_a_comma_list_in_canonical_order_and_bad_items_are_one_line(tmp_path, capsys):
    plan = make_plan(grid=[("vary", "g=9:10:2")], keep="rotation, period,impacts:4,first:2,lyapunov")
    assert plan.keep.text == "impacts:4,first:2,period,lyapunov,rotation" == plan.spec()["keep"]
    assert make_plan(grid=[("vary", "g=9:10:2")], keep=["summary", "period"]).keep.text == "period"
    assert make_plan(grid=[("vary", "g=9:10:2")]).spec()["keep"] == "summary"
    assert make_plan(grid=[("vary", "g=9:10:2")], keep="impacts:3").spec()["keep"] == "impacts:3"  # as before
    for keep, says in [("impacts:2,impacts:3", "given twice"), ("period:3", "comma list"), ("first:0", "M in first:M"),
                       ("strobe:3", "needs a forced scene"), ("lyapunov,,", "comma list"), ("chaos", "comma list")]:
        out = tmp_path / "out"
        assert main(["sweep", "--vary", "g=9:10:2", "--keep", keep, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and says in err, (keep, err)
        assert not out.exists()


def test_period_of_a_symmetric_head_on_pair_is_one_impact_checked_by_hand(tmp_path):
    import mpmath

    ds = run_sweep(scene_text=SYMMETRIC, values={"bodies[1].phi": [-0.5, -0.4]},
                   keep="impacts:3,first:2,period,rotation", workers=1, out=tmp_path)
    assert ds["period"].dims == ds["status"].dims and ds["period"].dtype == np.int64
    symmetric, lopsided = ds.isel({"bodies[1].phi": 0}), ds.isel({"bodies[1].phi": 1})
    assert int(symmetric["period"]) == 1 and int(symmetric["collisions"]) >= 17
    # By hand: phi'' = -a sin(phi); from rest at -0.5 to the contact at -phi_c, sin(phi_c) = r / (R - r).
    scene = heyroll.parse_scene(SYMMETRIC)
    a = mpmath.mpf(float(scene.track.angular_stiffness(scene.bodies[0], scene.g)))
    phi_c = mpmath.asin(mpmath.mpf(1) / 9)
    fall = mpmath.quad(lambda p: 1 / mpmath.sqrt(2 * a * (mpmath.cos(p) - mpmath.cos(0.5))), [-0.5, -phi_c])
    assert float(symmetric["period_time"]) == pytest.approx(float(2 * fall), rel=1e-9)
    assert np.allclose(symmetric["impact_q_i"].values, -float(phi_c), rtol=1e-9)
    assert np.all(np.diff(symmetric["impact_t"].values) == pytest.approx(float(2 * fall), rel=1e-9))
    # The first impacts: the first is the fall itself; equal to simulate's.
    result = heyroll.simulate(scene, t_end=20.0)
    assert np.array_equal(symmetric["first_impact_t"].values, result.collision_table()["t"][:2])
    assert float(symmetric["first_impact_t"][0]) == pytest.approx(float(fall), rel=1e-9)
    # Rotation: body 1 oscillates, its net turn over the run is its final phase's offset.
    assert float(symmetric["rotation"]) == (result.final_state[0] - result.initial_state[0]) / (2 * np.pi * 20.0)
    # Released off-centre, the pair's impacts wander (quasi-periodic): no period.
    assert int(lopsided["period"]) == 0 and np.isnan(float(lopsided["period_time"]))
    assert int(lopsided["collisions"]) >= 17 + 4  # enough impacts to test p = 1..4 at least


def test_period_detection_on_synthetic_sequences():
    from heyroll.sweep.points import IMPACT_COLUMNS, impact_period

    def table(pairs, q, rate, t):
        rows = np.zeros(len(t), dtype=[(c, np.int64 if c in ("n", "i", "j") else float) for c in IMPACT_COLUMNS])
        rows["i"], rows["j"] = np.array(pairs).T
        rows["q_i"] = rows["q_j"] = q
        rows["dq_i_after"], rows["dq_j_after"] = rate, -np.asarray(rate)
        rows["t"] = t
        return rows

    n = 60
    three = np.arange(n) % 3
    # Period 3 in the positions (one wraps around the circle between cycles), pairs alternating.
    q = np.array([0.1, 2.0, 3.1])[three] + 2 * np.pi * (np.arange(n) // 3)
    t = np.cumsum(np.array([0.5, 0.25, 1.0])[three])
    rows = table([(1, 2), (2, 1), (1, 2)] * (n // 3), q, np.array([1.0, -2.0, 3.0])[three], t)
    assert impact_period(rows, angle=True) == (3, pytest.approx(1.75))
    assert impact_period(rows, angle=False)[0] == 0  # unwrapped, the positions never repeat
    assert impact_period(rows[:3 + 15], angle=True) == (0, pytest.approx(np.nan, nan_ok=True))  # too few impacts
    drift = rows.copy()
    drift["dq_i_after"] *= 1 + 1e-5 * np.arange(n)  # a slow drift: above 1e-6 relative
    assert impact_period(drift, angle=True)[0] == 0


def test_lyapunov_estimate_per_point_with_its_error_and_nan_with_a_reason(tmp_path):
    from heyroll.analysis.horizon import lyapunov_estimate
    from heyroll.sweep.points import block_error

    ds = run_sweep(values={"collision.restitution": [0.9, 1.0]}, keep="lyapunov", t_end=6.0, workers=1, out=tmp_path)
    scene = heyroll.parse_scene(scene_with(default_scene_text(), **{"collision.restitution": "1.0"}))
    estimate = lyapunov_estimate(scene, t_end=6.0)
    point = ds.sel({"collision.restitution": 1.0})
    assert float(point["lyapunov"]) == estimate.exponent
    assert float(point["lyapunov_error"]) == block_error(estimate.times, estimate.history) > 0
    assert str(point["lyapunov_message"].values) == estimate.message
    assert ds["lyapunov"].attrs["units"] == "1/s"
    # Blocks: the rates of equal halves 1 and 3 1/s -> mean 2, standard error 1.
    assert block_error([1, 2, 3, 4], [1, 1, 5 / 3, 2], blocks=2) == pytest.approx(1.0)
    assert np.isnan(block_error([1, 2, 3], [1, 1, 1]))  # too few segments
    # A forced path scene: not estimated, NaN and the reason; no rotation number off a circle.
    forced = run_sweep(ROOT / "examples" / "rough_parabola_forced.toml", values={"forcing.amplitude": [2.0]},
                       keep="lyapunov,rotation", t_end=2.0, workers=1, out=tmp_path / "forced")
    assert np.isnan(forced["lyapunov"]).all() and np.isnan(forced["rotation"]).all()
    assert "slip state" in str(forced["lyapunov_message"].values[0])
    # A smooth curve in a turning plane: estimated like a circle scene (the same function, the same number).
    turning = run_sweep(ROOT / "examples" / "rotating_curve.toml", values={"frame.omega": [2.0, 3.0]},
                        keep="lyapunov", t_end=5.0, workers=1, out=tmp_path / "turning")
    alone = lyapunov_estimate(load_scene(ROOT / "examples" / "rotating_curve.toml"), t_end=5.0)
    assert float(turning["lyapunov"].sel({"frame.omega": 3.0})) == alone.exponent
    assert np.isfinite(turning["lyapunov_error"]).all()


def test_strobe_samples_of_a_forced_scene_and_the_poincare_figure(tmp_path, capsys):
    from heyroll.sweep.figures import sweep_figures

    scene = ROOT / "examples" / "rough_parabola_forced.toml"
    ds = run_sweep(scene, values={"forcing.amplitude": [1.5, 2.0, 2.5]}, keep="strobe:4,period", t_end=8.0,
                   workers=1, out=tmp_path)
    assert ds["strobe_state"].dims == ("forcing.amplitude", "strobe", "state")
    assert ds["state"].values.tolist() == ["x1", "dx1"]
    alone = heyroll.parse_scene(scene.read_text().replace("amplitude = 2.0", "amplitude = 2.5"))
    strobe = heyroll.simulate(alone, t_end=8.0).strobe_table  # t = 0, pi, 2 pi: one slot of 4 empty
    point = ds.sel({"forcing.amplitude": 2.5})
    assert len(strobe) == 3 and np.isnan(point["strobe_t"].values[3])
    assert np.array_equal(point["strobe_t"].values[:3], strobe[:, 0])
    assert np.array_equal(point["strobe_state"].values[:3], strobe[:, 1:])
    assert main(["plot", str(tmp_path / "sweep.zarr"), "--out", str(tmp_path / "f")]) == 0
    assert (tmp_path / "f" / "poincare.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "f" / "scalars.png").is_file()  # period against the amplitude
    assert sweep_figures(tmp_path / "sweep.zarr", tmp_path / "g", points=[0])[-1].name == "poincare.png"
    with pytest.raises(SweepError, match="point numbers run from 0 to 2"):
        sweep_figures(tmp_path / "sweep.zarr", tmp_path / "g", points=[3])


def test_plot_maps_the_estimates_of_two_keys(tmp_path, capsys):
    run_sweep(vary={"collision.restitution": (0.9, 1.0, 2), "bodies[1].dphi": (0, 0.5, 2)},
              keep="period,lyapunov,rotation", t_end=3.0, workers=1, out=tmp_path)
    capsys.readouterr()
    assert main(["plot", str(tmp_path / "sweep.zarr"), "--out", str(tmp_path / "f")]) == 0
    printed = capsys.readouterr().out
    for name in ("energy_loss", "collisions", "period", "lyapunov", "rotation"):
        assert f"map_{name}.png" in printed and (tmp_path / "f" / f"map_{name}.png").is_file()
    assert main(["plot", str(tmp_path / "sweep.zarr"), "--out", str(tmp_path / "g"), "--scalar", "period_time"]) == 0
    run_sweep(vary={"g": (9, 10, 2), "collision.restitution": (0.9, 1.0, 2)}, t_end=1.0, workers=1, out=tmp_path / "s")
    assert main(["plot", str(tmp_path / "s" / "sweep.zarr"), "--scalar", "lyapunov"]) == 2  # not kept there
    assert "must be one of energy_loss, collisions, t_final, relative_energy_change" in capsys.readouterr().err


def test_precision_reaches_every_point_and_the_store_says_it(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(default_scene_text() + '\n[sweep]\nvalues = ["collision.restitution=0.9,1"]\nprecision = "long"\n'
                     'keep = "impacts:2,period"\n')
    ds = run_sweep(scene, t_end=2.0, workers=1, out=tmp_path / "long")
    assert ds.attrs["precision"] == "long" and make_plan(scene).spec()["precision"] == "long"
    alone = heyroll.parse_scene(scene_with(default_scene_text(), **{"collision.restitution": "0.9"}))
    result = heyroll.simulate(alone, t_end=2.0, precision="long")
    point = ds.sel({"collision.restitution": 0.9})
    assert ds["t_final"].dtype == np.float64 and ds["impact_t"].dtype == np.float64
    assert float(point["energy_final"]) == result.energy_final
    assert np.array_equal(point["final_state"].values, np.asarray(result.final_state, dtype=float))
    assert np.array_equal(point["impact_t"].values, result.collision_table()["t"][-2:])
    assert "precision" not in make_plan(grid=[("vary", "g=9:10:2")]).spec()  # double: the spec as before
    with pytest.raises(SweepStoreError, match="precision differ"):
        run_sweep(scene, t_end=2.0, workers=1, out=tmp_path / "long", precision="double")
    with pytest.raises(SweepError, match="--precision: unknown precision 'single'"):
        make_plan(grid=[("vary", "g=9:10:2")], precision="single")


def test_resume_with_estimates_gives_the_identical_store(tmp_path):
    plan = make_plan(scene_text=SYMMETRIC, grid=[("values", "bodies[1].phi=-0.5,-0.45,-0.4,2")],
                     keep="impacts:2,first:2,period,lyapunov,rotation", t_end=4.0, chunk_points=2)
    sweep_run.execute(plan, tmp_path / "whole", workers=1, command="sweep")

    def stop(n):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sweep_run.execute(plan, tmp_path / "part", workers=1, command="sweep", after_chunk=stop)
    outcome = sweep_run.execute(plan, tmp_path / "part", workers=1, command="sweep")
    assert outcome.stored_before == 2 and outcome.statuses == {"completed": 3, "invalid_scene": 1}
    whole = open_sweep(tmp_path / "whole" / "sweep.zarr")
    assert open_sweep(tmp_path / "part" / "sweep.zarr").identical(whole)
    invalid = whole.isel({"bodies[1].phi": 3})  # phi = 2 overlaps ball 2: recorded with its error
    assert str(invalid["status"].values) == "invalid_scene" and int(invalid["period"]) == -1
    assert np.isnan(float(invalid["lyapunov"])) and str(invalid["lyapunov_message"].values) == ""


def test_the_cli_passes_precision_and_picks_poincare_points(tmp_path):
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "sweep", "--values",
                           "collision.restitution=0.9,1", "--precision", "long", "--workers", "1", "--t-end", "1",
                           "--no-figures", "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert open_sweep(out / "sweep.zarr").attrs["precision"] == "long"
    bad = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "sweep", "--values",
                          "collision.restitution=0.9,1", "--precision", "single", "--out", str(tmp_path / "bad")],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "--precision" in bad.stderr and bad.stderr.count("\n") == 1
    plot = subprocess.run([sys.executable, "-m", "heyroll.interfaces.cli", "plot", str(out / "sweep.zarr"),
                           "--points", "x"], capture_output=True, text=True, timeout=120)
    assert plot.returncode == 2 and "--points" in plot.stderr


def test_long_figure_titles_are_broken_to_fit_the_figure():
    """Acceptance test: a one-key table sweep's title ran past the figure's right edge."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from heyroll.sweep.figures import _title

    fig, ax = plt.subplots(figsize=(7.5, 3))
    text = "dissipative elliptical billiard: 300 points: cushion impacts among the last 10 impacts each (Birkhoff coordinates)"
    _title(ax, text, fontsize=10)
    fig.canvas.draw()
    shown = ax.title.get_window_extent()
    assert ax.title.get_text().replace("\n", " ") == text and "\n" in ax.title.get_text()
    assert 0 <= shown.x0 and shown.x1 <= fig.bbox.x1
    plt.close(fig)


def test_a_rough_track_sweep_keeps_its_last_impacts_and_period(tmp_path):
    """Acceptance test: --keep impacts:M (or period) on a rough track raised 'too many values to unpack' (the
    run's records carry the friction modes too) and left a store of '' statuses."""
    text = ('[track]\ntype = "circle"\nradius = 1.2\nfriction = 0.15\nstatic_friction = 0.25\n'
            '[[bodies]]\nshape = "particle"\nmass = 0.5\nphi = -0.8\ndphi = 0.0\n'
            '[[bodies]]\nshape = "particle"\nmass = 0.8\nphi = 0.6\ndphi = -1.5\n'
            '[collision]\nlaw = "newton"\nrestitution = 0.7\n')
    ds = run_sweep(scene_text=text, vary={"collision.restitution": "0.5:0.9:2"}, keep="impacts:3,period", t_end=40.0,
                   workers=1, out=tmp_path)
    for k, value in enumerate(["0.5", "0.9"]):
        result = heyroll.simulate(heyroll.parse_scene(text.replace("restitution = 0.7", f"restitution = {value}")),
                                  t_end=40.0)
        point = ds.isel({"collision.restitution": k})
        assert str(point["status"].values) == result.status.value
        kept = [t for t in point["impact_t"].values.tolist() if t == t]  # (NaN after a run's last impact)
        assert kept == result.collision_table()["t"][-3:].tolist() and kept
        assert "period" in ds


def test_keep_repeated_is_one_list_and_points_without_strobe_samples_are_refused(tmp_path, capsys):
    """`--keep a --keep b` is `--keep a,b` (argparse would keep the last); `plot --points` on a store without
    stroboscopic samples is refused in one line, before any figure is drawn."""
    out = tmp_path / "s"
    assert main(["sweep", "--values", "collision.restitution=0.9,1.0", "--keep", "impacts:3", "--keep", "period",
                 "--max-collisions", "20", "--workers", "1", "--out", str(out), "--progress", "off",
                 "--no-figures"]) == 0
    ds = open_sweep(out / "sweep.zarr")
    assert "period" in ds.data_vars and ds.sizes["impact"] == 3
    capsys.readouterr()
    assert main(["plot", str(out / "sweep.zarr"), "--out", str(tmp_path / "f"), "--points", "0"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--points" in err and "strobe:M" in err
    assert not (tmp_path / "f").exists() or not any((tmp_path / "f").iterdir())
    assert main(["run", "--max-collisions", "1", "--no-figures", "--out", str(tmp_path / "r"),
                 "--progress", "off"]) == 0
    assert "1 collision, 0 limiter impacts, 0 junction passages" in capsys.readouterr().out


@pytest.mark.parametrize("keys", [("bodies[1].dphi", "bodies[1].omega"), ("bodies[2].density", "bodies[2].mass")])
def test_two_keys_that_set_one_quantity_are_refused(keys, tmp_path):
    """dphi and omega (mass and density) of one body are one quantity: varied together, the second written
    dropped the first and one axis was silently ignored (its points labelled apart, equal: acceptance test)."""
    with pytest.raises(SweepError, match=r"are one quantity .* vary one of them") as caught:
        make_plan(None, grid=[("vary", f"{keys[0]}=0.5:1:2"), ("vary", f"{keys[1]}=0.5:1:2")])
    assert caught.value.field == "--vary"
    with pytest.raises(SweepError, match="one quantity"):
        make_plan(None, random=[f"{keys[0]}=0.5:1", f"{keys[1]}=0.5:1"], samples=3)
    assert make_plan(None, grid=[("vary", f"{keys[0]}=0.5:1:2"), ("vary", "bodies[2].phi=0.1:0.2:2")]).n_points == 4


def test_a_scalar_with_no_finite_value_is_refused_not_drawn_empty(tmp_path, capsys):
    """relative_energy_change divides by energy_initial: on a forced track that starts at energy 0 every point
    was inf, and `plot --scalar relative_energy_change` drew an empty figure with a made-up axis, exit 0
    (acceptance test). It is undefined there (NaN) and the plot refuses it in one line."""
    out = tmp_path / "s"
    run_sweep(ROOT / "examples" / "rough_parabola_forced.toml", values={"forcing.amplitude": [1.5, 2.0]}, t_end=1.0,
              workers=1, out=out)
    capsys.readouterr()
    assert main(["plot", str(out / "sweep.zarr"), "--out", str(tmp_path / "f"), "--scalar",
                 "relative_energy_change"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--scalar" in err and "energy_initial = 0" in err
    assert not (tmp_path / "f").exists()


def test_a_body_given_by_its_shape_is_swept_over_kappa(tmp_path):
    """Review: bodies[N].kappa is a numeric key, but on a body given by its shape every point was invalid
    ("give shape or kappa, not both"); kappa now stands for the shape, as mass does for density."""
    from heyroll.interfaces.scene_file import default_scene_text

    scene = tmp_path / "s.toml"  # (the default scene's ball 1 given by its mass: a density needs a shape)
    scene.write_text(default_scene_text().replace("density = 7850.0          # steel, kg/m^3", "mass = 0.0329", 1))
    ds = run_sweep(scene, values={"bodies[1].kappa": "1.4,2"}, t_end=1.0, workers=1, out=tmp_path / "k")
    assert list(ds["status"].values) == ["completed", "completed"]
    final = ds["final_state"].values
    assert not (final[0] == final[1]).all()  # (ball 1 rolls down with kappa 1.4 or 2: not the same motion)


def test_the_progress_bar_shows_every_stored_chunk(capsys):
    """Acceptance test: tqdm's own pacing skipped updates, and the bar said 188 of 3000 at a Ctrl-C that
    left 376 stored."""
    from heyroll.sweep.run import _progress_bar

    with _progress_bar("on", 3000, 0) as bar:
        for stored in range(1, 6):
            bar.update(188)
            shown = capsys.readouterr().err.rsplit("\r", 1)[-1]
            assert f"{188 * stored}/3000" in shown


def test_figures_of_invalid_points_say_so(tmp_path, monkeypatch):
    """Review: a 1-D sweep whose points were all invalid drew an empty bifurcation diagram over a made-up axis,
    with no word why (the 2-D maps counted them)."""
    from heyroll.sweep import figures

    out = tmp_path / "bad"
    assert main(["sweep", "--values", "bodies[1].radius=1.5,1.6", "--keep", "impacts:2", "--t-end", "1",
                 "--workers", "1", "--out", str(out), "--progress", "off", "--no-figures"]) == 0
    titles, notes = [], []
    monkeypatch.setattr(figures, "_title", lambda ax, text, fontsize=12: titles.append(text))
    real = figures._none_to_draw
    monkeypatch.setattr(figures, "_none_to_draw", lambda ax, count: (notes.append(count), real(ax, count)))
    paths = figures.sweep_figures(out / "sweep.zarr", out)
    assert [p.name for p in paths] == ["bifurcation.png"] and paths[0].exists()
    assert titles and all(", 2 invalid" in t for t in titles) and notes == [0]


def test_a_map_of_points_that_ran_without_a_value_says_so(tmp_path, monkeypatch):
    """Review: every point of a rough track's sweep completed, its Lyapunov exponent not estimated (NaN): the map
    said "4 invalid or not run" over a colour bar of nothing. Now it tells points that ran with no value apart."""
    from heyroll.sweep import figures

    out = tmp_path / "rough"
    scene = Path(__file__).parent.parent / "examples" / "rough_parabola_forced.toml"
    assert main(["sweep", str(scene), "--vary", "forcing.amplitude=1:2:2", "--vary", "forcing.frequency=1:2:2",
                 "--keep", "lyapunov", "--t-end", "0.5", "--workers", "1", "--out", str(out), "--progress", "off",
                 "--no-figures"]) == 0
    titles = []
    monkeypatch.setattr(figures, "_title", lambda ax, text, fontsize=12: titles.append(text))
    paths = figures.sweep_figures(out / "sweep.zarr", out, scalar="lyapunov")
    assert [p.name for p in paths] == ["map_lyapunov.png"]
    assert titles == [titles[0]] and titles[0].endswith("; 4 ran with no value (blank)") and "invalid" not in titles[0]
