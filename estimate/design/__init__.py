"""Design of the next test: the drive the rig can run that best pins down what the data
cannot yet separate.

* :mod:`~estimate.design.drives` - the drive families (steady sine, stepped sine, amplitude
  steps, linear chirp; spin and coning on the spinning rig) and the rig's limits;
* :mod:`~estimate.design.information` - the Fisher information a record would add, from
  CasADi sensitivities through the simulation and from the fit's own Jacobians;
* :mod:`~estimate.design.problem` - the fit so far, the rig, the targets;
* :mod:`~estimate.design.search` - grid and local solves over every family;
* :mod:`~estimate.design.discrimination` - the drive that best tells two models apart;
* :mod:`~estimate.design.report` - the recommendation as text, JSON, drive file and plot.

Public API::

    from estimate.design import DesignProblem, design
    problem = DesignProblem.build("A_fit.json", load_case("A.toml"), targets=["p1.mass"])
    result = design(problem)
    print(result.summary())
"""

from .discrimination import Discrimination, discrimination
from .drives import (
    LATERAL_FAMILIES,
    AmplitudeSteps,
    LateralDrive,
    LinearChirp,
    SpinDrive,
    SteadySine,
    SteppedSine,
)
from .problem import CRITERIA, GOAL, LINEAR_SWING, MAX_SWING, DesignProblem, required_limits
from .report import Design
from .search import Candidate, Search, search

__all__ = ["AmplitudeSteps", "CRITERIA", "Candidate", "Design", "DesignProblem", "GOAL",
           "Discrimination", "LATERAL_FAMILIES", "LINEAR_SWING", "LateralDrive",
           "LinearChirp", "MAX_SWING", "Search", "SpinDrive", "SteadySine", "SteppedSine",
           "design", "discrimination", "required_limits", "search"]


def design(problem: DesignProblem, *, families: tuple[str, ...] | None = None,
           finalists: int = 3) -> Design:
    """Search the drives of ``problem``'s rig and return the recommendation.

    Parameters
    ----------
    problem : DesignProblem
        The fit so far, the rig and its limits, the targets (:meth:`DesignProblem.build`).
    families : tuple of str, optional
        Lateral drive families to search (:data:`LATERAL_FAMILIES`); default all.
    finalists : int, default 3
        How many of the best families' drives are judged by the fit's own information.

    Examples
    --------
    >>> result = design(DesignProblem.build("A_fit.json", case))   # doctest: +SKIP
    >>> result.gains()                                              # doctest: +SKIP
    ['interval of p1.mass from +/-5.5 % to +/-0.11 %', ...]
    """
    return Design(problem, search(problem, families=families, finalists=finalists))
