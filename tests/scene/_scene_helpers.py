"""Scene texts shared by the scene tests (built here, not by the code under test)."""

import functools
import math
import warnings
from pathlib import Path

from mechcirc.kinematics.fourbar import FourBar


def fourbar_pose(fb: FourBar, theta_pose: float):
    """Points A, B, C, D of ``fb`` at crank angle ``theta_pose`` [rad], from the closed form."""
    st = fb.evaluate(theta_pose)
    a, c, d = fb.crank, fb.rocker, fb.frame
    B = (a * math.cos(theta_pose), a * math.sin(theta_pose))
    phi4 = float(st.phi4)
    C = (d + c * math.cos(phi4), c * math.sin(phi4))
    return {"A": (0.0, 0.0), "B": B, "C": C, "D": (d, 0.0)}


def sley_scene_text(p, theta_pose: float) -> str:
    """Mrázek's one-side sley as a scene: shaft -C2- four-bar -C4- sley, posed at ``theta_pose``."""
    P = fourbar_pose(p.fourbar(), theta_pose)
    pts = "\n".join(f"{k} = [{x!r}, {y!r}]" for k, (x, y) in P.items())
    return f'''name = "sley"
units = "mm"
[points]
{pts}
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = {p.omega!r}
[[torsion]]
name = "C2"
link = "crank"
body = "shaft"
stiffness = {p.C2!r}
damping = {p.k2!r}
[[torsion]]
name = "C4"
link = "rocker"
body = "sley"
stiffness = {p.C4!r}
damping = {p.k4!r}
[[masses]]
name = "I2P"
link = "crank"
inertia = {p.I2P!r}
[[masses]]
name = "I4"
link = "rocker"
inertia = {p.I4!r}
[[masses]]
name = "I4P"
link = "sley"
inertia = {p.I4P!r}
[drive]
link = "shaft"
velocity = {p.omega!r}
'''


@functools.cache
def shipped_and_reference(name: str):
    """The shipped scene ``examples/<name>.toml`` and its run by DOP853 at rtol 1e-12 (2
    revolutions, 720 points): the reference of test_scene_simulation.py's RK4 and rk8
    tests and of test_sim_default_step.py (the six-bar), computed once for all three (the
    same call in each was 0.46 s of CPU for the six-bar)."""
    from mechcirc.scene import load_scene
    from mechcirc.scene.simulation import simulate_scene

    scene = load_scene(Path(__file__).resolve().parents[2] / "examples" / f"{name}.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = simulate_scene(scene, revolutions=2, points=720, method="DOP853", rtol=1e-12,
                             error_estimate=False)
    return scene, ref

