"""heyroll: collisions of bodies in rolling and the vibro-impact dynamics they drive.

Public API (everything else is private and may change):

    scene = heyroll.load_scene("scene.toml")      # or heyroll.default_scene()
    result = heyroll.simulate(scene)
    table = result.collision_table()              # numpy structured array

Layers, with one-way imports: ``heyroll.model`` (bodies, tracks, laws) ->
``heyroll.simulation`` (heyoka systems, events, driver, results) ->
``heyroll.interfaces`` (scene files, CLI, figures, reports).
``heyroll.reference`` is an independent mpmath solution used for validation.
"""

from ._version import __version__
from .errors import SceneError, SceneFileError
from .interfaces.scene_file import default_scene, load_scene, parse_scene
from .model.bodies import Body, Shape
from .model.laws import CollisionLaw, GeneralizedNewtonLaw, HedrihRollingLaw, NewtonCentreLaw, make_law
from .model.scene import RunSettings, Scene
from .model.tracks import CircleTrack
from .simulation.driver import simulate
from .simulation.precision import Precision
from .simulation.result import TABLE_COLUMNS, SimulationResult, Status

__all__ = [
    "Body",
    "CircleTrack",
    "CollisionLaw",
    "GeneralizedNewtonLaw",
    "HedrihRollingLaw",
    "NewtonCentreLaw",
    "Precision",
    "RunSettings",
    "Scene",
    "SceneError",
    "SceneFileError",
    "Shape",
    "SimulationResult",
    "Status",
    "TABLE_COLUMNS",
    "__version__",
    "default_scene",
    "load_scene",
    "make_law",
    "parse_scene",
    "simulate",
]
