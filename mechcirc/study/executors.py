"""Running a study: :func:`run_study`, the output's lock, tasks sized from memory,
and the executors that run them (this process, a local process pool, a Dask
cluster)."""

import contextlib
import itertools
import math
import os
import signal
import sys
import threading
from dataclasses import dataclass, field, replace
from typing import Callable, TextIO

import numpy as np

from ..errors import MechcircError
from ..sources import brief, data_frame, summary_repr
from .journal import (csv_text, curve_writer, journal_path, journal_record, open_journal,
                      require_pyarrow, resumed_rows, write_output)
from .rows import run_batch
from .spec import StudySpec, column_units

__all__ = ["run_study", "StudyResult"]


@dataclass
class StudyResult:
    """The rows of a study in index order, and how it ran.

    ``rows`` holds every row, or with ``run_study(keep_rows=False)`` only the
    failed ones (the table is in the output file); ``count`` is the number of
    rows of the table either way.  ``units`` maps each column to its unit
    (:func:`column_units`).
    """

    __repr__ = summary_repr

    columns: list[str]
    rows: list[dict]
    executor: str
    workers: int
    skipped: int = 0
    failed: int = field(default=0)
    count: int = -1
    units: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        if self.count < 0:
            self.count = len(self.rows)

    def to_dataframe(self):
        """:attr:`rows` as a ``pandas.DataFrame`` in :attr:`columns`; ``attrs["units"]`` the
        unit of each column ("" where it has none)."""
        return data_frame(self.rows, {c: self.units.get(c) or "" for c in self.columns})


def _todo(spec: StudySpec, have: set, size: int):
    """The points not in ``have``, in batches of ``size``, made as they are taken (a
    million points are not held at once): each ``(indices, values)``, two arrays, so
    that a task travels to a worker as a few kilobytes of numbers, not dicts."""
    todo = ((i, p) for i, p in enumerate(spec.points) if i not in have)
    while batch := list(itertools.islice(todo, size)):
        index, values = zip(*batch)
        yield np.array(index, dtype=np.int64), np.array(values, dtype=float)


@dataclass
class _TaskOut:
    """What a task sends back: its rows already written as journal lines (made on
    the worker, so the study's own process only appends text), the failed rows,
    and all rows only when they are asked for."""

    text: str
    n: int
    bad: list
    rows: list | None
    K: object = None


def _run_task(spec: StudySpec, points, curves: bool, keep: bool, lines: bool) -> _TaskOut:
    """One task on a worker: :func:`run_batch` of ``points`` (``(indices, values)``
    from :func:`_todo`), its journal lines made here."""
    index, values = points
    batch = [(int(i), dict(zip(spec.params, v))) for i, v in zip(index.tolist(),
                                                                  values.tolist())]
    rows, K = run_batch(spec, batch, curves) if curves else (run_batch(spec, batch), None)
    text = csv_text(journal_record(r, spec.columns) for r in rows) if lines else ""
    bad = [r for r in rows if r["status"] != "ok"]
    return _TaskOut(text, len(rows), bad, rows if keep or curves else None, K)


