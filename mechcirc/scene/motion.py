"""A scene over the whole cycle in the time domain: :func:`motion_model`.

Each rigid part (the bodies left joined when the elastic links and torsion
rods are released) keeps its exact kinematics and gets one coordinate: the
rotation from the pose of one of its bodies — the crank for a part holding a
crank, the body itself for a single body, else a link pinned to the frame.
Every rotation and point position the energies need is tabulated against that
coordinate (value, first and second derivative from the linkage solver) and
interpolated by quintic Hermite pieces, as the sley kernel does for μ, ν.
The drive's part follows the rigid motion at crank speed Ω; the others obey
Lagrange II (:mod:`mechcirc.scene._motion_kernels`), written once for any
scene.  :mod:`mechcirc.scene.simulation` integrates it.

The model's linearisation about the rigid motion at θ is the circuit of
:func:`mechcirc.scene.build` (tested by finite differences in
``tests/scene/test_motion.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import GeometryError
from ..kinematics.linkage import Crank, Linkage
from ..motion_laws import hermite_table
from ..sources import positive_number, summary_repr
from .files import Scene

__all__ = ["MotionModel", "motion_model", "hermite_table", "dead_centre"]

TWO_PI = 2.0 * math.pi
#: Intervals of every kinematic table (per revolution or per tabulated range).
TABLE_POINTS = 1024
_LAWS = {"elastobacklash": 1, "dead-zone": 2}


@dataclass(frozen=True, eq=False)
class MotionModel:
    """A scene's equations of motion as arrays for the kernel (plain, picklable data).

    Attributes
    ----------
    scene : Scene
        The scene the equations are of.
    omega : float
        Crank shaft speed Ω [rad/s].
    parts : tuple of tuple of str
        Rigid parts, the drive's first (prescribed).
    coordinate : tuple of str
        The body whose rotation from the pose is each part's coordinate [rad].
    bodies, elements, moments : tuple of str
        Output order of body accelerations, element forces/deformations, moments.
    arrays : dict
        FI, FF, tabs, MI, MW, EI, EF, MOI, MOF, PRIG, BI (see the kernel module).
    body_fn : dict
        Body → its rotation function index (for the rigid accelerations).
    """

    __repr__ = summary_repr

    scene: Scene
    omega: float
    parts: tuple
    coordinate: tuple
    bodies: tuple
    elements: tuple
    moments: tuple
    arrays: dict
    body_fn: dict
    centre: dict
    #: Point → (x function, y function, part) for every point on a moving part (outputs).
    point_fn: dict = field(default_factory=dict)

    @property
    def n_free(self) -> int:
        return len(self.parts) - 1

    def naux(self) -> int:
        return len(self.bodies) + 2 * len(self.elements) + 2 + len(self.moments)

    def kernel_args(self, theta_s: float, limit: float, *, outputs: bool = False,
                    ripple: tuple = (0.0, 0.0), loads_on_mean: bool = False):
        """The kernel's array arguments; ``outputs``: evaluate the functions of the bodies'
        outputs too (not the points', which the kernel's outputs do not need);
        ``ripple`` = (A, ν): the crank speed is Ω + A cos(ν t) [rad/s] (default constant);
        ``loads_on_mean``: a load's reference is the rigid motion at the mean crank angle
        θs + Ω t instead of the actual one (a load to the frame, as in the circuit)."""
        a = self.arrays
        pv = np.array([self.omega, float(theta_s), float(limit),
                       float(a.get("n_out", a["FI"].shape[0]) if outputs else a["n_dyn"]),
                       1.0 if outputs else 0.0, float(ripple[0]), float(ripple[1]),
                       1.0 if loads_on_mean else 0.0])
        return (pv, a["FI"], a["FF"], a["tabs"], a["MI"], a["MW"], a["EI"], a["EF"], a["MOI"],
                a["MOF"], a["PRIG"], a["BI"])

    def rigid_state(self, theta: float, speed: float | None = None):
        """y = [q, q̇] of the free parts in the rigid motion at crank rotation θ, the crank
        turning at ``speed`` [rad/s] (default Ω)."""
        from ._motion_kernels import load_python

        kern = load_python()
        a = self.arrays
        w = self.omega if speed is None else float(speed)
        vd = [kern.feval(*function_args(a, r), theta)[:2] for r in a["PRIG"][1:]]
        return np.array([v for v, _ in vd] + [d * w for _, d in vd])


class Builder:
    """The kernel's functions of the parts' coordinates as they are made: FI, FF rows and the
    tables (the first a dummy of n rows)."""

    def __init__(self, n, period=TWO_PI):
        self.FI, self.FF, self.tabs = [], [], [np.zeros((n, 6))]
        self.n, self.period = n, period

    def table(self, part, lo, h, f, f1, f2, periodic, w=0.0, period=None):
        f = np.asarray(f, float) - w * (lo + h * np.arange(len(f)))
        f1 = np.asarray(f1, float) - w
        if periodic and max(np.max(np.abs(f)), np.max(np.abs(f1)),
                            np.max(np.abs(f2))) < 1e-13:
            return self.line(part, 0.0, w)          # turns exactly with the crank
        self.tabs.append(hermite_table(h, f, f1, f2))
        return self.add((0 if periodic else 1, part, len(self.tabs) - 1),
                        (0.0, 0.0, (period or self.period) if periodic else 0.0, lo, h, w))

    def line(self, part, a, b):
        """A function a + b q of part's coordinate q."""
        return self.add((2, part, 0), (a, b, 0.0, 0.0, 1.0, 0.0))

    def circle(self, part, a, b, c):
        """A circle's coordinate a + b cos(q + c) of part's angle q."""
        return self.add((3, part, 0), (a, b, c, 0.0, 1.0, 0.0))

    def add(self, fi, ff):
        """A function of its FI row ``fi`` (kind, part, table) and FF row ``ff`` (a, b, c, lo,
        h, w); its index."""
        self.FI.append(fi)
        self.FF.append(ff)
        return len(self.FI) - 1


