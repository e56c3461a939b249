"""Parameter identification and controller optimization (the seed's chapter 6).

* :mod:`.data`: measured experiments (CSV, Parquet, pandas) with checked units and times.
* :mod:`.bench`: a virtual test bench with hidden true parameters.
* :mod:`.classic`: the classic motor tests (locked rotor, time constants, friction).
* :mod:`.discretize`: sampled trajectories with exact forward sensitivities.
* :mod:`.problem`: weighted least squares over several experiments, with confidence
  intervals (:mod:`.uncertainty`: honest ones for correlated residuals);
  :mod:`.multistart`: several starts inside the bounds, as batch tasks, the best kept.
* :mod:`.validation`: the fitted model on other data (RMSE, fit %, residual
  correlations), :mod:`.expressions`: measured outputs as expressions of variables.
* :mod:`.sensitivity`: Monte Carlo sensitivity analysis.
* :mod:`.optimize`: response optimization of controller gains with requirements.
"""

from mechatron.estimation.data import Experiment, load_experiment
from mechatron.estimation.problem import (EstimationProblem, EstimationResult,
                                           FreeParameter, estimate)
from mechatron.estimation.validation import ValidationReport, validate

__all__ = ["Experiment", "load_experiment", "EstimationProblem", "EstimationResult",
           "FreeParameter", "estimate", "validate", "ValidationReport", "demo_run"]


def demo_run(out_dir) -> dict:
    """The chapter-6 workflow on the virtual bench (see :mod:`.demo`)."""
    from mechatron.estimation.demo import demo_run as run
    return run(out_dir)