def run_study(spec: StudySpec, *, output: str | os.PathLike | None = None,
              scheduler: str | None = None, workers: int | None = None, resume: bool = False,
              batch_size: int | None = None, connect_timeout: float = 10.0, keep_rows: bool = True,
              on_rows: Callable[[int], None] | None = None,
              curves: str | os.PathLike | None = None) -> StudyResult:
    """Run every point of ``spec``; return the rows (and write them to ``output``).

    Parameters
    ----------
    spec : StudySpec
        From :func:`load_spec` or :func:`parse_spec`.
    output : path, optional
        CSV (or ``.parquet``, needs pyarrow) written atomically at the end (an existing file is kept
        until then) from the journal, in index order and in chunks, with the spec and column units
        (Parquet metadata or sidecar ``OUTPUT.meta.json``).  Rows are journalled with checksums to
        ``OUTPUT.partial.csv`` (:func:`journal_path`), removed at the end.
    scheduler : str, optional
        Dask scheduler address (``tcp://host:8786``); by default the local cores run the study.
    workers : int, optional
        Local processes (default: all cores); 1 runs in this process.
    resume : bool
        Keep the verified rows of the journal (or of a finished ``output``) and run only the
        missing points; refused when they were made from another spec.
    batch_size : int, optional
        Points per task (default: sized from memory, :func:`task_size`).
    connect_timeout : float
        Seconds to wait for the Dask scheduler, then for its first worker, before giving up.
    keep_rows : bool
        Return every row (default); False keeps only the failed ones in memory (with ``output``,
        for studies too large to hold: the table is the file).
    on_rows : callable, optional
        Called with the number of rows each time a batch finishes (progress).
    curves : path, optional
        Also write K(ω) of every point (a sweep) to this Parquet file (needs pyarrow), long
        format: a row per point and ω, columns ``design`` (the table's ``index``), ``omega``
        [rad/s], ``K_re``, ``K_im`` [m/(N·s), or rad/(N·m·s) for a rotary drive]; units in the
        fields' metadata, the spec (:func:`provenance`) in the file's.  One row group per task,
        in the order tasks finish; failed points have none.  Not with ``resume``.

    Returns
    -------
    StudyResult
        Columns, rows (or the failed ones), executor, workers, counts.

    Raises
    ------
    MechcircError
        Another study holds ``output`` (its ``OUTPUT.lock``); ``resume`` finds rows of another spec;
        the scheduler cannot be reached or has no worker (nothing is written).
    """
    parquet = _check_run(spec, output, scheduler, connect_timeout, resume, curves)
    with _lock(output) if output else contextlib.nullcontext(), \
            curve_writer(curves, spec) as write_curves:
        journal = journal_path(output) if output else None
        done = resumed_rows(spec, output, journal, parquet) if resume and journal else []
        take = _Take(spec, journal, done, keep_rows or not output, write_curves, on_rows)
        run = _execute(spec, done, (scheduler, connect_timeout), workers, batch_size, take)
        if journal:
            _publish(output, parquet, spec, journal, take, done)
    return take.result(*run)


def _publish(output, parquet: bool, spec: StudySpec, journal: str, take, done: list) -> None:
    """Write ``output`` whole (atomically) from the journal, then remove the journal."""
    # Rows are journalled as they finish to a CSV beside the output, each with
    # a checksum; the output itself is written whole at the end, so an
    # existing file stays as it was until the new table is complete.
    if take.sink is None:           # nothing ran: the journal holds the kept rows
        open_journal(journal, spec, done).close()
    write_output(output, parquet, spec, journal)
    with contextlib.suppress(FileNotFoundError):
        os.unlink(journal)


def _check_run(spec: StudySpec, output, scheduler, connect_timeout, resume: bool,
               curves) -> bool:
    """Refuse :func:`run_study` settings that cannot work, before anything is written;
    whether the output is Parquet."""
    if parquet := bool(output) and str(output).lower().endswith(".parquet"):
        require_pyarrow()
    if scheduler and not (isinstance(connect_timeout, (int, float)) and
                          0 < connect_timeout <= 3600):
        raise MechcircError(f"connect_timeout must be from 0 to 3600 s, got "
                            f"{brief(connect_timeout)}")
    if curves is not None:
        if spec.analysis != "sweep":
            raise MechcircError(f"curves of K(omega) need analysis = \"sweep\" (an omega grid); "
                                f"this study is {spec.analysis!r}")
        if resume:
            raise MechcircError("curves cannot be resumed (the points kept would have "
                                "none): run the study again without --resume")
        require_pyarrow()
    return parquet


class _Take:
    """Takes each finished task in the study's process: its curves written, its
    rows counted and kept (all, or the failed ones), its journal lines appended
    to the journal (opened with the kept rows when the first task finishes), and
    progress reported."""

    def __init__(self, spec: StudySpec, journal: str | None, done: list[dict],
                 keep_rows: bool, write_curves: Callable | None,
                 on_rows: Callable[[int], None] | None):
        self.spec, self.journal, self.done = spec, journal, done
        self.keep_rows, self.write_curves, self.on_rows = keep_rows, write_curves, on_rows
        self.rows = list(done) if keep_rows else [r for r in done if r["status"] != "ok"]
        self.count, self.failed = len(done), sum(r["status"] != "ok" for r in done)
        self.sink: TextIO | None = None

    @property
    def task(self) -> tuple:
        """What each task returns besides its failed rows: (curves, all rows, journal text)."""
        return (self.write_curves is not None, self.keep_rows, bool(self.journal))

    def __call__(self, out: _TaskOut) -> None:
        if self.write_curves is not None:
            self.write_curves(out.rows, out.K)
        self.count += out.n
        self.failed += len(out.bad)
        self.rows.extend((out.rows or []) if self.keep_rows else out.bad)
        if self.journal:
            if self.sink is None:
                self.sink = open_journal(self.journal, self.spec, self.done)
            self.sink.write(out.text)
            self.sink.flush()
        if self.on_rows is not None:
            self.on_rows(out.n)

    def close(self) -> None:
        if self.sink is not None:
            self.sink.close()

    def result(self, executor: str, n_workers: int) -> StudyResult:
        self.rows.sort(key=lambda r: r["index"])
        return StudyResult(self.spec.columns, self.rows, executor, n_workers, len(self.done),
                           self.failed, self.count, column_units(self.spec))