def _winding(v, q=1):
    """Mean slope of an angle over the cycle: whole turns per q crank revolutions."""
    return float(round((v[-1] - v[0]) / TWO_PI)) / q


def motion_model(scene: Scene, omega: float | None = None, *,
                 table_points: int = TABLE_POINTS) -> MotionModel:
    """Tabulate ``scene``'s kinematics and gather its energies into a :class:`MotionModel`.

    Parameters
    ----------
    scene : Scene
        The scene to model.
    omega : float, optional
        Crank speed Ω [rad/s]; default: |ω| of the scene's first crank.
    table_points : int
        Crank angles per revolution of the kinematic tables.

    Returns
    -------
    MotionModel
        The tables and arrays the time-domain kernel reads.

    Raises
    ------
    GeometryError
        The rigid linkage cannot turn a full revolution, or a part's own
        kinematics cannot be tabulated.
    """
    lk = scene.linkage
    omega = abs(lk.cranks[0].omega) if omega is None else omega
    if not (positive_number(omega)):
        raise ValueError(f"omega must be a finite number > 0 rad/s, got {omega!r}")
    omega = float(omega)
    cam = getattr(lk, "cam", None) is not None    # a cam swings the crank: tabulate it too
    N = _table_points(lk, int(table_points))
    tables, tlink = body_tables(scene, N)
    B = Builder(N * scene.cycle_revolutions, scene.cycle)
    crank = lk.cranks[0].link
    coords, prig, makers = zip(*[_part_functions(scene, B, TWO_PI / N, i, part, tables, tlink,
                                                 cam) for i, part in enumerate(scene.parts)])
    bodies = scene.bodies
    travel = {c: i for i, c in enumerate(coords) if c not in bodies}   # "BLOCK.travel" [m]
    fns = _OnDemand(scene, makers)
    MI, MW = _inertias(scene, fns)
    EI, EF, enames = _elements(scene, prig, fns.point, fns.angle, fns.part_of)
    MOI, MOF, mnames, centres = _moments(scene, B, fns.part_of, fns.angle, crank, cam)
    body_names = tuple(bodies) + tuple(travel)
    n_dyn = len(B.FI)          # functions the dynamics need; the rest only for outputs
    BI = [fns.angle(b) if b in bodies else B.line(travel[b], 0.0, 1.0) for b in body_names]
    n_out = len(B.FI)          # and the bodies' outputs; the points' are evaluated apart
    pfn = {p: pf for p in lk.pose if (pf := fns.point(p)) is not None}   # output-only
    arrays = kernel_arrays(B, n_dyn, dict(MI=MI, MW=MW, EI=EI, EF=EF, MOI=MOI, MOF=MOF,
                                           PRIG=prig, BI=BI))
    arrays["n_out"] = n_out
    return MotionModel(scene, omega, scene.parts, tuple(coords), body_names, tuple(enames),
                       tuple(mnames), arrays, {b: f for b, f in zip(body_names, BI)}, centres,
                       pfn)


