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
from reference.inputs import STB

ROOT = Path(__file__).resolve().parents[1]
NETLIST = STB


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
    (["cam", "--law", "cycloidal", "--rise", "120", "--return", "120", "--stroke", "20",
      "--base-radius", "40", "--roller-radius", "10", "-o", "{d}/c.csv", "--svg",
      "{d}/c.svg"], ["c.csv", "c.svg"]),
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
        # Only the command's own outputs: numba also writes its disk cache through
        # os.replace when a kernel compiles here first (which worker runs which
        # test first varies from run to run).
        if Path(dst).parent == tmp_path:
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


# ------------------------------------------------ what an output path may be (issue 23 §5)
# Links are followed (their target replaced, the link kept); FIFOs and character
# devices are written in place, never replaced by a regular file; sockets, block
# devices and folders are refused; an output never replaces one of the inputs.
SWEEP = ["sweep", str(NETLIST), "--omega-min", "1", "--omega-max", "10", "--points", "3"]
posix_only = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="FIFOs and Unix sockets")


def _csv_of_sweep(tmp_path, capsys) -> str:
    plain = tmp_path / "plain.csv"
    assert main(SWEEP + ["-o", str(plain)]) == 0
    capsys.readouterr()
    text = plain.read_text()
    plain.unlink()
    return text


@posix_only
def test_fifo_output_is_written_in_place_not_replaced(tmp_path, capsys):
    import stat

    expected = _csv_of_sweep(tmp_path, capsys)
    fifo = tmp_path / "out.csv"
    os.mkfifo(fifo)
    # A non-blocking reader: the open succeeds at once, and if the FIFO were
    # replaced the read would find end-of-file instead of hanging.
    fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
    try:
        assert main(SWEEP + ["-o", str(fifo)]) == 0, capsys.readouterr().err
        received = os.read(fd, 1 << 16).decode()
    finally:
        os.close(fd)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert received == expected
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]     # no temporary


@posix_only
def test_atomic_open_on_a_fifo_writes_through(tmp_path):
    import stat

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
    try:
        with atomic_open(fifo) as fh:          # no fsync of a pipe (EINVAL)
            fh.write("through\n")
        assert os.read(fd, 100) == b"through\n"
    finally:
        os.close(fd)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_symlink_output_writes_its_target_and_keeps_the_link(tmp_path, capsys):
    expected = _csv_of_sweep(tmp_path, capsys)
    (tmp_path / "data").mkdir()
    real = tmp_path / "data" / "real.csv"
    real.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(real)
    assert main(SWEEP + ["-o", str(link)]) == 0, capsys.readouterr().err
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert real.read_text() == expected
    assert sorted(p.name for p in (tmp_path / "data").iterdir()) == ["real.csv"]


