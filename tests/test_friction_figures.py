"""Figures of rough-track and forced runs (heyroll.interfaces.friction_figures)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from heyroll.interfaces.friction_figures import _body_modes, _MODE_NAMES, _transitions, friction_figures
from heyroll.model.bodies import Body
from heyroll.model.forcing import Forcing
from heyroll.model.laws import make_law
from heyroll.model.scene import RunSettings, Scene
from heyroll.model.tracks import CircleTrack, CurveTrack
from heyroll.simulation.driver import simulate

PNG = b"\x89PNG\r\n\x1a\n"
PARTICLE = Body.of_shape("particle", 0, mass=1.0)


@pytest.fixture(scope="module")
def circle_run():
    """Two particles on a rough circle: collisions and friction transitions, dense output."""
    scene = Scene.make(CircleTrack.of_radius(1), [PARTICLE, PARTICLE], [-0.5, 0.8], [3.0, 0.0],
                       law=make_law("newton", 0.7), friction=0.1, static_friction=0.2, run=RunSettings.make(10))
    return simulate(scene, dense=True)


@pytest.fixture(scope="module")
def forced_run():
    """One particle on a rough parabola forced periodically (stroboscopic samples, no dense output)."""
    scene = Scene.make(CurveTrack.make("x**2/2", -3, 3), [PARTICLE], [0.0], [0.0], friction=0.1,
                       static_friction=0.2, forcing=Forcing.make("force", amplitude=2.0, frequency=2.0),
                       run=RunSettings.make(20), track_sides="one")
    return simulate(scene)


@pytest.fixture(scope="module")
def resting_run():
    """A particle at rest at the bottom of a rough parabola: it stays stuck, no transition at all."""
    scene = Scene.make(CurveTrack.make("x**2/2", -3, 3), [PARTICLE], [0.0], [0.0], friction=0.1,
                       static_friction=0.2, run=RunSettings.make(2), track_sides="one")
    return simulate(scene, dense=True)


def _check(files: dict, out, keys: set) -> None:
    assert set(files) == keys
    for name in files.values():
        path = out / name
        assert path.is_file()
        data = path.read_bytes()
        assert data[:8] == PNG
        assert 5_000 < len(data) < 5_000_000
    # Written atomically: no temporary file left behind.
    assert not [p for p in out.iterdir() if p.name.endswith(".tmp")]


def test_dense_run_with_collisions(circle_run, tmp_path):
    assert circle_run.scene.rough and circle_run.dense is not None
    assert len(circle_run.transitions) > 0 and circle_run.collision_table().size > 0
    files = friction_figures(circle_run, tmp_path)
    _check(files, tmp_path, {"friction_portrait", "friction_energy"})
    assert files == {"friction_portrait": "friction_portrait.png", "friction_energy": "friction_energy.png"}


def test_run_without_dense_output(circle_run, tmp_path):
    files = friction_figures(dataclasses.replace(circle_run, dense=None), tmp_path / "new" / "dir")
    _check(files, tmp_path / "new" / "dir", {"friction_portrait", "friction_energy"})


def test_forced_run_has_stroboscopic_section(forced_run, tmp_path):
    assert forced_run.scene.forcing is not None and forced_run.dense is None
    assert forced_run.strobe_table.shape[0] > 0
    files = friction_figures(forced_run, str(tmp_path))
    _check(files, tmp_path, {"friction_portrait", "friction_energy", "stroboscopic_figure"})
    assert files["stroboscopic_figure"] == "stroboscopic.png"


def test_forced_run_without_samples_has_no_stroboscopic_section(forced_run, tmp_path):
    files = friction_figures(dataclasses.replace(forced_run, strobe=()), tmp_path)
    _check(files, tmp_path, {"friction_portrait", "friction_energy"})


def test_run_without_transitions(resting_run, tmp_path):
    assert len(resting_run.transitions) == 0
    files = friction_figures(resting_run, tmp_path)
    _check(files, tmp_path, {"friction_portrait", "friction_energy"})
    bare = dataclasses.replace(resting_run, dense=None, friction_work=(), final_modes=())
    _check(friction_figures(bare, tmp_path / "bare"), tmp_path / "bare", {"friction_portrait", "friction_energy"})


def test_transitions_stripped_from_a_collision_run(circle_run, tmp_path):
    stripped = dataclasses.replace(circle_run, transitions=(), transition_work=())
    _check(friction_figures(stripped, tmp_path), tmp_path, {"friction_portrait", "friction_energy"})


def test_modes_along_the_run(circle_run):
    rows = _transitions(circle_run)
    for k in range(circle_run.n_bodies):
        mine = [row for row in rows if row[1] == k]
        t = np.array([0.0, float(circle_run.t_final)])
        modes = [_MODE_NAMES[i] for i in _body_modes(circle_run, rows, k, t)]
        if mine and mine[0][0] > 0:
            assert modes[0] == mine[0][2]  # before the first transition: its "from" mode
        assert modes[-1] == (mine[-1][3] if mine else circle_run.final_modes[k])
        assert modes[-1] == circle_run.final_modes[k]
