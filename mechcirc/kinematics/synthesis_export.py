"""Synthesized beat-up four-bars as files the rest of mechcirc reads.

For each :class:`~.synthesis.Design`, two TOML files:

* ``design_K.linkage.toml`` — the four-bar as a linkage (``docs/kinematics.md``),
  posed with the crank along the frame line A→D (θ = 0 of :class:`FourBar`),
  lengths in mm, the crank turning at ``omega``;
* ``design_K.scene.toml`` — the same linkage as a scene (``docs/scenes.md``):
  Mrázek's one-side sley by default — the drive shaft turns the crank through
  the torsion rod C2 (damping k2), the rocker carries the sley through the
  torsion rod C4 (damping k4); inertias I2P (crank), I4 (rocker), I4P (sley);
  the drive is the shaft's speed.  ``mechcirc scene FILE --theta DEG`` gives its
  circuit at any crank angle.

The beat-up moment (a half sine of amplitude M0 over a crank window α around
the front dead centre) is not part of today's scene format; it is written as
a comment with its values, for the time-domain scene reader to come.

Values default to ``mechcirc.sley.preset("one-side", 1)`` (Mrázek's variant 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from ..errors import GeometryError

__all__ = ["SceneOptions", "linkage_toml", "scene_toml", "export_designs"]


@dataclass(frozen=True)
class SceneOptions:
    """Dynamic data of an exported scene (SI); defaults are Mrázek's one-side variant 1.

    Attributes
    ----------
    omega : float
        Crank (shaft) speed [rad/s].
    I2P, I4, I4P : float
        Inertias of the crank side, the rocker and the sley [kg·m²].
    C2, C4 : float
        Torsion rod stiffnesses shaft–crank and rocker–sley [N·m/rad].
    k2, k4 : float
        Their dampings [N·m·s/rad].
    M0 : float
        Beat-up moment amplitude [N·m], positive turning the sley counter-clockwise
        (a ``[[moments]]`` table when the scene reader has one, else a comment).
    alpha_deg : float
        Beat-up window [deg of crank] (written as a comment).
    """

    omega: float = 100.0
    I2P: float = 0.005
    I4: float = 0.025
    I4P: float = 0.35
    C2: float = 1.0e5
    C4: float = 5.0e4
    k2: float = 7.0
    k4: float = 29.0
    M0: float = 0.0
    alpha_deg: float = 10.0      # the sley default (fitted to Tables 1 and 2 in docs/sley.md)

    def __post_init__(self):
        for name in ("omega", "I2P", "I4", "I4P", "C2", "C4"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise GeometryError(f"scene {name} must be a positive finite number, got {v}")
        for name in ("k2", "k4"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise GeometryError(f"scene {name} must be a finite number ≥ 0, got {v}")
        if not math.isfinite(self.M0):
            raise GeometryError(f"scene M0 must be a finite number [N·m], got {self.M0}")
        if not (math.isfinite(self.alpha_deg) and 0 < self.alpha_deg <= 360):
            raise GeometryError(f"scene beat-up window must be in (0, 360] deg, got "
                                f"{self.alpha_deg}")


def _header(design, k):
    front, back = design.fourbar().dead_centres()
    return (f"# Beat-up four-bar #{k} from mechcirc synth: a = {design.a:.6g}, b = {design.b:.6g}, "
            f"c = {design.c:.6g}, d = {design.d:.6g} mm\n"
            f"# swing {design.swing_deg:.4f}°; front dead centre at θ = "
            f"{math.degrees(front.theta):.4f}°, back at θ = {math.degrees(back.theta):.4f}°\n"
            f"# pose: crank along the frame line A→D (θ = 0); θ of mechcirc is measured from it\n")


def linkage_toml(design, k: int = 1, omega: float = 100.0) -> str:
    """The design as a linkage TOML (lengths in mm, crank speed ``omega`` [rad/s]).

    Parameters
    ----------
    design : Design
        A synthesised design.
    k : int
        The design's number (in the header).
    omega : float
        Crank speed [rad/s].

    Returns
    -------
    str
    """
    pts = "\n".join(f"{p} = [{x!r}, {y!r}]"
                    for p, (x, y) in zip("ABCD", design.fourbar().joints(0.0)))
    return (_header(design, k) +
            f'name = "beat-up four-bar {k}"\nunits = "mm"\n\n[points]\n{pts}\n\n'
            '[ground]\npoints = ["A", "D"]\n\n'
            '[links]\ncrank = ["A", "B"]\ncoupler = ["B", "C"]\nrocker = ["D", "C"]\n\n'
            f'[[cranks]]\nlink = "crank"\nomega = {float(omega)!r}\n')


def scene_toml(design, k: int = 1, opts: SceneOptions = SceneOptions()) -> str:
    """The design as a scene TOML: shaft -C2- four-bar -C4- sley (see the module docstring).

    Parameters
    ----------
    design, k
        As for :func:`linkage_toml`.
    opts : SceneOptions
        Speed, inertias, rods.

    Returns
    -------
    str
    """
    o = opts
    front, _ = design.fourbar().dead_centres()
    masses = (("I2P", "crank", o.I2P), ("I4", "rocker", o.I4), ("I4P", "sley", o.I4P))
    tables = [_table("[[torsion]]            # drive shaft -> crank", name="C2", link="crank",
                     body="shaft", stiffness=o.C2, damping=o.k2),
              _table("[[torsion]]            # rocker -> sley", name="C4", link="rocker",
                     body="sley", stiffness=o.C4, damping=o.k4),
              *(_table("[[masses]]", name=name, link=link, inertia=v) for name, link, v in masses),
              _table("[drive]", link="shaft", velocity=o.omega),
              f"[analysis]\ntheta_deg = {round((math.degrees(front.theta) + 90.0) % 360.0, 6)!r}"
              "   # 90° after beat-up\n"]
    return linkage_toml(design, k, o.omega) + "\n" + "\n".join(tables) + _beat_up(o, front)


def _table(header: str, **keys) -> str:
    """The TOML table ``header`` with a line ``key = value`` per keyword, in order (a string
    quoted, a number as its ``repr``)."""
    return header + "".join(f'\n{key} = "{v}"' if isinstance(v, str) else f"\n{key} = {v!r}"
                            for key, v in keys.items()) + "\n"


def export_designs(designs, directory, opts: SceneOptions = SceneOptions()) -> list:
    """Write ``design_K.linkage.toml`` and ``design_K.scene.toml`` for each design (K from 1).

    Every file is written to a temporary name and renamed when all are
    written (:class:`~mechcirc.outputs.OutputSet`): an error leaves none.
    The folder must exist.

    Parameters
    ----------
    designs : sequence of Design
        The designs, numbered from 1 in this order.
    directory : str or Path
        An existing folder to write into.
    opts : SceneOptions
        The scenes' dynamic data.

    Returns
    -------
    list of (Path, Path)
        (linkage file, scene file) per design.
    """
    from ..outputs import OutputSet

    folder = Path(directory)
    if not folder.is_dir():
        raise GeometryError(f"{directory}: no such folder (create it first)")
    out = []
    with OutputSet() as files:
        for k, des in enumerate(designs, 1):
            lk_path = folder / f"design_{k}.linkage.toml"
            sc_path = folder / f"design_{k}.scene.toml"
            files.path(lk_path).write_text(linkage_toml(des, k, opts.omega), encoding="utf-8")
            files.path(sc_path).write_text(scene_toml(des, k, opts), encoding="utf-8")
            out.append((lk_path, sc_path))
    return out


_MOMENTS = """
[[moments]]            # the beat-up: a half sine on the sley around the front dead centre
name = "beatup"
body = "sley"
amplitude = {M0!r}     # M0 [N·m], positive turning the sley counter-clockwise
window_deg = {alpha!r}
centre = "front-dead-centre"
"""


def _beat_up(o, front):
    """The beat-up moment as the scene's ``[[moments]]`` table (``docs/scenes.md``); a zero
    moment is only a comment."""
    if o.M0 != 0:
        return _MOMENTS.format(M0=float(o.M0), alpha=float(o.alpha_deg))
    return (f"\n# No beat-up moment (M0 = 0); a half sine of amplitude M0 [N·m] over "
            f"alpha = {o.alpha_deg!r}° of crank,\n# centred on the front dead centre at theta = "
            f"{math.degrees(front.theta):.6f}° from the pose, would be a [[moments]] table.\n")