def _table_points(lk, n):
    """Table intervals per revolution: ``n``, or with a cam and the default count, the
    count nearest it that puts table nodes on the cam law's joints."""
    law = getattr(lk, "cam", None)
    if law is None or n != TABLE_POINTS:
        return n
    from .cam import aligned_points

    return aligned_points(law, n)


def body_tables(scene: Scene, N: int):
    """:func:`rigid_tables` as dicts, a torsion body given its link's rotation tables.

    Parameters
    ----------
    scene : Scene
        The scene whose rigid mechanism is tabulated over its cycle.
    N : int
        Intervals per crank revolution (the tables have N · revolutions + 1 rows).

    Returns
    -------
    tables : tuple of dict
        Rotation, its first and second θ-derivatives (body → array; a torsion
        body's are its link's), point position, velocity and acceleration
        (point → array of shape (nodes + 1, 2)).
    tlink : dict
        Body → link of the torsion rods (the first rod of a body).
    """
    ang, ang1, ang2, pos, vel, acc = (dict(x) for x in rigid_tables(scene, N))
    tlink: dict[str, str] = {}
    for t in scene.torsions:
        tlink.setdefault(t.body, t.link)
    for b, l in tlink.items():
        ang[b], ang1[b], ang2[b] = ang[l], ang1[l], ang2[l]
    return (ang, ang1, ang2, pos, vel, acc), tlink


def _part_functions(scene, B, h, i, part, tables, tlink, cam):
    """Part i's coordinate, its rigid-motion function of θ and the maker of its functions
    (kind "angle", "x" or "y", name) → function index, by the kind of part."""
    lk = scene.linkage
    crank = lk.cranks[0].link
    slide = next((x for x in lk.sliders if part == (x.link,) and x.guide == "ground"), None)
    if crank in part:                        # a geared crank alone: a linkage part
        return _crank_part(scene, B, h, i, crank, tables, cam)
    if slide is not None:
        return _block_part(scene, B, h, i, slide, tables)
    if len(part) == 1:
        return _pivoted_part(scene, B, h, i, part[0], tables)
    return _linkage_part(scene, B, h, i, part, tables, tlink)


def _crank_part(scene, B, h, i, crank, tables, cam):
    """The crank's part: its coordinate θ, turning with the crank (a cam's crank, the
    follower, swings: tabulated like its other bodies); returns (coordinate, rigid-motion
    function, maker of the part's functions)."""
    ang, ang1, ang2, pos, vel, acc = tables
    nq = scene.cycle_revolutions

    def make(kind, name):
        if kind == "angle":
            return B.line(i, 0.0, 1.0) if name == crank and not cam else B.table(
                i, 0.0, h, ang[name], ang1[name], ang2[name], True, _winding(ang[name], nq))
        k = "xy".index(kind)
        return B.table(i, 0.0, h, pos[name][:, k], vel[name][:, k], acc[name][:, k], True)
    return crank, B.line(-1, 0.0, 1.0), make


