"""Multi-objective optimisation, independent of vtb's physics and split as pymoo splits it:
:mod:`~vtb.optim.problem` (a problem evaluated a whole generation at once, its population and
result), :mod:`~vtb.optim.indicators` (fronts, crowding, hypervolume, IGD, trade-off choices),
:mod:`~vtb.optim.nsga2` and :mod:`~vtb.optim.gamultiobj` (the algorithms),
:mod:`~vtb.optim.algorithm` (what they share), :mod:`~vtb.optim.driver` (:func:`minimize`: warm
start, hypervolume stop) and :mod:`~vtb.optim.checkpoint` (resumable runs).

Everything minimises. ``vtb.optim`` holds every name of the former ``vtb.optim``.
"""

from .checkpoint import saved_identity, write_atomically
from .driver import minimize
from .gamultiobj import GAMULTIOBJ_DEFAULTS
from .indicators import (asf, crowding_distance, hypervolume_2d, hypervolume_settled, igd, igd_plus, knee_point, min_distance_to_ideal,
                         non_dominated_sort)
from .nsga2 import NSGA2_DEFAULTS
from .problem import Generation, Population, Problem, Result, constraint_violation

__all__ = [
    "Problem", "Population", "Generation", "Result", "minimize", "non_dominated_sort", "crowding_distance", "constraint_violation",
    "hypervolume_2d", "hypervolume_settled", "igd", "igd_plus", "knee_point", "min_distance_to_ideal", "asf", "NSGA2_DEFAULTS",
    "GAMULTIOBJ_DEFAULTS", "saved_identity", "write_atomically",
]
