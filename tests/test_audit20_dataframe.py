"""Tabular results reach a DataFrame (issue 26) as Sweep does: one row per point, each column
the result's own array bit for bit, ``attrs["units"]`` the unit of each column (on main
PeriodicResult, SpeedMap and Resonances had no to_dataframe; TransientResult keyed its
units by quantity, not by column)."""

from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc.periodic import periodic, speed_map

pytest.importorskip("pandas")
HEALD = Path(__file__).resolve().parents[1] / "netlists" / "heald_damped.mcir"


@pytest.fixture(scope="module")
def heald():
    return mechcirc.load(HEALD)


def test_periodic_result_frame(heald):
    p = periodic(heald, 600, elements=["k4", "k0"], points=72)
    df = p.to_dataframe()
    assert list(df.columns) == ["angle_deg", "Q", "x", "v", "F(k4)", "F(k0)", "dv(k4)", "dv(k0)"]
    assert len(df) == 72
    for col, arr in (("angle_deg", p.angle_deg), ("Q", p.Q), ("x", p.x), ("v", p.v),
                     ("F(k4)", p.forces["k4"]), ("dv(k0)", p.velocities["k0"])):
        np.testing.assert_array_equal(df[col], arr)
    assert df.attrs["units"] == {"angle_deg": "deg", "Q": "N", "x": "m", "v": "m/s",
                                 "F(k4)": "N", "F(k0)": "N", "dv(k4)": "m/s", "dv(k0)": "m/s"}


def test_speed_map_frame(heald):
    m = speed_map(heald, 300, 900, 7, elements="k4")
    df = m.to_dataframe()
    assert list(df.columns) == ["rpm", "peak", "harmonics", "error", "peak(k4)"]
    np.testing.assert_array_equal(df["rpm"], np.linspace(300, 900, 7))
    np.testing.assert_array_equal(df["peak(k4)"], m.element_peaks["k4"])
    np.testing.assert_array_equal(df["harmonics"], m.harmonics)
    assert df.attrs["units"] == {"rpm": "rpm", "peak": "N", "harmonics": "", "error": "1",
                                 "peak(k4)": "N"}


def test_resonances_frame():
    # m = 1 kg on k = 100 N/m: one resonance at 10 rad/s, f = 10/2π Hz, undamped
    found = mechcirc.parse("drive V a 0 velocity=1\nmass m a b 1\nspring k b 0 100\n").resonances()
    df = found.to_dataframe()
    assert list(df.columns) == ["kind", "omega", "f_hz", "omega_d", "zeta", "error"]
    assert df["kind"].tolist() == ["resonance"]
    assert df["omega"][0] == pytest.approx(10.0, rel=1e-13)
    assert df["f_hz"][0] == pytest.approx(10.0 / (2 * np.pi), rel=1e-13)
    assert df.attrs["units"]["omega"] == "rad/s" and df.attrs["units"]["f_hz"] == "Hz"
    empty = mechcirc.parse("drive V a 0 velocity=1\ndamper c a 0 1\n").resonances().to_dataframe()
    assert len(empty) == 0 and list(empty.columns) == list(df.columns)


def test_frame_loading_and_sley_frames():
    from mechcirc.kinematics import FourBar, frame_loading
    from mechcirc.sley import simulate

    fl = frame_loading(FourBar(35, 62.8, 170.1, 170.65), np.linspace(0, 6.28, 37), 20.0)
    df = fl.to_dataframe()
    assert list(df.columns) == list(fl.columns()) and len(df) == 37
    np.testing.assert_array_equal(df["T_Nm"], fl.torque)
    u = df.attrs["units"]
    assert (u["theta_deg"], u["F_Ax_N"], u["S_abs_N"], u["T_Nm"]) == ("deg", "N", "N", "N·m")
    r = simulate("one-side", 3, 1, points_per_revolution=90, error_estimate=False)
    df = r.to_dataframe()
    np.testing.assert_array_equal(df["M4"], r.M4)
    assert df.attrs["units"] == {"crank_angle_deg": "deg", "eps2P": "rad/s²", "eps4P": "rad/s²",
                                 "eps4T": "rad/s²", "M2V": "N·m", "M4": "N·m"}


def test_study_result_frame():
    from mechcirc.study import load_spec, run_study

    r = run_study(load_spec(HEALD.parents[1] / "examples" / "study_stb.toml"), workers=1)
    df = r.to_dataframe()
    assert list(df.columns) == r.columns and len(df) == r.count == 18
    assert df["eta2"].tolist() == [row["eta2"] for row in r.rows]
    u = df.attrs["units"]       # stb_heald.mcir has a velocity drive: K in m/(N·s), Q0 in N
    assert (u["K_abs_min"], u["Q0_abs_max"], u["omega_at_K_max"], u["eta1"]) == \
        ("m/(N·s)", "N", "rad/s", "")