def _execute(spec: StudySpec, done: list, dask: tuple, workers: int | None,
             batch_size: int | None, take: _Take) -> tuple[str, int]:
    """Run the points not in ``done`` on the Dask scheduler ``dask`` = (address,
    timeout) if given, else on the local cores, then close ``take``; the
    executor's name and its number of workers."""
    have = {r["index"] for r in done}
    n_todo = len(spec.points) - len(have)
    # Connect before the journal is touched: a failed start leaves no file.
    client = _dask_client(*dask) if dask[0] else None
    try:
        if client is not None:
            return "dask", _run_dask(spec, have, n_todo, client, batch_size, take)
        return _run_local(spec, have, n_todo, workers or os.cpu_count() or 1, batch_size, take)
    finally:
        take.close()


@contextlib.contextmanager
def _lock(output):
    """Hold ``OUTPUT.lock`` while a study writes ``output`` (a context manager).

    ``fcntl.flock`` on the lock file: the kernel releases it when its holder
    ends, however it ends, so a lock file left by a killed study (its pid no
    longer running) is simply taken over.  The file names the holder's pid for
    the message a second writer gets.  Without ``fcntl`` (Windows) the file is
    created with ``O_EXCL`` and one left by a killed study must be deleted by hand.
    """
    import socket

    path = f"{os.fspath(output)}.lock"

    def held(holder: str, hint: str = ""):
        return MechcircError(f"{os.fspath(output)} is being written by another study "
                             f"({holder or 'pid unknown'}, per {path}); wait for it to end, "
                             f"or write another -o{hint}")

    try:
        import fcntl
    except ImportError:
        fcntl = None
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | (0 if fcntl else os.O_EXCL), 0o644)
        except FileExistsError:
            raise held(_holder(path), f" (if it is no longer running, delete {path})") from None
        except OSError as exc:
            raise MechcircError(f"{os.fspath(output)}: cannot create the lock file {path}: "
                                f"{exc.strerror}") from None
        if fcntl is None:
            break
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise held(_holder(path)) from None
        with contextlib.suppress(FileNotFoundError):   # the holder may have removed it
            if os.path.samestat(os.fstat(fd), os.stat(path)):
                break
        os.close(fd)
    _LOCK_FDS.add(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode())
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)         # before the lock goes: see the samestat check
        _LOCK_FDS.discard(fd)
        os.close(fd)


#: Descriptors of the output locks this process holds: a forked worker closes its
#: copies (:func:`_die_with_parent`), so that the lock ends with the study's process.
_LOCK_FDS: set[int] = set()


def _holder(path: str) -> str:
    with contextlib.suppress(OSError), open(path, encoding="utf-8", errors="replace") as fh:
        return fh.read(200).strip()
    return ""


#: Memory a task may fill with its arrays (bytes): the batch's K, error bound,
#: Q0 and flags on the designs × ω grid and its stacked nodal matrices.
TASK_BYTES = 64 * 2 ** 20
#: Bytes a design takes in a task: for its resonances and extremes, and per ω point
#: (tracemalloc's peak over designs + sweep + flags + resonances + extremes of
#: stb_heald.mcir: 12.3 kB and 37 B measured; see docs/performance.md).
_BYTES_PER_DESIGN, _BYTES_PER_POINT = 13_000, 40


def task_size(spec: StudySpec, n_points: int, n_workers: int,
              batch_size: int | None = None) -> int:
    """Points per task: ``batch_size`` if given, else as many as fit in
    :data:`TASK_BYTES` (the designs' arrays), but at least four tasks per worker
    (so that the workers share the end of the study) and at most ``n_points``.
    A sley simulation is one point at a time: at most 500 per task."""
    if batch_size:
        return max(1, int(batch_size))
    share = math.ceil(n_points / (4 * max(1, n_workers)))
    if spec.analysis == "simulate":
        return max(1, min(500, share))
    width = spec.omega[2] if spec.analysis == "sweep" and spec.omega else 0
    fit = TASK_BYTES // (_BYTES_PER_DESIGN + _BYTES_PER_POINT * width)
    return max(1, min(fit, share))


