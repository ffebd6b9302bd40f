"""Scenes (issue 7): a linkage with lumped masses and elastic elements, at a moment of its cycle.

* :mod:`.files` -- the scene TOML format, :func:`load_scene`, :func:`parse_scene`.
* :mod:`.model` -- :func:`build`: the mechanical circuit at crank angle θ.
* :mod:`.cycle` -- :func:`cycle_map`: resonances and |Q0| at shaft harmonics over a revolution.

Documented in ``docs/scenes.md``.
"""

from .files import (ElasticLink, Load, Scene, SceneDrive, SceneMass, Torsion, load_scene,
                    parse_scene)
from .cycle import CycleMap, cycle_map
from .model import SceneCircuit, build

__all__ = ["Scene", "SceneMass", "ElasticLink", "Torsion", "Load", "SceneDrive", "load_scene",
           "parse_scene", "build", "SceneCircuit", "cycle_map", "CycleMap"]
