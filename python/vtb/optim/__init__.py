"""Multi-objective optimisation algorithms, independent of vtb's physics (split as pymoo splits
them): :mod:`~vtb.optim.problem` (problem, population, result), :mod:`~vtb.optim.indicators`
(fronts, crowding, hypervolume, trade-off choices), :mod:`~vtb.optim.nsga2`,
:mod:`~vtb.optim.gamultiobj` and :mod:`~vtb.optim.minimize` (the driver: warm start, stop,
checkpoints)."""
