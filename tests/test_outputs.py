"""Output safety (issue 8, §4): outputs appear whole or not at all.

Every file a command writes goes to a temporary file beside the target and is
renamed into place.  A sweep killed with SIGINT or SIGTERM in the middle of
writing its CSV must leave the old file (or none) and no temporary file.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mechcirc.cli import main
from mechcirc.outputs import OutputSet, atomic_open, atomic_path
from bounds import SUBPROCESS_TIMEOUT

ROOT = Path(__file__).resolve().parents[1]
NETLIST = ROOT / "netlists" / "stb_heald.mcir"


def _temporaries(folder: Path, name: str) -> list[Path]:
    return sorted(folder.glob(f".{name}.*"))


def _sweep_then_kill(tmp_path: Path, sig: int, old: str | None):
    """Start a long sweep writing out.csv, send ``sig`` while the CSV is being written."""
    target = tmp_path / "out.csv"
    if old is not None:
        target.write_text(old)
    proc = subprocess.Popen(
        [sys.executable, "-m", "mechcirc", "sweep", str(NETLIST), "--omega-min", "1",
         "--omega-max", "1e4", "--points", "1000000", "-o", str(target)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        # Wait until the temporary CSV has data in it: the kill lands mid-write.  No
        # clock: however slow the machine, the sweep either starts writing or ends.
        while True:
            tmps = _temporaries(tmp_path, "out.csv")
            if tmps and tmps[0].stat().st_size > 100_000:
                break
            assert proc.poll() is None, "the sweep ended before it could be interrupted"
            time.sleep(0.02)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=SUBPROCESS_TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return proc.returncode, err, target


@pytest.mark.parametrize("sig, status, word", [(signal.SIGINT, 130, "interrupted"),
                                               (signal.SIGTERM, 143, "terminated")])
def test_killed_sweep_keeps_the_old_file_and_leaves_no_temporary(tmp_path, sig, status, word):
    code, err, target = _sweep_then_kill(tmp_path, sig, old="old contents\n")
    assert code == status, err
    assert word in err
    assert "Traceback" not in err
    assert target.read_text() == "old contents\n"
    assert _temporaries(tmp_path, "out.csv") == []


def test_killed_sweep_without_old_file_leaves_nothing(tmp_path):
    code, err, target = _sweep_then_kill(tmp_path, signal.SIGTERM, old=None)
    assert code == 143, err
    assert not target.exists()
    assert list(tmp_path.iterdir()) == []


def test_exception_mid_write_keeps_old_file(tmp_path):
    target = tmp_path / "a.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_open(target) as fh:
            fh.write("half")
            raise RuntimeError("disk on fire")
    assert target.read_text() == "old"
    assert _temporaries(tmp_path, "a.txt") == []


def test_output_set_is_all_or_nothing(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.png"
    a.write_text("old a")
    with pytest.raises(KeyboardInterrupt):
        with OutputSet() as out:
            out.path(a).write_text("new a")
            out.path(b).write_text("new b")
            raise KeyboardInterrupt
    assert a.read_text() == "old a" and not b.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv"]
    with OutputSet() as out:
        out.path(a).write_text("new a")
        out.path(b).write_text("new b")
    assert a.read_text() == "new a" and b.read_text() == "new b"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "b.png"]


def test_atomic_path_keeps_suffix_and_mode(tmp_path):
    target = tmp_path / "fig.svg"
    with atomic_path(target) as tmp:
        assert tmp.suffix == ".svg" and tmp.parent == tmp_path
        tmp.write_text("<svg/>")
    umask = os.umask(0)
    os.umask(umask)
    assert (target.stat().st_mode & 0o777) == (0o666 & ~umask)


# Each command that writes files, with the options that name them.  A failure
# after the outputs are named (here: a bad option value found late, or an
# unreadable input) must leave the old files untouched.
WRITERS = [
    (["sweep", str(NETLIST), "--omega-min", "1", "--omega-max", "1e3", "--points", "20",
      "-o", "{d}/k.csv", "--plot", "{d}/k.png"], ["k.csv", "k.png"]),
    (["fourbar", "--crank", "29", "--coupler", "37", "--rocker", "188", "--frame", "189",
      "--plot", "{d}/f.png"], ["f.png"]),
    (["linkage", str(ROOT / "examples" / "fnf_sixbar.toml"), "--theta", "30",
      "--plot", "{d}/l.svg"], ["l.svg"]),
    (["simulate", "--variant", "3", "--revolutions", "1", "--points", "360",
      "-o", "{d}/s.csv"], ["s.csv"]),
]


@pytest.mark.parametrize("argv, names", WRITERS, ids=lambda v: v[0] if isinstance(v, list)
                         and v and isinstance(v[0], str) and not v[0].endswith(("png", "svg",
                                                                                 "csv"))
                         else None)
def test_commands_write_through_a_temporary_and_rename(tmp_path, monkeypatch, capsys, argv,
                                                        names):
    """Each written file is created by os.replace from a temporary beside it."""
    replaced = []
    real_replace = os.replace

    def spy(src, dst):
        replaced.append((Path(src), Path(dst)))
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", spy)
    argv = [a.replace("{d}", str(tmp_path)) for a in argv]
    assert main(argv) == 0, capsys.readouterr().err
    targets = {dst.name for _, dst in replaced}
    assert set(names) <= targets
    for src, dst in replaced:
        assert src.parent == dst.parent and src.name.startswith(f".{dst.name}.")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)