def _run_local(spec, have, n_todo, n_workers, batch_size, take) -> tuple[str, int]:
    size = task_size(spec, n_todo, n_workers, batch_size)
    if n_workers <= 1 or n_todo <= size:
        # One batch or one worker: starting processes would cost more than it saves.
        for batch in _todo(spec, have, size):
            take(_run_task(spec, batch, *take.task))
        return "inline", 1
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    with ProcessPoolExecutor(max_workers=n_workers, initializer=_die_with_parent,
                             initargs=(os.getpid(),)) as pool:
        # The spec without its point list: each batch carries its own points, and the
        # spec is pickled once per batch (a million points would otherwise travel with
        # every batch).
        light = replace(spec, points=())
        batches = _todo(spec, have, size)
        pending: set = set()
        try:
            # A few tasks per worker in flight, the next made as one finishes: the
            # points of a large study are never all in memory as tasks.
            pending.update(pool.submit(_run_task, light, batch, *take.task)
                           for batch in itertools.islice(batches, 2 * n_workers))
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for fut in finished:
                    take(fut.result())
                    if (batch := next(batches, None)) is not None:
                        pending.add(pool.submit(_run_task, light, batch, *take.task))
        except BaseException:
            for fut in pending:
                fut.cancel()
            # Ended here, none is left for the pool's shutdown to wait on (2 Ctrl-C in 10
            # hung: a worker blocked sending back its interrupted batch, the pool joining it)
            for proc in list((getattr(pool, "_processes", None) or {}).values()):
                proc.kill()
            raise
    return "local", n_workers


def _die_with_parent(parent: int) -> None:
    """Worker initializer: end this worker when the study's process ends, however it ends.

    After SIGKILL of the parent, workers would otherwise be re-parented to
    init and wait on the pipe for minutes.  On Linux the kernel delivers
    SIGKILL to the worker when its parent dies (``prctl(PR_SET_PDEATHSIG)``);
    elsewhere a daemon thread polls the parent's pid once a second.  A forked
    worker also closes its copies of the output lock's descriptor (a flock
    belongs to every copy: the lock would outlive a killed study in its workers).
    Ctrl-C is the parent's to handle (it ends the workers), and SIGTERM ends a worker
    at once (the command line's handler, inherited by the fork, would raise inside its
    batch and send that back).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    for fd in _LOCK_FDS:
        with contextlib.suppress(OSError):
            os.close(fd)
    _LOCK_FDS.clear()

    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):     # no libc or prctl: poll
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            PR_SET_PDEATHSIG = 1
            if libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
                if os.getppid() != parent:      # the parent died before prctl took hold
                    os._exit(1)
                return

    def watch():
        import time

        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="mechcirc-parent-watch", daemon=True).start()


def _dask_client(scheduler: str, timeout: float):
    """A client of the scheduler at ``scheduler`` once it has a worker, else a user error
    within about ``timeout`` seconds (for the connection, then for the first worker)."""
    try:
        from distributed import Client
    except ImportError:
        raise MechcircError("--scheduler needs Dask: pip install 'mechcirc[study]'") from None
    try:
        client = Client(scheduler, timeout=f"{timeout}s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise MechcircError(f"cannot reach the Dask scheduler at {brief(scheduler)}: "
                            f"{exc}") from None
    try:
        client.wait_for_workers(1, timeout=timeout)
    except BaseException as exc:
        client.close()
        if not isinstance(exc, (OSError, TimeoutError)):
            raise
        raise MechcircError(f"the Dask scheduler at {scheduler} has no workers (none joined "
                            f"within {timeout:g} s); start one with 'dask worker {scheduler}' "
                            "or raise --connect-timeout") from None
    return client


def _run_dask(spec, have, n_todo, client, batch_size, take) -> int:
    from distributed import as_completed

    try:
        n_workers = max(1, sum(w.get("nthreads", 1) for w in
                               client.scheduler_info()["workers"].values()))
        size = task_size(spec, n_todo, n_workers, batch_size)
        try:
            spec_future = client.scatter(replace(spec, points=()), broadcast=True)   # as local
        except TimeoutError:
            raise MechcircError("the Dask cluster's workers left before the study "
                                "started") from None
        # A few tasks per worker thread in flight, the next submitted as one finishes.
        batches = _todo(spec, have, size)
        futures = as_completed([client.submit(_run_task, spec_future, batch, *take.task,
                                              pure=False)
                                for batch in itertools.islice(batches, 4 * n_workers)])
        for fut in futures:
            take(fut.result())
            if (batch := next(batches, None)) is not None:
                futures.add(client.submit(_run_task, spec_future, batch, *take.task, pure=False))
        return n_workers
    finally:
        client.close()
