"""The heyroll command line: outputs as documented, bad input exits 2 and writes nothing."""

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import heyroll
from heyroll.interfaces.cli import main
from heyroll.interfaces.scene_file import load_scene

from conftest import EXAMPLE, body, scene_text

REQUIRED_COLUMNS = (
    "n,t,i,j,q_i,q_j,omega_i_before,omega_j_before,omega_i_after,omega_j_after,energy_before,energy_after"
).split(",")
SUMMARY_KEYS = {"status", "message", "collisions", "t_final", "energy_initial", "energy_final", "final_state", "wall_time_s", "versions"}


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_run_default_scene_writes_every_output(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", "--out", str(out), "--max-collisions", "6"]) == 0
    assert {p.name for p in out.iterdir()} == {"collisions.csv", "summary.json", "phase_portrait.png", "energy.png"}
    rows = read_csv(out / "collisions.csv")
    assert list(rows[0])[: len(REQUIRED_COLUMNS)] == REQUIRED_COLUMNS
    assert len(rows) == 6
    summary = json.loads((out / "summary.json").read_text())
    assert SUMMARY_KEYS <= set(summary)
    assert summary["status"] == "max_collisions" and summary["collisions"] == 6
    assert {"heyroll", "heyoka", "numpy"} <= set(summary["versions"])
    assert len(summary["final_state"]) == 2 and {"q", "dq"} <= set(summary["final_state"][0])
    for png in ("phase_portrait.png", "energy.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "max_collisions" in capsys.readouterr().out


def test_csv_floats_round_trip_exactly(tmp_path):
    out = tmp_path / "out"
    assert main(["run", str(EXAMPLE), "--out", str(out), "--no-figures"]) == 0
    rows = read_csv(out / "collisions.csv")
    table = heyroll.simulate(heyroll.load_scene(EXAMPLE)).collision_table()
    assert len(rows) == table.size == 20  # [run] max_collisions = 20
    for name in ("t", "q_i", "omega_j_after", "energy_before"):
        assert np.array_equal(np.array([float(r[name]) for r in rows]), table[name])
    assert all(len(r["t"].replace(".", "").replace("-", "").split("e")[0].lstrip("0")) <= 17 for r in rows)


def test_overrides_from_the_command_line(tmp_path):
    out = tmp_path / "o"
    assert main(["run", str(EXAMPLE), "--out", str(out), "--t-end", "2.5", "--max-collisions", "1000", "--no-figures"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["t_final"] == 2.5


BAD_FILES = {
    "radius": scene_text(body(radius="1.0")),
    "typo": scene_text(body(extra="mas = 1.0")),
    "not toml": "[[[ not toml",
    "overlap": scene_text(body(phi="0.0") + body(phi="0.05")),
    "restitution": scene_text(body(phi="-1") + body(phi="1"), extra="[collision]\nrestitution = 2.0"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_scene_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, case):
    path = tmp_path / "scene.toml"
    path.write_text(BAD_FILES[case])
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("heyroll: error: ")
    assert not out.exists()


@pytest.mark.parametrize(
    "args",
    [["--t-end", "nan"], ["--t-end", "-1"], ["--t-end", "inf"], ["--max-collisions", "-2"], ["--max-collisions", "x"], ["--precision", "octuple"], ["--precision", "mp:12"], ["--bogus"],
     ["--tolerance", "0"], ["--tolerance", "1"], ["--tolerance", "x"], ["--tolerance", "nan"]],
)
def test_bad_arguments_exit_2_and_write_nothing(tmp_path, capsys, args):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) if args == ["--bogus"] else _no_raise():
        code = main(["run", "--out", str(out), *args])
        assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error" in err
    assert not out.exists()


class _no_raise:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_console_script_reports_without_traceback(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(scene_text(body(shape="cube")))
    proc = subprocess.run(
        [sys.executable, "-m", "heyroll.interfaces.cli", "run", str(path), "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip() == "heyroll: error: bodies[1].shape: unknown shape 'cube'; expected one of solid_sphere | hollow_sphere | disk | ring | particle"


def test_quad_run_writes_36_digit_round_trip_table(tmp_path):
    import heyoka

    out = tmp_path / "q"
    assert main(["run", "--out", str(out), "--max-collisions", "3", "--precision", "quad", "--no-figures"]) == 0
    rows = read_csv(out / "collisions.csv")
    result = heyroll.simulate(heyroll.default_scene(), max_collisions=3, precision="quad")
    for row, t in zip(rows, result.times):
        digits = row["t"].lstrip("-").replace(".", "").lstrip("0")
        assert len(digits) == 36
        assert heyoka.real128(row["t"]) == t
    summary = json.loads((out / "summary.json").read_text())
    assert summary["significant_digits"] == 36
    # acceptance test: the final state was only in floats; a quad run could not be continued from its summary
    texts = summary["final_state_text"]
    nb = len(texts)
    for k, entry in enumerate(texts):
        assert heyoka.real128(entry["q"]) == result.final_state[k]
        assert heyoka.real128(entry["dq"]) == result.final_state[nb + k]


def test_validate_writes_a_report_with_every_section(tmp_path, capsys):
    out = tmp_path / "val"
    out.mkdir()
    # acceptance test: an earlier run's table and summary stayed beside the report's figures of another run
    for name in ("collisions.csv", "summary.json", "lyapunov.png", "birkhoff_map.png"):
        (out / name).write_text("stale")
    (out / "notes.txt").write_text("mine")
    assert main(["validate", "--out", str(out), "--collisions", "4", "--progress", "on"]) == 0
    # every long job shows progress: a bar over the report's sections (it took 20 s with none)
    assert "validate: 100%" in capsys.readouterr().err
    assert (out / "notes.txt").read_text() == "mine"
    assert not any((out / name).exists() for name in ("collisions.csv", "summary.json", "birkhoff_map.png"))
    report = (out / "report.md").read_text()
    for heading in (
        "## Collision times: double, quad and the exact reference",
        "## Energy jumps at collisions",
        "## Phase trajectory branches with jumps",
        "## The paper's truncated series against the exact elliptic integral",
        "## The paper's method end to end",
        "## Predictability horizon",
        "## Versions, precisions and cost",
    ):
        assert heading in report
    assert "pair sequence identical" in report
    for png in ("energy.png", "phase_portrait.png", "series_error.png", "horizon.png", "lyapunov.png"):
        assert (out / png).read_bytes()[:4] == b"\x89PNG"


def test_a_run_replaces_an_earlier_runs_outputs_and_leaves_other_files(tmp_path):
    # measured before: an old collisions.npy and old figures stayed beside a new collisions.csv
    out = tmp_path / "out"
    out.mkdir()
    for name in ("collisions.npy", "collisions.parquet", "energy.png", "phase_portrait.png", "passages.csv",
                 ".collisions.csv.tmp", "report.md", "horizon.png"):  # a report's too: it shares figure names
        (out / name).write_text("stale")
    (out / "notes.txt").write_text("mine")
    assert main(["run", "--out", str(out), "--t-end", "2", "--no-figures", "--progress", "off"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["collisions.csv", "notes.txt", "summary.json"]


@pytest.mark.parametrize("out", ["", "   ", "/dev/null/sub", "/proc/heyroll-cannot-create"])
def test_an_out_directory_that_cannot_be_written_is_one_line_exit_2(out, capsys):
    assert main(["run", "--out", out, "--t-end", "1", "--no-figures", "--progress", "off"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("heyroll: error: --out:"), err


def test_an_io_error_while_writing_leaves_no_half_written_set(tmp_path, capsys, monkeypatch):
    # A full disk while the summary is written (simulated): one line, exit 2, no outputs kept.
    from heyroll.interfaces import outputs

    def full(path, text):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(outputs, "atomic_write_text", full)
    out = tmp_path / "out"
    assert main(["run", "--out", str(out), "--t-end", "2", "--no-figures", "--progress", "off"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "No space left on device" in err[0]
    assert not out.exists()  # its partial outputs removed, and the directory the run made for them
    kept = tmp_path / "kept"  # a directory that was there before stays, empty
    kept.mkdir()
    assert main(["run", "--out", str(kept), "--t-end", "2", "--no-figures", "--progress", "off"]) == 2
    assert list(kept.iterdir()) == []


def test_no_command_prints_the_usage_and_exits_2(capsys):
    assert main([]) == 2
    err = capsys.readouterr().err
    assert "usage: heyroll" in err and "run" in err and err.strip().endswith("a command is required")


def test_max_events_stops_a_run_whose_events_pile_up(tmp_path):
    out = tmp_path / "out"
    chain = str(Path(__file__).resolve().parent.parent / "examples" / "arc_chain.toml")
    assert main(["run", chain, "--out", str(out), "--max-events", "5",
                 "--no-figures", "--progress", "off"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "max_events" and summary["limiter_impacts"] + summary["junction_passages"] == 5
    assert main(["run", "--out", str(out), "--max-events", "0", "--progress", "off"]) == 2


def test_drawn_branches_are_pieces_of_the_run_ending_at_the_next_collision():
    # measured before the fix: the figure's last branch (after collision 30) was integrated
    # without collision events to t_end, and the two balls passed through each other on it.
    from heyroll.interfaces.scene_file import default_scene
    from heyroll.simulation.trajectory import sample_branches

    scene = default_scene()
    result = heyroll.simulate(scene, t_end=60.0)
    assert result.n_collisions > 31
    branches = sample_branches(result, max_branches=31)
    assert len(branches) == 31
    assert branches[-1].times[-1] == pytest.approx(float(result.times[30]), abs=1e-12)
    for b in branches:
        gaps = scene.gap(0, 1, b.states[:, 0], b.states[:, 1])
        assert gaps.min() > -1e-9


def test_fast_and_tolerance_are_run_settings_recorded_in_the_summary(tmp_path):
    out = tmp_path / "fast"
    assert main(["run", "--fast", "--tolerance", "1e-13", "--t-end", "20", "--no-figures", "--progress", "off",
                 "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["fast_math"] is True and summary["tolerance"] == 1e-13
    default = tmp_path / "default"
    assert main(["run", "--t-end", "20", "--no-figures", "--progress", "off", "--out", str(default)]) == 0
    reference = json.loads((default / "summary.json").read_text())
    assert reference["fast_math"] is False and summary["collisions"] == reference["collisions"]
    # The price: the elastic scene's energy error grows, still small over 20 s.
    error = abs(summary["energy_final"] - summary["energy_initial"]) / summary["energy_initial"]
    assert error < 1e-9


def test_python_dash_m_heyroll_is_the_command_line():
    done = subprocess.run([sys.executable, "-m", "heyroll", "--version"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and heyroll.__version__ in done.stdout + done.stderr


def test_bad_numbers_are_shown_as_written(tmp_path, capsys):
    """Acceptance review: 'got Decimal('-0.2')' (the scene file's decimals by their Python repr)."""
    path = tmp_path / "negmu.toml"
    path.write_text(scene_text(body(), track='type = "circle"\nradius = 1.0\nfriction = -0.2'))
    assert main(["run", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "track.friction" in err and "got -0.2" in err and "Decimal" not in err
    assert main(["sweep", str(path), "--vary", "collision.restitution=0:1:3", "--workers", "-2"]) == 2
    assert "--workers: must be >= 1, got -2" in capsys.readouterr().err


def test_import_heyroll_loads_neither_heyoka_nor_matplotlib():
    # The command catches a Ctrl-C from its first instruction on only if importing the package is instant.
    code = "import sys, heyroll; heyroll.__version__; print(sorted(m for m in ('heyoka', 'matplotlib', 'mpmath') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
    assert heyroll.Scene.__module__ == "heyroll.model.scene" and "TableBall" in dir(heyroll)


def test_ctrl_c_while_the_command_starts_is_one_line_and_exit_130(monkeypatch, capsys):
    import types

    import heyroll.__main__ as entry

    class Loading(types.ModuleType):  # the command's module, interrupted while it loads
        def __getattr__(self, name):
            raise KeyboardInterrupt

    monkeypatch.setitem(sys.modules, "heyroll.interfaces.cli", Loading("heyroll.interfaces.cli"))
    assert entry.main(["run"]) == 130
    err = capsys.readouterr().err
    assert err == "heyroll: interrupted while starting: nothing was run or written\n"


def test_ctrl_c_outside_a_runs_own_handling_is_one_line_and_exit_130(tmp_path, monkeypatch, capsys):
    from heyroll.interfaces import cli

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "load_scene", interrupted)  # a Ctrl-C while the scene's file is read
    assert main(["run", "some.toml", "--out", str(tmp_path / "never")]) == 130
    assert capsys.readouterr().err == "heyroll: run: interrupted\n"
    assert not (tmp_path / "never").exists()


def test_the_command_called_in_process_leaves_ctrl_c_alone(tmp_path):
    """Review: heyroll.__main__.main() set SIGINT to be ignored for the rest of the calling process (a notebook,
    a test run); only the script's entry (console) does, once the command has returned."""
    import signal

    import heyroll.__main__ as entry

    before = signal.getsignal(signal.SIGINT)
    assert entry.main(["run", "--out", str(tmp_path / "o"), "--max-collisions", "2", "--no-figures"]) == 0
    assert signal.getsignal(signal.SIGINT) is before


def test_an_interrupted_run_says_how_to_skip_its_figures(tmp_path, monkeypatch, capsys):
    """Acceptance test: after a Ctrl-C a long run's figures took 14 s more, unannounced; it now says Ctrl-C again
    skips them (one line on stderr; the table and summary.json are written first)."""
    import dataclasses

    from heyroll.interfaces import cli
    from heyroll.simulation.result import Status

    real = cli.simulate

    def interrupted(*args, **kwargs):
        return dataclasses.replace(real(*args, **kwargs), status=Status.INTERRUPTED, message="interrupted at t = ...")

    monkeypatch.setattr(cli, "simulate", interrupted)
    assert main(["run", "--out", str(tmp_path / "o"), "--max-collisions", "3"]) == 130
    assert "Ctrl-C again to skip them" in capsys.readouterr().err
    assert {"collisions.csv", "summary.json", "phase_portrait.png"} <= {p.name for p in (tmp_path / "o").iterdir()}


def test_a_reader_that_goes_away_leaves_the_run_whole(tmp_path):
    """Acceptance test: `heyroll run ... | head -1` raised BrokenPipeError at the first line (a traceback, exit 1,
    the run stopped before it started). Output past a closed pipe is dropped; the run completes and writes."""
    process = subprocess.Popen([sys.executable, "-m", "heyroll", "run", "--out", str(tmp_path), "--no-figures",
                                "--t-end", "50", "--progress", "off"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    process.stdout.close()  # the reader is gone before the first line
    errors = process.stderr.read().decode()
    assert process.wait() == 0 and "Traceback" not in errors
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "completed"


@pytest.mark.parametrize("value", ["-1e-10", "-2.5E+3", "-.5e1"])
def test_a_negative_number_with_an_exponent_gets_the_options_own_rule(value, tmp_path, capsys):
    """Acceptance test: `--tolerance -1e-10` gave argparse's 'expected one argument' (it took the value for an
    option); `--tolerance=-1e-10` gave the option's own one-line error. Both give that now."""
    assert main(["run", "--out", str(tmp_path / "out"), "--tolerance", value]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--tolerance" in err[0] and "expected one argument" not in err[0]
    assert not (tmp_path / "out").exists()


def test_a_closed_stdout_leaves_the_run_whole(tmp_path):
    """Review: with stdout closed (`heyroll run ... >&-`) sys.stdout is None: an AttributeError traceback and
    nothing written. Its output now goes nowhere and the run completes."""
    process = subprocess.run([sys.executable, "-m", "heyroll", "run", "--out", str(tmp_path), "--no-figures",
                              "--t-end", "50", "--progress", "off"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             close_fds=True, preexec_fn=lambda: __import__("os").close(1))
    assert process.returncode == 0 and "Traceback" not in process.stderr.decode()
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "completed"


def test_validate_writes_its_report_where_the_lyapunov_reference_leaves_a_one_sided_track(tmp_path):
    """Acceptance test: on a one-sided circle the Lyapunov estimate's reference run stops where the body would
    leave the track: a RuntimeError traceback, no report.md. The report now says why there is no estimate."""
    scene = tmp_path / "one_sided.toml"
    scene.write_text('[track]\ntype = "circle"\nradius = 1.0\nsides = "one"\n[[bodies]]\nshape = "disk"\n'
                     'radius = 0.1\nmass = 1.0\nphi = 0.0\ndphi = 4.5\n[collision]\nlaw = "hedrih"\nrestitution = 0.9\n'
                     '[run]\nt_end = 5\n')
    assert main(["validate", str(scene), "--out", str(tmp_path / "val"), "--collisions", "3"]) == 0
    report = (tmp_path / "val" / "report.md").read_text()
    assert "largest Lyapunov exponent: not estimated (the reference trajectory failed" in report


def test_a_run_with_no_trajectory_to_draw_writes_its_summary_and_says_no_figures(tmp_path, capsys, monkeypatch):
    """A path-track run that failed at its start (a curve whose x**4 was NaN at x = 0, acceptance test) has no
    continuous output: drawing its figures raised a traceback and summary.json was never written. Now the
    summary says why there are no figures, the report says it in one line, and summary.json is strict JSON
    (a non-finite number is null, not NaN)."""
    import dataclasses

    import heyroll.interfaces.portrait_figures  # noqa: F401  (imported now, they bind the real simulate:
    import heyroll.interfaces.report  # noqa: F401  first imported under the patch, they kept it for later tests)
    import heyroll.simulation.driver as driver

    real = driver.simulate

    def without_trajectory(scene, **kwargs):  # the figures' dense re-run of a run that failed at once
        result = real(scene, **kwargs)
        return dataclasses.replace(result, dense=()) if kwargs.get("dense") else result

    monkeypatch.setattr(driver, "simulate", without_trajectory)
    out = tmp_path / "o"
    assert main(["run", str(EXAMPLE.parent / "arc_chain.toml"), "--t-end", "0.5", "--out", str(out),
                 "--progress", "off"]) == 0
    report = capsys.readouterr().out
    assert "no figures: the run has no trajectory to draw" in report
    summary = json.loads((out / "summary.json").read_text(), parse_constant=lambda name: pytest.fail(name))
    assert summary["files"]["figures"].startswith("none: ") and not list(out.glob("*.png"))
    from heyroll.interfaces.outputs import _finite_or_null

    assert _finite_or_null({"e": [1.0, float("nan"), float("inf")], "s": "x"}) == {"e": [1.0, None, None], "s": "x"}


def test_a_circle_run_stopped_at_its_start_draws_no_empty_figures(tmp_path, capsys):
    """Acceptance test: a body placed where a one-sided circle cannot hold it stops at t = 0 (left_track); its
    energy.png and phase_portrait.png were empty axes, listed in files. Now: no figures, and why."""
    scene = tmp_path / "left.toml"
    scene.write_text('[track]\ntype = "circle"\nradius = 1.0\nsides = "one"\n[[bodies]]\nshape = "solid_sphere"\n'
                     'radius = 0.1\nmass = 1.0\nphi = 2.5\ndphi = 0.0\n')
    out = tmp_path / "o"
    assert main(["run", str(scene), "--out", str(out), "--progress", "off"]) == 1
    assert "no figures: the run has no trajectory to draw (left_track at t = 0 s" in capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "left_track" and summary["files"]["figures"].startswith("none: ")
    assert not list(out.glob("*.png")) and "energy" not in summary["files"]


def test_bad_input_found_after_the_out_directory_was_made_leaves_no_directory(tmp_path, capsys):
    """`billiard portrait --ball 5` on a 4-ball table: exit 2, one line, and the --out it had created is gone
    (an empty directory was left behind: acceptance test); --max-events says one rule for 0 and -5."""
    table = str(EXAMPLE.parent / "newtons_cradle.toml")
    out = tmp_path / "bp"
    assert main(["billiard", "portrait", table, "--ball", "5", "--out", str(out)]) == 2
    assert not out.exists() and capsys.readouterr().err.count("\n") == 1
    nested = tmp_path / "nest" / "a" / "b"  # every directory it made goes, not only the innermost (review)
    assert main(["billiard", "portrait", table, "--ball", "5", "--out", str(nested)]) == 2
    assert not (tmp_path / "nest").exists()
    for bad in ("0", "-5", "x"):
        assert main(["run", "--max-events", bad, "--out", str(tmp_path / "r")]) == 2
        assert "--max-events: must be a whole number >= 1 (or 'none')" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_a_forced_run_draws_its_stroboscopic_section_from_the_whole_run(tmp_path, monkeypatch):
    """The path-track figures come from a dense re-run cut at FIGURE_COLLISIONS collisions; the stroboscopic
    section came from it too, and a forced run with more collisions than that before its first sample wrote no
    stroboscopic.png (acceptance test: 1756 collisions, 7 samples). It is the whole run's now."""
    from heyroll.interfaces import figures

    monkeypatch.setattr(figures, "FIGURE_COLLISIONS", 0)  # the re-run stops at its first collision
    scene = tmp_path / "forced.toml"  # two balls meet at ~0.5 s, before the first sample (nu t + psi = 2 pi: 1.64 s)
    scene.write_text('[track]\ntype = "circle"\nradius = 1.0\n' + "".join(
        f'[[bodies]]\nshape = "solid_sphere"\nradius = 0.1\nmass = 1.0\nphi = {p}\ndphi = 0.0\n' for p in ("-0.5", "0.5"))
        + '[forcing]\nkind = "force"\namplitude = 0.5\nfrequency = 2.0\nphase = 3.0\n')
    out = tmp_path / "o"
    assert main(["run", str(scene), "--t-end", "8", "--out", str(out), "--progress", "off"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["files"]["stroboscopic_figure"] == "stroboscopic.png" and (out / "stroboscopic.png").is_file()


def test_validate_does_not_hold_a_rough_or_forced_scene_to_the_smooth_reference(tmp_path):
    """validate on a rough circle compared it with the smooth circle's elliptic reference ('pair sequence
    DIFFERENT'), and on a forced path track that starts at energy 0 it divided by 0 (traceback, no report:
    acceptance test). The report now checks such scenes across precisions and says why the reference is not
    applied."""
    for name, why in (("rough_circle", "has no friction"), ("rough_parabola_forced", "has no forcing")):
        out = tmp_path / name
        assert main(["validate", str(EXAMPLE.parent / f"{name}.toml"), "--out", str(out), "--collisions", "3"]) == 0
        report = (out / "report.md").read_text()
        assert why in report and "Collision times: double and long against quad" in report
    assert "J from 0" in report  # (the forced track starts at energy 0)


def test_a_quad_run_writes_its_limiter_impacts_with_36_digits(tmp_path):
    """passages.csv had 17 digits of a quad run's times (review: 0.84674749675944216 where mpmath's quadrature gives
    0.846747496759442184838424575); now the run's own numbers, as collisions.csv."""
    import heyoka

    scene = tmp_path / "limiter.toml"
    scene.write_text('[track]\ntype = "curve"\ny = "x**2"\nx_min = -0.5\nx_max = 1.0\n'
                     '[[bodies]]\nshape = "disk"\nradius = 0.05\nmass = 1.0\nx = 0.9\n[run]\nt_end = 1\n')
    out = tmp_path / "q"
    assert main(["run", str(scene), "--out", str(out), "--precision", "quad", "--no-figures", "--progress", "off"]) == 0
    rows = read_csv(out / "passages.csv")
    result = heyroll.simulate(load_scene(scene), precision="quad")
    assert len(rows) == len(result.passages) == 1
    assert len(rows[0]["t"].replace(".", "").lstrip("0")) == 36
    assert heyoka.real128(rows[0]["t"]) == result.passages[0][0]
    assert abs(float(rows[0]["t"]) - 0.846747496759442184838424575) < 1e-16


def test_a_second_command_writing_into_the_same_out_is_refused_and_leaves_the_first_alone(tmp_path, capsys):
    """Two runs into one --out: the second's start removed the first's outputs, and the first's end the second's
    (acceptance test: an empty directory). The second is refused in one line while the first holds the directory."""
    import signal
    import time

    out = tmp_path / "shared"
    proc = subprocess.Popen([sys.executable, "-m", "heyroll.interfaces.cli", "run", "--out", str(out), "--t-end", "1e7",
                             "--no-figures", "--progress", "off"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 60
    while time.time() < deadline and not (out / ".collisions.csv.tmp").exists():
        time.sleep(0.1)
    assert main(["run", "--out", str(out), "--max-collisions", "3", "--no-figures", "--progress", "off"]) == 2
    assert capsys.readouterr().err.strip() == (f"heyroll: error: --out: another heyroll command is writing to {out}: "
                                               "let it finish or choose another directory")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"
    assert (out / "collisions.csv").exists()
    assert main(["run", "--out", str(out), "--max-collisions", "3", "--no-figures", "--progress", "off"]) == 0


@pytest.mark.parametrize("options, field", [({"tolerance": 2.0}, "tolerance"), ({"tolerance": 0.0}, "tolerance"),
                                            ({"precision": "single"}, "precision"), ({"t_end": -1.0}, "t_end"),
                                            ({"max_events": 0}, "max_events")])
def test_the_api_refuses_bad_run_options_as_the_cli_does_with_one_error_class(options, field):
    """RunOptions(tolerance=2.0) passed where --tolerance 2 is refused, and a bad precision raised a SceneError where
    every other option raises OptionsError (acceptance test). (t_end = 0 stays allowed in the API: a zero-length
    run measures the set-up.)"""
    from heyroll.simulation.driver import OptionsError

    with pytest.raises(OptionsError) as caught:
        heyroll.RunOptions(**options)
    assert caught.value.field == field and isinstance(caught.value, ValueError)


def test_a_sweep_into_a_directory_a_run_is_writing_is_refused(tmp_path, capsys):
    """Review: `heyroll sweep --out D` took no lock (a run and a sweep, or two sweeps, into one directory)."""
    from heyroll.interfaces.outputs import hold_directory

    out = tmp_path / "busy"
    out.mkdir()
    held = hold_directory(out)  # (another command's open file description: flock locks conflict across them)
    try:
        code = main(["sweep", "--vary", "collision.restitution=0.5:1:2", "--out", str(out), "--workers", "1",
                     "--t-end", "1", "--no-figures", "--progress", "off"])
        assert code == 2
        assert capsys.readouterr().err.strip().endswith(f"--out: another heyroll command is writing to {out}: "
                                                        "let it finish or choose another directory")
        assert not (out / "sweep.zarr").exists()
    finally:
        held.close()
    assert main(["sweep", "--vary", "collision.restitution=0.5:1:2", "--out", str(out), "--workers", "1",
                 "--t-end", "1", "--no-figures", "--progress", "off"]) == 0


def test_a_validation_interrupted_while_drawing_keeps_no_figures_without_their_report(tmp_path, capsys, monkeypatch):
    # The report is written last: a Ctrl-C before it left figures with no report beside them.
    from heyroll.interfaces import report

    def interrupted(scene, out_dir, **kwargs):
        (out_dir / "energy.png").write_bytes(b"\x89PNG partial")
        raise KeyboardInterrupt

    monkeypatch.setattr(report, "validate", interrupted)
    out = tmp_path / "val"
    assert main(["validate", "--out", str(out)]) == 130
    assert capsys.readouterr().err.strip() == "heyroll: validate: interrupted"
    assert list(out.iterdir()) == []


def test_a_sweep_interrupted_while_drawing_says_its_store_is_whole(tmp_path, capsys, monkeypatch):
    # Acceptance test: a Ctrl-C after the last point printed "wrote .../sweep.zarr", then "heyroll: sweep:
    # interrupted", exit 130, both at once. Now one message says what is kept and how to draw the figures.
    from heyroll.interfaces import cli

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_write_sweep_figures", interrupted)
    out = tmp_path / "sw"
    code = main(["sweep", "--vary", "collision.restitution=0.5:1:2", "--out", str(out), "--workers", "1",
                 "--t-end", "1", "--progress", "off"])
    captured = capsys.readouterr()
    assert code == 130
    assert captured.err == ""
    assert captured.out.strip().splitlines()[-1] == (f"interrupted while drawing the figures: {out}/sweep.zarr is "
                                                     f"whole; heyroll plot {out}/sweep.zarr draws them")
