"""Drive waveforms of a transient: what the drive does in time.

A :class:`Waveform` is the drive's value u(t) in units of its amplitude: at
rest, harmonic, a step, an impulse, a table of samples (``--waveform
csv:PATH``), a function of t, or a cam's motion over one shaft revolution at
a shaft speed.  :func:`parse_waveform` reads the CLI's ``--waveform`` text.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

import numpy as np

from ..errors import MechcircError, NetlistError
from ..units import parse_omega

if TYPE_CHECKING:  # pragma: no cover - annotations only
    from ..motion_laws import Motion

__all__ = ["Waveform", "parse_waveform"]


@dataclass(frozen=True)
class Waveform:
    """A drive waveform, in units of the drive's amplitude (multiplied by it).

    ``kind``: ``"rest"`` (0), ``"harmonic"`` (sin ω t), ``"step"`` (1 for t ≥ 0),
    ``"impulse"`` (a unit-area pulse at t = 0: momentum for a force drive, a
    displacement step of amplitude × 1 s for a velocity drive), ``"samples"``
    (``times``, ``values``: linear interpolation, held beyond the ends; values
    are absolute, not scaled), ``"callable"`` (``func(t)``, absolute) or
    ``"motion"`` (the velocity Ω·dx/dθ(Ωt) of ``motion``, a
    :class:`~mechcirc.motion_laws.Motion` over one shaft revolution, at the
    shaft speed ``omega`` = Ω [rad/s]; times the amplitude, 1 for a netlist's
    ``motion=`` drive).
    """

    kind: str
    omega: float = 0.0
    times: tuple = ()
    values: tuple = ()
    func: Callable | None = field(default=None, compare=False)
    motion: Motion | None = None

    def sample(self, t: np.ndarray, amplitude: float) -> np.ndarray:
        if self.kind in ("rest", "impulse"):
            return np.zeros_like(t)
        if self.kind == "harmonic":
            return amplitude * np.sin(self.omega * t)
        if self.kind == "step":
            return np.full_like(t, amplitude)
        if self.kind == "samples":
            return np.interp(t, np.asarray(self.times), np.asarray(self.values))
        if self.kind == "motion":
            return amplitude * self.omega * self._motion().evaluate(self.omega * t)[1]
        if self.kind == "callable":
            func = self.func
            if func is None:
                raise ValueError("a 'callable' waveform needs func")
            try:
                out = np.asarray(func(t), dtype=np.float64).reshape(t.shape)
            except (TypeError, ValueError):   # a function of one number (math.sin) or a constant
                out = np.array([float(func(float(s))) for s in t])
            if not np.all(np.isfinite(out)):
                raise MechcircError("the drive function returned a non-finite value")
            return out
        raise ValueError(f"unknown waveform kind {self.kind!r}")

    def rate(self, t: np.ndarray, amplitude: float) -> np.ndarray:
        """du/dt of a ``"motion"`` waveform: amplitude · Ω² d²x/dθ² at θ = Ωt."""
        return amplitude * self.omega ** 2 * self._motion().evaluate(self.omega * t)[2]

    def _motion(self) -> Motion:
        if self.motion is None:
            raise ValueError("a 'motion' waveform needs motion")
        return self.motion

    @property
    def label(self) -> str:
        """A few words for titles: ``"sin(50 rad/s·t)"``, ``"step"``, ``"table of 12 samples"``."""
        return {"rest": "at rest", "harmonic": f"sin({self.omega:.6g} rad/s·t)",
                "samples": f"table of {len(self.times)} samples",
                "callable": "function of t",
                "motion": f"motion of a turn at Ω = {self.omega:.6g} rad/s"}.get(self.kind, self.kind)


def parse_waveform(text: str | None) -> Waveform:
    """``harmonic:OMEGA`` | ``step`` | ``impulse`` | ``csv:PATH`` | ``rest`` (or None) → Waveform.

    Parameters
    ----------
    text : str or None
        The ``--waveform`` text.

    Returns
    -------
    Waveform
        The waveform named by ``text``.
    """
    if text is None or text in ("rest", "step", "impulse"):
        return Waveform(text or "rest")
    kind, _, arg = text.partition(":")
    if kind == "harmonic" and arg:
        try:
            omega = parse_omega(arg)
        except Exception as exc:  # noqa: BLE001 - reported as a user error
            raise MechcircError(f"--waveform {text!r}: {exc}") from None
        if not (math.isfinite(omega) and omega > 0):
            raise MechcircError(f"--waveform {text!r}: ω must be a finite number > 0 [rad/s]")
        return Waveform("harmonic", omega=omega)
    if kind == "csv" and arg:
        return read_csv_drive(arg)
    from ..sources import did_you_mean

    forms = {"harmonic": "harmonic:OMEGA (rad/s, or with a unit: harmonic:50Hz)",
             "csv": "csv:PATH", "step": "step", "impulse": "impulse", "rest": "rest"}
    hint = f"; write it as {forms[kind]}" if kind in forms else did_you_mean(kind, forms)
    raise MechcircError(f"--waveform {text!r} is not understood (expected harmonic:OMEGA, "
                        f"step, impulse, csv:PATH or rest){hint}")


def read_csv_drive(path: str) -> Waveform:
    """Drive samples from a CSV file of two columns, time [s] and value (one header line allowed)."""
    from ..sources import csv_rows, is_number, read_source

    text = read_source(path, "a drive CSV (time,value)")
    times: list[float] = []
    values: list[float] = []
    for lineno, row, cols, end in csv_rows(text, path):
        if len(row) != 2:
            raise NetlistError(f"{len(row)} column(s)", path, lineno, cols[2] if len(row) > 2
                               else end, "two columns time,value")
        try:
            t, v = float(row[0]), float(row[1])
        except ValueError:
            if not times and lineno == 1:
                continue                        # a header line
            j = 0 if not is_number(row[0]) else 1
            raise NetlistError(f"{row[j].strip()!r} is not a number", path, lineno, cols[j],
                               "time,value: two numbers") from None
        if not (math.isfinite(t) and math.isfinite(v)):
            j = int(math.isfinite(t))           # the first of the two that is not
            raise NetlistError(f"{row[j].strip()!r} is not finite", path, lineno, cols[j],
                               "finite numbers")
        if times and t <= times[-1]:
            raise NetlistError(f"time {t:g} is not after the previous {times[-1]:g}", path,
                               lineno, cols[0], "times that increase")
        times.append(t)
        values.append(v)
    if len(times) < 2:
        raise MechcircError(f"{path}: needs at least two samples (time,value)")
    return Waveform("samples", times=tuple(times), values=tuple(values))
