"""Preisach hysteresis of the PPAM force function (thesis §3.6).

Modules (one concept each):

* :mod:`.everett` -- the weight (3.33) and its Everett function;
* :mod:`.memory` -- the staircase memory in a flat float64 row, and the
  compiled update/peek leaves for the plant's effect-state vector;
* :mod:`.preisach` -- the operator on sampled inputs, the major loop
  (fig. 3.12) and its least-squares line W_fit;
* :mod:`.force` -- eps_s (3.34), the force factor of (3.35), delta constants;
* :mod:`.tensile` -- a simulated tensile test (§3.6.1) and the least-squares
  fit of delta;
* :mod:`.dahl` -- Dahl presliding friction along a sampled path (the friction
  hysteresis of the synthetic cylinder campaigns).
"""

from .everett import C_THESIS, D_THESIS, THESIS_WEIGHT, PreisachWeight, everett
from .force import (DELTA_25_FIBRES, DELTA_40_FIBRES, EPS_MAX, hysteresis_factor,
                    scaled_contraction, scaled_input)
from .memory import (MAX_DEPTH, MEMORY, STATE_LENGTH, history_of_memory, initial_memory,
                     preisach_output, preisach_peek, preisach_update)
from .preisach import major_loop, preisach_response, w_fit

__all__ = ["C_THESIS", "D_THESIS", "DELTA_25_FIBRES", "DELTA_40_FIBRES", "EPS_MAX",
           "MAX_DEPTH", "MEMORY", "PreisachWeight", "STATE_LENGTH", "THESIS_WEIGHT", "everett",
           "history_of_memory", "hysteresis_factor", "initial_memory", "major_loop", "preisach_output",
           "preisach_peek", "preisach_response", "preisach_update", "scaled_contraction",
           "scaled_input", "w_fit"]
