"""Kineto-static analysis of the beat-up four-bar: bearing forces, input torque, frame shaking.

Patent CN104178888 eq. (7).  The four-bar of :mod:`.fourbar`
(A at the origin, D at (d, 0); crank AB, coupler BC, rocker CD carrying the
sley and reed) turns at a constant crank speed ω > 0.  Each moving link has a
mass, a centre of mass given in the link's own frame and a moment of inertia
about that centre; the cloth pushes on the reed with a force F(θ).

Units are SI: lengths [m] (build the :class:`FourBar` in metres), masses
[kg], inertias [kg·m²], forces [N], moments [N·m], ω [rad/s].

Link frames: the crank's frame has its origin at A and x along A→B; the
coupler's at B with x along B→C; the rocker's at D with x along D→C; y is
90° counter-clockwise from x in each.

Newton–Euler for each link, with ``F_A`` and ``F_D`` the forces of the frame
on the crank and on the rocker, ``F_B`` the force of the crank on the
coupler, ``F_C`` the force of the coupler on the rocker, ``T`` the driving
torque on the crank and ``g`` gravity::

    crank:   F_A − F_B + m2 g = m2 a_G2,  (A − G2)×F_A − (B − G2)×F_B + T = J2 α2 (= 0)
    coupler: F_B − F_C + m3 g = m3 a_G3,  (B − G3)×F_B − (C − G3)×F_C = J3 α3
    rocker:  F_C + F_D + F + m4 g = m4 a_G4,  (C − G4)×F_C + (D − G4)×F_D + (P − G4)×F = J4 α4

nine linear equations in nine unknowns per crank angle, solved batched.
The linkage pushes on the frame with −F_A at A, −F_D at D and the reaction
−T of the drive, so

* shaking force ``S = −(F_A + F_D)`` (patent Figs. 5–6);
* shaking moments about A and D (our reading of eq. (7), which the OCR
  leaves with ambiguous signs)::

      T_a = AD × (−F_D) − T = F_Dx·AD_y − F_Dy·AD_x − T
      T_d = DA × (−F_A) − T = AD_x·F_Ay − AD_y·F_Ax − T   (DA = −AD)

  with ``AD = D − A``; the first is eq. (7) letter for letter, the second
  has the opposite sign of the cross-product term from the print, as the
  moment transfer T_a − T_d = AD × S requires (the print's sign would hold
  for F_a taken as the force on the frame while F_d is the force on the link).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import GeometryError
from ..sources import data_frame, positive_number, summary_repr
from .fourbar import FourBar
from .linkage_solver import rigid_points, to_complex, to_xy

__all__ = ["LinkMass", "FrameLoading", "frame_loading", "link_kinematics", "beat_up_force"]


@dataclass(frozen=True)
class LinkMass:
    """Inertia of one moving link.

    Parameters
    ----------
    mass : float
        Mass [kg], ≥ 0.
    com : (float, float)
        Centre of mass in the link's frame (see the module docstring) [m].
    inertia : float
        Moment of inertia about the centre of mass [kg·m²], ≥ 0.
    """

    mass: float = 0.0
    com: tuple[float, float] = (0.0, 0.0)
    inertia: float = 0.0

    def __post_init__(self):
        for what, value, unit in (("mass", self.mass, "kg"), ("inertia", self.inertia, "kg·m²")):
            if not (math.isfinite(value) and value >= 0):
                raise GeometryError(f"link {what} must be finite and ≥ 0 {unit}, got {value}")
        com = tuple(float(x) for x in self.com)
        if len(com) != 2 or not all(math.isfinite(x) for x in com):
            raise GeometryError(f"link centre of mass must be two finite numbers [m], got {self.com}")
        object.__setattr__(self, "com", com)


@dataclass(frozen=True)
class FrameLoading:
    """Result of :func:`frame_loading`; arrays along the crank angle (first axis).

    Attributes
    ----------
    theta : ndarray, shape (n,)
        Crank angle [rad].
    omega : float
        Crank speed [rad/s].
    F_A, F_B, F_C, F_D : ndarray, shape (n, 2)
        Frame on crank at A, crank on coupler at B, coupler on rocker at C,
        frame on rocker at D [N].
    torque : ndarray, shape (n,)
        Driving torque T on the crank [N·m].
    reed_force : ndarray, shape (n, 2)
        The reed force in world axes [N].
    shaking_force : ndarray, shape (n, 2)
        S = −(F_A + F_D), the force of the linkage on the frame [N].
    T_a, T_d : ndarray, shape (n,)
        Shaking moments on the frame about A and about D [N·m].
    """

    __repr__ = summary_repr

    theta: NDArray[np.float64]
    omega: float
    F_A: NDArray[np.float64]
    F_B: NDArray[np.float64]
    F_C: NDArray[np.float64]
    F_D: NDArray[np.float64]
    torque: NDArray[np.float64]
    reed_force: NDArray[np.float64]
    shaking_force: NDArray[np.float64]
    T_a: NDArray[np.float64]
    T_d: NDArray[np.float64]

    @property
    def shaking_force_magnitude(self) -> NDArray[np.float64]:
        """|S| [N]."""
        return np.hypot(self.shaking_force[:, 0], self.shaking_force[:, 1])

    @property
    def T_d_printed(self) -> NDArray[np.float64]:
        """T_d as eq. (7) is printed, F_ax·AD_y − F_ay·AD_x − T [N·m] (for comparison only).

        The cross term has the opposite sign of :attr:`T_d`, so this equals
        −T_d − 2T; it breaks the moment transfer T_a − T_d = AD × S.
        """
        return -self.T_d - 2.0 * self.torque

    #: How T_a and T_d are defined, for reports.
    CONVENTION = ("T_a = F_Dx·AD_y − F_Dy·AD_x − T (eq. 7 as printed); "
                  "T_d = AD_x·F_Ay − AD_y·F_Ax − T (eq. 7's cross term with the sign the "
                  "moment transfer T_a − T_d = AD × S requires; the printed T_d = "
                  "F_Ax·AD_y − F_Ay·AD_x − T differs from it by 2·(AD × F_A)); F_A, F_D are "
                  "the forces of the frame on the crank and on the rocker, T the driving "
                  "torque, S = −(F_A + F_D) the shaking force on the frame")

    def columns(self) -> dict:
        """Ordered columns (name with unit → array) for tables and CSV."""
        S = self.shaking_force
        cols = {"theta_deg": np.degrees(self.theta)}
        for name, F in (("F_A", self.F_A), ("F_B", self.F_B), ("F_C", self.F_C),
                        ("F_D", self.F_D)):
            cols[f"{name}x_N"], cols[f"{name}y_N"] = F[:, 0], F[:, 1]
            cols[f"{name}_abs_N"] = np.hypot(F[:, 0], F[:, 1])
        return cols | {"S_x_N": S[:, 0], "S_y_N": S[:, 1], "S_abs_N": self.shaking_force_magnitude,
                       "T_Nm": self.torque, "T_a_Nm": self.T_a, "T_d_Nm": self.T_d,
                       "T_d_printed_Nm": self.T_d_printed}

    def to_dataframe(self):
        """:meth:`columns` as a ``pandas.DataFrame``, a row per crank angle; ``attrs["units"]``
        the unit of each column, as its name ends: deg, N, N·m."""
        cols = self.columns()
        return data_frame(cols, {c: {"deg": "deg", "N": "N", "Nm": "N·m"}[c.rpartition("_")[2]]
                                 for c in cols})

    def summary(self) -> dict:
        """Extremes (value and crank angle in degrees) of the main quantities, plain data."""
        deg = np.degrees(self.theta)

        def ext(x):
            i, j = int(np.argmin(x)), int(np.argmax(x))
            return {"min": float(x[i]), "theta_at_min_deg": float(deg[i]),
                    "max": float(x[j]), "theta_at_max_deg": float(deg[j])}

        cols = self.columns()
        out = {name: ext(cols[name]) for name in
               ("S_abs_N", "F_A_abs_N", "F_D_abs_N", "T_Nm", "T_a_Nm", "T_d_Nm")}
        out["T_d_printed_minus_T_d_max_abs_Nm"] = float(np.max(np.abs(self.T_d_printed - self.T_d)))
        return out


def _cross(r, f):
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


def link_kinematics(fourbar: FourBar, theta: ArrayLike, omega: float, crank: LinkMass,
                    coupler: LinkMass, rocker: LinkMass, reed_point=(0.0, 0.0)) -> dict:
    """Positions, velocities and accelerations of joints, centres of mass and the reed point.

    Returns a dict of (n, 2) arrays ``A B C D G2 G3 G4 P`` [m], ``vG2 vG3 vG4
    vP`` [m/s], ``aG2 aG3 aG4`` [m/s²], and (n,) arrays ``phi2 phi3 phi4``
    [rad], ``w2 w3 w4`` [rad/s], ``al2 al3 al4`` [rad/s²].

    Parameters
    ----------
    fourbar : FourBar
        The linkage.
    theta : array_like
        Crank angles [rad], shape (n,).
    omega : float
        Crank speed [rad/s].
    crank, coupler, rocker : LinkMass
        Where each link's centre of mass lies.
    reed_point : tuple of float
        The reed point in the rocker's frame [m].

    Returns
    -------
    dict[str, ndarray]
    """
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    st = fourbar.evaluate(theta)
    a, b, d = fourbar.crank, fourbar.coupler, fourbar.frame
    n = theta.size
    w2, w3, w4 = np.full(n, float(omega)), st.mu3 * omega, st.mu * omega
    al2, al3, al4 = np.zeros(n), st.nu3 * omega ** 2, st.nu * omega ** 2
    crank_turn = (theta, w2, al2)                     # each link's angle, rate, acceleration
    coupler_turn, rocker_turn = (st.phi3, w3, al3), (st.phi4, w4, al4)

    def point(origin, turn, s):
        return rigid_points(origin, turn[1:], np.exp(1j * turn[0]) * s)

    B = point((0.0, 0.0, 0.0), crank_turn, a)
    G2, G3, G4, P = (point(origin, turn, complex(*uv)) for origin, turn, uv in (
        ((0.0, 0.0, 0.0), crank_turn, crank.com), (B, coupler_turn, coupler.com),
        ((d, 0.0, 0.0), rocker_turn, rocker.com), ((d, 0.0, 0.0), rocker_turn, reed_point)))
    return dict(A=np.zeros((n, 2)), B=to_xy(B[0]), C=to_xy(point(B, coupler_turn, b)[0]),
                D=np.tile([d, 0.0], (n, 1)), G2=to_xy(G2[0]), G3=to_xy(G3[0]), G4=to_xy(G4[0]),
                P=to_xy(P[0]), vG2=to_xy(G2[1]), vG3=to_xy(G3[1]), vG4=to_xy(G4[1]), vP=to_xy(P[1]),
                aG2=to_xy(G2[2]), aG3=to_xy(G3[2]), aG4=to_xy(G4[2]), phi2=theta, phi3=st.phi3,
                phi4=st.phi4, w2=w2, w3=w3, w4=w4, al2=al2, al3=al3, al4=al4)


def frame_loading(fourbar: FourBar, theta: ArrayLike, omega: float, *,
                  crank: LinkMass = LinkMass(), coupler: LinkMass = LinkMass(),
                  rocker: LinkMass = LinkMass(),
                  reed_force: Callable[[NDArray[np.float64]], ArrayLike] | None = None,
                  reed_point: tuple[float, float] = (0.0, 0.0),
                  gravity: tuple[float, float] = (0.0, 0.0)) -> FrameLoading:
    """Bearing forces, driving torque and frame shaking of a four-bar at constant crank speed.

    Parameters
    ----------
    fourbar : FourBar
        The linkage, lengths in metres.
    theta : array_like, shape (n,)
        Crank angles [rad].
    omega : float
        Crank speed [rad/s], constant.
    crank, coupler, rocker : LinkMass
        Mass, centre of mass (link frame) and inertia of each moving link; the
        rocker includes the sley and reed.
    reed_force : callable, optional
        ``reed_force(theta)`` → array (n, 2): the cloth's force on the reed
        [N] in the *rocker's* frame (x along D→C), applied at ``reed_point``.
    reed_point : (float, float)
        Where the reed force acts, in the rocker's frame [m].
    gravity : (float, float)
        Gravitational acceleration in world axes [m/s²]; default none.

    Returns
    -------
    FrameLoading

    Raises
    ------
    GeometryError
        The linkage locks at some θ, ω is not finite and > 0, or the reed
        force has the wrong shape.

    Notes
    -----
    One batched 9×9 linear solve per angle; the matrix is singular only where
    the coupler and rocker are in line (γ = 0), which a crank-rocker never reaches.
    """
    if not (positive_number(omega)):
        raise GeometryError(f"crank speed ω must be finite and > 0 rad/s, got {omega}")
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    k = link_kinematics(fourbar, theta, omega, crank, coupler, rocker, reed_point)
    g = np.asarray(gravity, dtype=float)
    F = _reed_in_world(reed_force, theta, k["phi4"])
    M, rhs = _equilibrium(k, crank, coupler, rocker, F, g)
    x = np.linalg.solve(M, rhs[..., None])[..., 0]
    F_A, F_B, F_C, F_D, T = x[:, 0:2], x[:, 2:4], x[:, 4:6], x[:, 6:8], x[:, 8]
    AD = k["D"] - k["A"]
    T_a = _cross(AD, -F_D) - T
    T_d = _cross(-AD, -F_A) - T
    return FrameLoading(theta, float(omega), F_A, F_B, F_C, F_D, T, F,
                        -(F_A + F_D), T_a, T_d)


def _reed_in_world(reed_force, theta, phi4):
    """The reed force (n, 2) [N] in world axes: ``reed_force(theta)``, given in the
    rocker's frame (at rocker angle ``phi4``), turned; zero without one."""
    n = theta.size
    if reed_force is None:
        F_local = np.zeros((n, 2))
    else:
        F_local = np.asarray(reed_force(theta), dtype=float)
        if F_local.shape != (n, 2):
            raise GeometryError(f"reed_force(theta) must return an array of shape ({n}, 2) "
                                f"[N, rocker frame], got {F_local.shape}")
    return to_xy(np.exp(1j * phi4) * to_complex(F_local))     # turned from the rocker's frame by φ4