def _block_part(scene, B, h, i, slide, tables):
    """A block on a fixed guide: its coordinate is its travel s along the guide [m], every
    point at pose + s·u, no turning; returns as :func:`_crank_part`."""
    lk, L = scene.linkage, scene.length_scale
    pos, vel, acc = tables[3:]
    p, u = slide.point, np.array(slide.direction)
    rig = B.table(-1, 0.0, h, (pos[p] - lk.pose[p] * L) @ u, vel[p] @ u, acc[p] @ u, True)

    def make(kind, name):
        if kind == "angle":
            return B.line(i, 0.0, 0.0)
        k = "xy".index(kind)
        return B.line(i, float(lk.pose[name][k] * L), float(u[k]))
    return f"{slide.link}.travel", rig, make


def _pivoted_part(scene, B, h, i, b, tables):
    """A lone body: its coordinate is its rotation, its points on circles about its frame
    pivot; returns as :func:`_crank_part`."""
    lk, L = scene.linkage, scene.length_scale
    ang, ang1, ang2 = tables[:3]
    rig = B.table(-1, 0.0, h, ang[b], ang1[b], ang2[b], True,
                  _winding(ang[b], scene.cycle_revolutions))
    piv = next((p for p in scene.bodies[b] if p in lk.ground), None)

    def make(kind, name):
        if kind == "angle":
            return B.line(i, 0.0, 1.0)
        o = lk.pose[piv] * L
        r = lk.pose[name] * L - o
        rad, a0 = float(np.hypot(*r)), float(math.atan2(r[1], r[0]))
        k = "xy".index(kind)
        return B.circle(i, float(o[k]), rad, a0 - k * 0.5 * math.pi)
    return b, rig, make


class _OnDemand:
    """Function indices made once, on demand, by the parts' makers: a body's rotation,
    a point's x and y with its part (None for a frame point)."""

    def __init__(self, scene, makers):
        self.scene, self.makers, self.made = scene, makers, {}
        self.part_of = scene.part_of_body()

    def need(self, i, kind, name):
        key = (i, kind, name)
        if key not in self.made:
            self.made[key] = self.makers[i](kind, name)
        return self.made[key]

    def angle(self, body):
        return self.need(self.part_of[body], "angle", body)

    def point(self, p):
        i = self.scene.part_of_point(p)
        return None if i is None else (self.need(i, "x", p), self.need(i, "y", p), i)


def _inertias(scene, fns):
    """The kinetic energy's rows: MI function indices (a point mass's x and y, an
    inertia's rotation), MW their masses [kg] or inertias [kg·m²]."""
    MI, MW = [], []
    for m in scene.masses:
        if m.kind != "mass":
            MI.append(fns.angle(m.link))
            MW.append(m.value)
        elif (pf := fns.point(m.point)) is not None:
            MI += [pf[0], pf[1]]
            MW += [m.value, m.value]
    return MI, MW


#: The kernel's row arrays: dtype and row width (None: flat).
_ROWS = {"MI": (np.int64, None), "MW": (float, None), "EI": (np.int64, 8), "EF": (float, 10),
         "MOI": (np.int64, 2), "MOF": (float, 4), "PRIG": (np.int64, None),
         "BI": (np.int64, None)}


def function_rows(FI, FF):
    """The kernel's FF: each function's [a, b, c, lo, h, w] (``FF``, rows of 6) and the
    reciprocals 1/c of a periodic table's period (0 for the other kinds) and 1/h (a table's
    node spacing; 1 for a line or a circle), which the kernel multiplies by instead of
    dividing."""
    ff = np.array(FF, dtype=float).reshape(-1, 6)
    periodic = np.asarray(FI).reshape(-1, 3)[:, 0] == 0
    ic = np.divide(1.0, ff[:, 2], out=np.zeros(len(ff)), where=periodic)
    return np.column_stack([ff, ic, 1.0 / ff[:, 4]])


def function_args(arrays, f) -> tuple:
    """The arguments of the kernels' ``feval`` (and ``eval_many``, ``point_samples``) for
    function ``f`` of a model's ``arrays``: its kind, the tables, its table's index and its
    row of ``FF`` (the layout :func:`function_rows` makes)."""
    return (arrays["FI"][f, 0], arrays["tabs"], arrays["FI"][f, 2], *arrays["FF"][f])


