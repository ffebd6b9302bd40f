"""Time domain of any circuit: transients, clearances (backlash) and the frequency-domain cross-check.

* :func:`transient` integrates a :class:`~mechcirc.circuit.Circuit` built from
  the same nodal assembly as the frequency domain (:mod:`.model`), exactly
  between drive samples when linear, with the ElastoBacklash clearance law
  (:mod:`._kernels`) otherwise.
* :func:`crosscheck` compares resonances and |Q0| of the sweep with ringing
  and steady-state amplitudes measured on transients (:mod:`._crosscheck`).
"""

from ._crosscheck import CrossCheck, crosscheck
from .result import TransientResult
from .simulate import transient
from .waveform import Waveform, parse_waveform

__all__ = ["transient", "TransientResult", "Waveform", "parse_waveform", "crosscheck", "CrossCheck"]
