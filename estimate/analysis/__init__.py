"""What a fitted or declared analog predicts: Monte Carlo dispersion of the rig force over
the fit's uncertainty, and the nutation time constant of a spinning spacecraft."""

from .montecarlo import MonteCarlo, MonteCarloResult, monte_carlo
from .ntc import (
                  NutationTimeConstant,
                  envelope_growth_rate,
                  linearize,
                  nutation_time_constant,
                  steady_spin,
)

__all__ = ["MonteCarlo", "MonteCarloResult", "NutationTimeConstant", "envelope_growth_rate",
           "linearize", "monte_carlo", "nutation_time_constant", "steady_spin"]
