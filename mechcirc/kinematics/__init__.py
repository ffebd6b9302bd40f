"""Kinematics of loom mechanisms: four-bar transfer functions (Mrázek), the
beat-up synthesis of patent CN104178888, frame loading, and planar
linkages with several driving cranks (Koshel & Koshel 2014); disc cams (:mod:`.cam`).

numpy and scipy only; nothing here imports matplotlib (see :mod:`.plots`).
"""

from .cam import CamCheck, CamProfile, cam_profile
from .fourbar import DeadCentre, FourBar, FourBarState, TransmissionRange
from ._frame_loading import FrameLoading, LinkMass, beat_up_force, frame_loading
from .linkage import Crank, Linkage, LinkageMotion, LinkageState, load_linkage, parse_linkage
from .synthesis import Design, SynthesisResult, evaluate_design, solve_eq10, synthesize

__all__ = ["FourBar", "FourBarState", "DeadCentre", "TransmissionRange",
           "Design", "SynthesisResult", "evaluate_design", "solve_eq10", "synthesize",
           "LinkMass", "FrameLoading", "frame_loading", "beat_up_force",
           "CamCheck", "CamProfile", "cam_profile",
           "Crank", "Linkage", "LinkageMotion", "LinkageState", "load_linkage", "parse_linkage"]
