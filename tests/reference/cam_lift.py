"""A cycloidal cam cycle written out by hand (rise, dwell, return, dwell), for references.

Independent of :mod:`mechcirc.motion_laws`: the scalar right-hand sides of the
follower references (tests/scene/test_cam_jump.py, test_shaft_cam.py) use it.
"""

import math


def cycloidal_cycle(th, H, rise, dwell, ret):
    """s, s' [m, m/rad] at cam angle ``th`` [rad]: lift H, rise/dwell/return angles [rad]."""
    th = th % (2 * math.pi)
    if th < rise:
        u = th / rise
        return H * (u - math.sin(2 * math.pi * u) / (2 * math.pi)), \
            H / rise * (1 - math.cos(2 * math.pi * u))
    if th < rise + dwell:
        return H, 0.0
    if th < rise + dwell + ret:
        u = (th - rise - dwell) / ret
        return H * (1 - u + math.sin(2 * math.pi * u) / (2 * math.pi)), \
            -H / ret * (1 - math.cos(2 * math.pi * u))
    return 0.0, 0.0
