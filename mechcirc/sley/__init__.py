"""Sley (beat-up) dynamics of Mrázek in the time domain.

* :mod:`.models` -- :class:`SleyParameters`, eqs. (4) and (9), clearance and beat-up laws.
* :mod:`.presets` -- Tables 1 and 2 (variants 1–7) and the paper's printed results.
* :mod:`.simulation` -- :func:`simulate`, :func:`simulate_batch`, :class:`SleyResult`.
* :mod:`.linear` -- linearisation at a crank angle, eigenfrequencies, the circuit
  (:func:`to_circuit`, :func:`to_netlist`).
* :mod:`.plots` -- the curves of Figs. 4–9 (matplotlib imported inside).

The beat-up interval α defaults to 10° (not printed in the paper; σ = α; fitted to the
printed cells, docs/sley.md).
"""

from .linear import (LinearModel, SleyMode, eigenfrequencies, linearise, to_circuit,
                     to_netlist)
from .models import DEFAULT_ALPHA_DEG, ParameterError, SleyParameters
from .presets import PAPER, all_presets, preset
from .simulation import METHODS, SleyResult, simulate, simulate_batch, simulate_params

__all__ = ["SleyParameters", "ParameterError", "DEFAULT_ALPHA_DEG", "preset", "all_presets",
           "PAPER", "simulate", "simulate_params", "simulate_batch", "SleyResult", "METHODS",
           "linearise", "eigenfrequencies", "to_circuit", "to_netlist", "LinearModel", "SleyMode"]
