"""Scenes: a linkage with lumped masses and elastic elements, at a moment of its cycle.

* :mod:`.files` -- the scene TOML format, :func:`load_scene`, :func:`parse_scene`.
* :mod:`.model` -- :func:`build`: the mechanical circuit at crank angle θ;
  :func:`build_needed`: that circuit reduced to what the scene's ``[analysis]`` asks for.
* :mod:`.cycle` -- :func:`cycle_map`: resonances and |Q0| at shaft harmonics over a revolution.
* :mod:`.simulation` -- :func:`simulate_scene`: the motion over whole revolutions;
  :mod:`.motion` builds its equations, :mod:`.crosscheck` compares them with the circuit.

Documented in ``docs/scenes.md``.
"""

from .cycle import CycleMap, cycle_map
from .files import (Analysis, ElasticLink, Load, Scene, SceneDrive, SceneMass, Torsion,
                    load_scene, parse_scene)
from .crosscheck import SceneCrosscheck, crosscheck_scene
from .model import SceneCircuit, build, build_needed
from .motion import MotionModel, motion_model
from .simulation import SceneMotion, simulate_scene

__all__ = ["Scene", "Analysis", "SceneMass", "ElasticLink", "Torsion", "Load", "SceneDrive",
           "load_scene", "parse_scene", "build", "build_needed", "SceneCircuit", "cycle_map",
           "CycleMap", "simulate_scene", "SceneMotion", "motion_model", "MotionModel",
           "crosscheck_scene", "SceneCrosscheck"]