def test_dangling_symlink_output_creates_its_target_or_names_the_missing_folder(tmp_path,
                                                                             capsys):
    expected = _csv_of_sweep(tmp_path, capsys)
    link = tmp_path / "new.csv"
    link.symlink_to(tmp_path / "made.csv")
    assert main(SWEEP + ["-o", str(link)]) == 0
    assert link.is_symlink() and (tmp_path / "made.csv").read_text() == expected
    capsys.readouterr()
    dangling = tmp_path / "dangling.csv"
    dangling.symlink_to(tmp_path / "nowhere" / "x.csv")
    assert main(SWEEP + ["-o", str(dangling)]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (f"mechcirc: error: {dangling}: a symbolic link to "
                           f"{tmp_path / 'nowhere' / 'x.csv'}, whose folder "
                           f"{tmp_path / 'nowhere'} does not exist")


@posix_only
def test_symlink_loop_and_socket_outputs_are_refused(tmp_path, capsys):
    import socket

    (tmp_path / "a.csv").symlink_to(tmp_path / "b.csv")
    (tmp_path / "b.csv").symlink_to(tmp_path / "a.csv")
    assert main(SWEEP + ["-o", str(tmp_path / "a.csv")]) == 2
    assert "cannot be written: Too many levels of symbolic links" in capsys.readouterr().err
    sock = socket.socket(socket.AF_UNIX)
    try:
        sock.bind(str(tmp_path / "s.csv"))
        assert main(SWEEP + ["-o", str(tmp_path / "s.csv")]) == 2
    finally:
        sock.close()
    assert f"{tmp_path / 's.csv'}: is a socket; an output must be a regular file" in \
        capsys.readouterr().err
    assert (tmp_path / "s.csv").is_socket()


@pytest.mark.parametrize("how", ["same name", "symlink", "hard link"])
def test_output_onto_the_commands_own_input_is_refused(tmp_path, capsys, how):
    netlist = tmp_path / "X.mcir"
    netlist.write_text(NETLIST.read_text())
    out = netlist
    if how == "symlink":
        out = tmp_path / "out.csv"
        out.symlink_to(netlist)
    elif how == "hard link":
        out = tmp_path / "out.csv"
        os.link(netlist, out)
    status = main(["sweep", str(netlist), "--omega-min", "1", "--omega-max", "10",
                   "--points", "3", "-o", str(out)])
    assert status == 2
    assert capsys.readouterr().err.strip() == (
        f"mechcirc: error: {out}: is also this command's input {netlist}; writing it "
        "would replace the input: give the output another name")
    assert netlist.read_text() == NETLIST.read_text()


@pytest.mark.parametrize("argv", [
    ["transient", "{in}", "--t-end", "0.01", "--waveform", "step", "-o", "{in}"],
    ["forces", "{in}", "--omega", "10", "--plot", "{in}.png", "--json"],
])
def test_other_commands_refuse_their_input_as_output(tmp_path, capsys, argv):
    netlist = tmp_path / "X.mcir"
    netlist.write_text(NETLIST.read_text())
    if argv[0] == "forces":                    # a plot named like the input's PNG twin
        (tmp_path / "X.mcir.png").symlink_to(netlist)
    argv = [a.replace("{in}", str(netlist)) for a in argv]
    assert main(argv) == 2
    assert "is also this command's input" in capsys.readouterr().err
    assert netlist.read_text() == NETLIST.read_text()


def test_permission_error_names_the_output_not_the_temporary(tmp_path, monkeypatch, capsys):
    """mkstemp's own error names the temporary file it tried (.out.csv.XXXX.tmp.csv)."""
    import tempfile

    def refused(prefix, suffix, dir):
        raise PermissionError(13, "Permission denied", os.path.join(dir, f"{prefix}abcd{suffix}"))

    monkeypatch.setattr(tempfile, "mkstemp", refused)
    target = tmp_path / "out.csv"
    assert main(SWEEP + ["-o", str(target)]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (f"{target}: error: permission denied (writing into folder "
                           f"{tmp_path})")


@pytest.mark.skipif(getattr(os, "geteuid", lambda: 0)() == 0,
                    reason="root writes into read-only folders (and Windows has no geteuid)")
def test_read_only_folder_names_the_output(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        assert main(SWEEP + ["-o", str(folder / "out.csv")]) == 2
    finally:
        folder.chmod(0o755)
    err = capsys.readouterr().err
    assert err.startswith(f"{folder / 'out.csv'}: error: permission denied") and ".tmp" not in err


@pytest.mark.parametrize("errno_, text", [(28, "no space left on device"),
                                          (30, "read-only file system")])
def test_a_system_refusal_at_the_rename_is_a_named_user_error(tmp_path, monkeypatch, capsys,
                                                              errno_, text):
    """Not an internal error: the disk or file system refused, and the output is named."""
    def refused(src, dst):
        raise OSError(errno_, os.strerror(errno_), src, dst)

    monkeypatch.setattr(os, "replace", refused)
    target = tmp_path / "out.csv"
    assert main(SWEEP + ["-o", str(target)]) == 2
    err = capsys.readouterr().err
    assert err.strip() == f"{target}: error: {text} (writing into folder {tmp_path})"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="no /proc/self/fd")
def test_a_descriptor_name_writes_into_its_pipe_and_refuses_its_regular_file(tmp_path, capsys):
    """``-o /dev/stdout`` is /proc/self/fd/1: to a pipe it is written in place (its link
    names no path, 'pipe:[…]'); to a regular file (stdout redirected) it is refused,
    since replacing that file or writing into it would lose or mix the summary."""
    expected = _csv_of_sweep(tmp_path, capsys)
    read, write = os.pipe()
    with os.fdopen(read) as reader:
        with os.fdopen(write, "w") as writer:
            status = main(SWEEP + ["-o", f"/proc/self/fd/{writer.fileno()}"])
        assert status == 0, capsys.readouterr().err
        assert reader.read() == expected
    capsys.readouterr()
    log = tmp_path / "log.txt"
    with open(log, "w") as fh:
        assert main(SWEEP + ["-o", f"/proc/self/fd/{fh.fileno()}"]) == 2
    assert f"an open file descriptor, here of the file {log}; give that file's name" in \
        capsys.readouterr().err
    assert log.read_text() == ""
