"""The 16-parameter Bouc-Wen bushing of seed 002 (eqs. 1-5), as one subpackage.

| module | what it holds |
|---|---|
| ``model`` | ``BoucWenBushing``: parameters, state, the model protocol |
| ``kernels`` | the batched compiled kernel every run calls |
| ``passes``, ``step`` | the hysteretic variables advanced along the travel, one step |
| ``tables`` | the per-parameter-set map of the travel, its inverse |
| ``reference`` | a fixed-step reference integration (accuracy checks) |
| ``accuracy`` | the kernel's error against a converged run |
"""

from bushenv.models.boucwen.model import (  # noqa: F401  (the names users import from here)
    TABLE3_N_MM,
    BoucWenBushing,
    BoucWenError,
    BoucWenRunaway,
    n_mm_to_si,
    simulate_population,
)