def kernel_arrays(B, n_dyn, rows):
    """The kernel's arrays: the functions of ``B``, the ``rows`` as :data:`_ROWS` says, and
    ``n_dyn``, how many functions the dynamics need."""
    arrays = {"FI": np.array(B.FI, dtype=np.int64).reshape(-1, 3),
              "FF": function_rows(B.FI, B.FF),
              "tabs": np.ascontiguousarray(np.array(B.tabs))}
    for k, (dtype, width) in _ROWS.items():
        a = np.array(rows[k], dtype=dtype)
        arrays[k] = a if width is None else a.reshape(-1, width)
    arrays["n_dyn"] = n_dyn
    return arrays


def _linkage_part(scene, B, h, i, part, tables, tlink):
    """Part i of several bodies without a crank: its coordinate (the rotation of a link
    pinned to the frame), its rigid-motion function of θ, and the maker of its functions,
    tabulated from the part's own sub-linkage driven by that link over its swing plus a
    margin (a geared crank's part: over a turn); ``h`` the tables' step in θ."""
    ang, ang1, ang2 = tables[:3]
    tbodies = set(tlink)
    lk, L = scene.linkage, scene.length_scale
    cb = next((b for b in part if b not in tbodies
               and any(p in lk.ground for p in scene.bodies[b])), None)
    if cb is None:
        raise GeometryError(f"{scene.source}: the rigid part {{{', '.join(part)}}} has no "
                            "link pinned to the frame to serve as its coordinate")
    rig = B.table(-1, 0.0, h, ang[cb], ang1[cb], ang2[cb], True,
                  _winding(ang[cb], scene.cycle_revolutions))
    turns = cb in [c.link for c in lk.cranks]   # a geared crank: its part repeats every turn
    lo, hi = (0.0, TWO_PI) if turns else (float(ang[cb].min()), float(ang[cb].max()))
    margin = 0.0 if turns else max(0.25 * (hi - lo), 0.05)
    plinks = {b: lk.links[b] for b in part if b not in tbodies}
    ppts = {p for pts in plinks.values() for p in pts}
    piv = next(p for p in plinks[cb] if p in lk.ground)
    sub = Linkage(f"{scene.name}:{cb}", {p: lk.pose[p] for p in ppts | {
                      p for x in lk.sliders if x.link in plinks for p in x.line}},
                  tuple(p for p in lk.ground if p in ppts), plinks,
                  (Crank(cb, piv, 1.0),), scene.source,
                  sliders=tuple(x for x in lk.sliders if x.link in plinks))
    sidx = sub.link_index()
    for _ in range(6):
        grid = np.linspace(lo - margin, hi + margin, B.n + 1)
        try:
            sub_states = sub.solve(grid)
            break
        except GeometryError:
            margin *= 0.5
    else:
        raise GeometryError(f"{scene.source}: the rigid part {{{', '.join(part)}}} cannot "
                            f"be tabulated against the rotation of {cb!r}")
    g0, sh = float(grid[0]), (grid[-1] - grid[0]) / B.n

    def make(kind, name):
        per = TWO_PI if turns else None
        if kind == "angle":
            name = tlink.get(name, name)
            if name == cb:
                return B.line(i, 0.0, 1.0)
            j = sidx[name]
            a = np.unwrap([s.q[3 * j + 2] for s in sub_states])
            return B.table(i, g0, sh, a, [s.qdot[3 * j + 2] for s in sub_states],
                           [s.qddot[3 * j + 2] for s in sub_states], turns,
                           _winding(a) if turns else 0.0, per)
        k = "xy".index(kind)
        return B.table(i, g0, sh, [s.points[name][k] * L for s in sub_states],
                       [s.velocities[name][k] * L for s in sub_states],
                       [s.accelerations[name][k] * L for s in sub_states], turns, 0.0, per)
    return cb, rig, make