def _equilibrium(k, crank, coupler, rocker, F, g):
    """The 9×9 d'Alembert equilibrium of the three links per angle: (M, rhs), with
    unknowns [FAx, FAy, FBx, FBy, FCx, FCy, FDx, FDy, T] (k: :func:`link_kinematics`)."""
    n = len(F)
    M, rhs = np.zeros((n, 9, 9)), np.zeros((n, 9))

    # per link: rows r, r + 1 its force balance, r + 2 its moments about its centre of
    # mass G; its two joint forces (columns c, c + 1) act on it with the sign given
    for r, link, G, joints in ((0, crank, "G2", ((0, 1, "A"), (2, -1, "B"))),
                               (3, coupler, "G3", ((2, 1, "B"), (4, -1, "C"))),
                               (6, rocker, "G4", ((4, 1, "C"), (6, 1, "D")))):
        for c, sign, P in joints:
            M[:, r, c] = sign
            M[:, r + 1, c + 1] = sign
            arm = sign * (k[P] - k[G])          # arm × F for F = (x[c], x[c+1]): (−arm_y, arm_x)
            M[:, r + 2, c] += -arm[:, 1]
            M[:, r + 2, c + 1] += arm[:, 0]
        rhs[:, r:r + 2] = link.mass * (k["a" + G] - g)
        rhs[:, r + 2] = link.inertia * k["al" + G[1]]
    M[:, 2, 8] = 1                      # the driving torque on the crank
    rhs[:, 6:8] -= F                    # the reed force on the rocker, at P
    rhs[:, 8] -= _cross(k["P"] - k["G4"], F)
    return M, rhs


