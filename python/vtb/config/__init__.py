"""The configuration: what a run is, and the one door to the core for it.

``fields`` (the dataclasses a run is made of), ``schema`` (the core's schema: fields, types,
defaults), ``irregularity`` (the track irregularity, generated on this side), ``resolution``
(the band a discretisation resolves), ``prepare`` (a run made ready for the core: its JSON made
once, plausibility, the irregularity's checks, warnings and sampled profile), ``presets``,
``trains``, ``spans`` and ``zones`` (ready-made configurations and builders), and ``gateway``,
the only module of this package that calls the core.

``vtb.config`` keeps every name of the former module of that name (now :mod:`vtb.config.fields`).
"""

from .fields import (
    Config, Coupling, DamperGroup, Damping, Discretisation, Layer, MovingForce, Output, RayleighCoefficients, RayleighRatio,
    QuarterCar, Solver, Structure, TIDs, Vehicle, check_types, core_dict, plausible_ranges,
)
from .irregularity import Irregularity

__all__ = [
    "Config", "Coupling", "DamperGroup", "Damping", "Discretisation", "Layer", "MovingForce", "Output", "RayleighCoefficients",
    "RayleighRatio", "QuarterCar", "Solver", "Structure", "TIDs", "Vehicle", "check_types", "core_dict", "plausible_ranges", "Irregularity",
]