def _elements(scene, prig, point_fns, angle_fn, part_of):
    """The elastic elements' kernel rows: EI = [type, law, fa, fa2, fb, fb2, part_a, part_b],
    EF = [k, d, clearance, l0, xa, ya, xb, yb, ux, uy] (see the kernel module), names."""
    lk, L = scene.linkage, scene.length_scale
    EI, EF, enames = [], [], []

    def law_of(el):
        return 0 if getattr(el, "clearance", 0.0) == 0 else _LAWS[el.clearance_law]

    def add(row, fl, name):
        EI.append(row)
        EF.append(fl)
        enames.append(name)

    for e in scene.elastic:
        a, b = lk.links[e.link]
        row, fl = [1, law_of(e), -1, -1, -1, -1, 0, 0], [e.stiffness, e.damping,
                                                         e.clearance, 0.0, 0, 0, 0, 0, 0, 0]
        for side, p in ((0, a), (1, b)):
            pf = point_fns(p)
            if pf is None:
                fl[4 + 2 * side:6 + 2 * side] = (lk.pose[p] * L).tolist()
            else:
                row[2 + 2 * side], row[3 + 2 * side], row[6 + side] = pf
        fl[3] = float(np.hypot(*(lk.pose[b] - lk.pose[a]))) * L
        add(row, fl, e.name)
    for t in scene.torsions:
        add([0, law_of(t), angle_fn(t.link), -1, angle_fn(t.body), -1, part_of[t.link],
             part_of[t.body]], [t.stiffness, t.damping, t.clearance, 0, 0, 0, 0, 0, 0, 0], t.name)
    for ld in scene.loads:
        fx, fy, i = point_fns(ld.point)
        fl = [ld.stiffness, ld.damping, 0, 0, 0, 0, 0, 0, 0, 0]
        if ld.anchor is not None:           # a spring to a frame point x: EF[4:6]
            fl[4:6] = (lk.pose[ld.anchor] * L).tolist()
        else:                               # along a fixed unit direction u: EF[8:10]
            u = np.array(ld.direction, float)
            fl[8:10] = (u / np.hypot(*u)).tolist()
        add([2 if ld.anchor is None else 3, 0, prig[i], -1, fx, fy, i, i], fl, ld.name)
    if getattr(lk, "contact", ""):        # a cam contact that can open (scene/cam.py)
        from .cam import open_contact_rows

        open_contact_rows(scene, EI, EF, enames, point_fns)
    return EI, EF, enames


def _moments(scene, B, part_of, angle_fn, crank0, cam):
    """The crank-angle moments' kernel rows: MOI = [window fn, body fn],
    MOF = [amplitude, alpha, sigma, centre], names, and each one's centre [rad]."""
    centres = {m.name: moment_centre(scene, m) for m in scene.moments}
    # the window is in shaft angle: with a cam the crank (its follower) swings, so θ is the
    # drive part's coordinate itself
    MOI = [[B.line(part_of[crank0], 0.0, 1.0) if cam else angle_fn(crank0), angle_fn(m.body)]
           for m in scene.moments]
    MOF = [[m.amplitude, m.window, m.sigma, centres[m.name]] for m in scene.moments]
    return MOI, MOF, [m.name for m in scene.moments], centres


_CACHE: dict = {}


def _signature(scene: Scene, *extra):
    lk = scene.linkage
    return (tuple((p, float(x[0]), float(x[1])) for p, x in lk.pose.items()), tuple(lk.ground),
            tuple((k, tuple(v)) for k, v in lk.links.items()),
            tuple((c.link, c.pivot, float(c.omega)) for c in lk.cranks), scene.length_scale,
            lk.sliders, getattr(lk, "key", ()), extra)


def _memo(key, make):
    if key not in _CACHE:
        if len(_CACHE) > 32:
            _CACHE.clear()
        _CACHE[key] = make()
    return _CACHE[key]