def beat_up_force(fourbar: FourBar, peak: tuple[float, float], window_deg: float = 40.0,
                  centre_deg: float | None = None) -> Callable[[NDArray[np.float64]], NDArray]:
    """A reed force for :func:`frame_loading`: a half sine of ``peak`` over a crank window.

    Parameters
    ----------
    fourbar : FourBar
        A crank-rocker (the window is centred on its front dead centre by default).
    peak : (float, float)
        The force at the centre of the window, in the rocker's frame [N].
    window_deg : float
        Width of the window [deg of crank], in (0, 360].
    centre_deg : float, optional
        Crank angle of the window's centre [deg]; default the front dead centre.

    Returns
    -------
    callable
        ``f(theta)`` → (n, 2): ``peak · cos(π x / window)`` for |x| < window/2,
        x the crank angle from the centre, else 0.
    """
    px, py = (float(v) for v in peak)
    if not (math.isfinite(px) and math.isfinite(py)):
        raise GeometryError(f"reed force peak must be two finite numbers [N], got {peak}")
    if not (math.isfinite(window_deg) and 0 < window_deg <= 360):
        raise GeometryError(f"beat-up window must be in (0, 360] degrees, got {window_deg}")
    centre = fourbar.dead_centres()[0].theta if centre_deg is None else math.radians(centre_deg)
    half = math.radians(window_deg) / 2

    def force(theta):
        x = (np.asarray(theta, dtype=float) - centre + math.pi) % (2 * math.pi) - math.pi
        mag = np.where(np.abs(x) < half, np.cos(x / (2 * half) * math.pi), 0.0)
        return np.stack([px * mag, py * mag], axis=-1)

    return force
