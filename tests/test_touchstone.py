"""The Touchstone reader: it never runs code, agrees with scikit-rf, refuses bad files clearly."""

import math
import os
import pickle
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import cli
from mechcirc.errors import NetlistError
from mechcirc.interop.touchstone import read_touchstone_one_port
from reference.inputs import STB

REPO = Path(__file__).resolve().parents[1]


def run(argv, capsys):
    try:
        status = cli.main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


class _Payload:
    """Unpickling this object creates the file named in ``marker``."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (Path(self.marker),))


@pytest.mark.parametrize("suffix", [".s1p", ".ntwk", ".p", ".s2p"])
def test_a_pickle_named_as_measured_data_runs_nothing(tmp_path, capsys, suffix):
    marker = tmp_path / "PWNED"
    evil = tmp_path / f"evil{suffix}"
    evil.write_bytes(pickle.dumps(_Payload(str(marker))))
    # Sanity: the payload does run when unpickled, so the test below could fail.
    pickle.loads(evil.read_bytes())
    assert marker.exists()
    marker.unlink()

    status, _, err = run(["compare", STB, evil], capsys)
    assert status == 2 and str(evil) in err
    assert not marker.exists()
    from mechcirc.interop.skrf import compare, read_mobility

    for call in (lambda: read_mobility(evil), lambda: compare(mechcirc.load(STB), evil)):
        with pytest.raises(NetlistError):
            call()
    assert not marker.exists()


@pytest.mark.parametrize("param,fmt", [("S", "RI"), ("S", "MA"), ("S", "DB"), ("Z", "RI"),
                                       ("Z", "MA"), ("Y", "DB"), ("Y", "RI")])
def test_reader_agrees_with_scikit_rf(tmp_path, param, fmt):
    skrf = pytest.importorskip("skrf")
    rng = np.random.default_rng(7)
    omega = np.sort(rng.uniform(1, 1e4, 40))
    K = (rng.uniform(-1, 1, 40) + 1j * rng.uniform(-1, 1, 40)) * 10.0 ** rng.uniform(-6, 0, 40)
    K.real = np.abs(K.real)             # passive: Re K ≥ 0
    freq = skrf.Frequency.from_f(omega / (2 * math.pi), unit="hz")
    net = skrf.Network.from_z(K.reshape(-1, 1, 1), frequency=freq, z0=2.0 ** -10)
    net.write_touchstone(str(tmp_path / "m"), form=fmt.lower(), r_ref=2.0 ** -10)
    path = tmp_path / "m.s1p"
    text = path.read_text()
    if param != "S":
        # scikit-rf writes S; rewrite the same data as Z or Y by hand.
        lines = [ln for ln in text.splitlines() if ln and not ln.startswith(("!", "#"))]
        R = 2.0 ** -10
        out = [f"# Hz {param} {fmt} R {R!r}"]
        for ln, k in zip(lines, K):
            f = ln.split()[0]
            v = k / R if param == "Z" else R / k
            if fmt == "RI":
                a, b = v.real, v.imag
            elif fmt == "MA":
                a, b = abs(v), math.degrees(np.angle(v))
            else:
                a, b = 20 * math.log10(abs(v)), math.degrees(np.angle(v))
            out.append(f"{f} {float(a)!r} {float(b)!r}")
        path.write_text("\n".join(out) + "\n")
    got_omega, got_K, name = read_touchstone_one_port(path)
    np.testing.assert_allclose(got_omega, omega, rtol=1e-12)
    if param != "Y":
        # scikit-rf 2.x reads version-1 Y data as Y = y·R (not y/R), so a
        # dimensionless normalised admittance y = Y·R comes back off by R²:
        # Y is checked against the data only.
        ref = skrf.Network(str(path)).z[:, 0, 0]    # a file we wrote: safe to hand to skrf
        np.testing.assert_allclose(got_K, ref, rtol=1e-9, atol=0)
    np.testing.assert_allclose(got_K, K, rtol=1e-6)     # MA/DB written with ~10 digits
    assert name == "m"


@pytest.mark.parametrize("body,message", [
    ("# Hz Z RI R 1\n! only comments\n", "has no data lines"),
    ("# Hz Z RI R -50\n1 1 0\n", "must be finite and positive"),
    ("# Hz Z RI R 0\n1 1 0\n", "must be finite and positive"),
    ("# Hz Z RI R 1\n-1 1 0\n", "is negative"),
    ("# Hz Z RI R 1\nnan 1 0\n", "not finite"),
    ("# Hz Z RI R 1\n2 1 0\n1 1 0\n", "does not increase"),
    ("# Hz Z RI R 1\n1 1 0 4\n", "has 4 numbers"),
    ("# Hz Z RI R 1\n1 x 0\n", "'x' is not a number"),
    ("# Hz G RI R 1\n1 1 0\n", "G parameters are not supported"),
    ("# Hz S RI R 1\n1 1 0\n", "infinite mobility"),
    ("# Hz Q RI R 1\n1 1 0\n", "unknown option 'Q'"),
    ("[Version] 2.0\n", "Touchstone 2.0"),
])
def test_bad_files_are_located_user_errors(tmp_path, capsys, body, message):
    path = tmp_path / "bad.s1p"
    path.write_text(body)
    with pytest.raises(NetlistError, match=message):
        read_touchstone_one_port(path)
    status, _, err = run(["compare", STB, path], capsys)
    assert status == 2 and message.split("'")[0] in err and "Traceback" not in err


def test_errors_carry_line_and_column(tmp_path):
    path = tmp_path / "bad.s1p"
    path.write_text("! header\n# Hz Z RI R 1\n1 1 0\n   2 y 0\n")
    with pytest.raises(NetlistError) as info:
        read_touchstone_one_port(path)
    assert (info.value.line, info.value.col) == (4, 6)


def test_two_port_extension_is_refused(tmp_path):
    path = tmp_path / "x.s2p"
    path.write_text("# Hz Z RI R 1\n1 1 0 0 0 0 0 1 0\n")
    with pytest.raises(NetlistError, match="2 ports"):
        read_touchstone_one_port(path)


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_devices_are_refused_before_reading():
    with pytest.raises(NetlistError, match="not a regular file"):
        read_touchstone_one_port("/dev/zero")


def test_file_larger_than_the_bound_is_refused_unread(tmp_path, monkeypatch):
    from mechcirc import sources

    monkeypatch.setattr(sources, "MAX_INPUT_BYTES", 100)
    path = tmp_path / "big.s1p"
    path.write_text("# Hz Z RI R 1\n" + "1 1 0\n" * 40)
    with pytest.raises(NetlistError, match="more than the limit of 100 bytes"):
        read_touchstone_one_port(path)