def rigid_tables(scene: Scene, N: int):
    """Rotations, point positions and their first and second derivatives with respect to
    the crank angle over the mechanism's cycle (N per revolution, plus one), memoised."""
    def make():
        lk = scene.linkage
        L = scene.length_scale
        w1 = lk.cranks[0].omega
        th = np.linspace(0.0, scene.cycle, N * scene.cycle_revolutions + 1)
        try:
            states = lk.solve(th)
        except GeometryError as exc:
            raise GeometryError(f"{scene.source}: the rigid mechanism cannot turn a full "
                                f"revolution, so the scene cannot be simulated over the cycle "
                                f"({exc})") from None
        idx = lk.link_index()
        ang = {l: np.unwrap([s.q[3 * i + 2] for s in states]) for l, i in idx.items()}
        ang1 = {l: np.array([s.qdot[3 * i + 2] for s in states]) / w1 for l, i in idx.items()}
        ang2 = {l: np.array([s.qddot[3 * i + 2] for s in states]) / w1 ** 2
                for l, i in idx.items()}
        pos = {p: np.array([s.points[p] for s in states]) * L for p in lk.pose}
        vel = {p: np.array([s.velocities[p] for s in states]) * L / w1 for p in lk.pose}
        acc = {p: np.array([s.accelerations[p] for s in states]) * L / w1 ** 2
               for p in lk.pose}
        return tuple(tuple(d.items()) for d in (ang, ang1, ang2, pos, vel, acc))
    return _memo(_signature(scene, "rigid", N), make)


def dead_centre(scene: Scene, kind: str = "front") -> float:
    """Crank rotation from the pose [rad, in [0, 2π)] where the crank and its coupler are
    extended (``"front"``) or folded (``"back"``); memoised per linkage.

    Parameters
    ----------
    scene : Scene
        The scene whose first crank is meant.
    kind : {"front", "back"}
        Extended or folded.

    Returns
    -------
    float

    Raises
    ------
    GeometryError
        The crank has no coupler (no other link at its moving point) or never
        lines up with it.
    """
    return _memo(_signature(scene, "dead", kind), lambda: _dead_centre(scene, kind))


def moment_centre(scene: Scene, moment) -> float:
    """The centre [rad] of a crank-angle moment's window: its rotation, or the dead centre
    it names (``"front-dead-centre"``, ``"back-dead-centre"``)."""
    c = moment.centre
    return dead_centre(scene, "front" if c.startswith("front") else "back") \
        if isinstance(c, str) else c


def _dead_centre(scene: Scene, kind: str) -> float:
    """Crank rotation from the pose [rad, in [0, 2π)] where the crank and its coupler are
    extended (``"front"``) or folded (``"back"``).

    Raises
    ------
    GeometryError
        The crank has no coupler (no other link at its moving point) or never
        lines up with it.
    """
    from scipy.optimize import brentq

    lk = scene.linkage
    crank = lk.cranks[0].link
    pts = lk.links[crank]
    piv = next(p for p in pts if p in lk.ground)
    tip = next((p for p in pts if p not in lk.ground), None)
    coupler = next((l for l, ps in lk.links.items() if l != crank and tip in ps), None)
    if coupler is None:
        raise GeometryError(f"{scene.source}: a dead centre needs a coupler at the crank's "
                            f"moving point; crank {crank!r} has none")
    far = next(p for p in lk.links[coupler] if p != tip)

    def cd(s):
        a = s.points[tip] - s.points[piv]
        b = s.points[far] - s.points[tip]
        return float(a[0] * b[1] - a[1] * b[0]), float(a @ b)

    th = np.linspace(0.0, TWO_PI, 361)
    vals = [cd(s) for s in lk.solve(th)]
    want = 1.0 if kind == "front" else -1.0
    for k in range(360):
        (c0, d0), (c1, _) = vals[k], vals[k + 1]
        if c0 == 0 and d0 * want > 0:
            return float(th[k])
        if c0 * c1 < 0 and d0 * want > 0:
            return float(brentq(lambda t: cd(lk.solve(t))[0], th[k], th[k + 1], xtol=1e-14))
    raise GeometryError(f"{scene.source}: the crank {crank!r} and coupler {coupler!r} never "
                        f"line up {'extended' if kind == 'front' else 'folded'}")
