"""vtb — vehicle–track–bridge vertical dynamics with a Rust core.

Quick start::

    import vtb
    cfg = vtb.paper_config()          # the article's validation case
    res = vtb.simulate(cfg)           # ~34 500 Newmark steps
    print(res.metrics()["rail_acc_max"])

See ``README.md`` for units and conventions and ``docs/`` for the model and its choices.
"""

from . import comfort, irregularity, spectra
from ._core import __version__
from .config import (
    Config,
    Coupling,
    Discretisation,
    Layer,
    MovingForce,
    Output,
    RayleighCoefficients,
    RayleighRatio,
    Solver,
    DamperGroup,
    Structure,
    TIDs,
    Vehicle,
)
from .errors import ConfigError, ConvergenceError, SolverError, StaleFileError, VtbError
from .fesea import FeSeaReport, fesea_report
from .irregularity import Irregularity, IrregularityWarning
from .presets import crh3_car, example_config, examples, moving_load_config, paper_config, paper_irregularity, tids_around
from .spectra import low_pass
from .contact import contact_patch_half_length
from .resolution import LayerBand, ResolutionWarning, ResolvedBand, resolved_band
from .simulate import Result, assembled_matrices, irregularity_profile, load, metric_unit, simulate, simulate_batch
from .studies import StudyResult, get_field, index_names, set_field, study
from .tid_sweep import SweepResult, pinned_pinned_frequency, sweep
from .track import Modes, decay_rate, deck_band, modes, receptance
from .spans import spans
from .trains import TrainInfo, consist_extent, train, trains
from .zones import bridge_extent, track_zones
from .optimize import OptimizationResult, ParetoResult, optimize
from .robust import DesignEvaluation, evaluate_design, evaluate_designs
from .tables import metrics_table, read_parquet, to_parquet
from .config import plausible_ranges

__all__ = [
    "Config", "Coupling", "Discretisation", "Layer", "MovingForce", "Output", "RayleighCoefficients",
    "RayleighRatio", "Solver", "Structure", "TIDs", "DamperGroup", "Vehicle", "Irregularity", "IrregularityWarning", "irregularity",
    "ConfigError", "StaleFileError", "ConvergenceError", "SolverError", "VtbError", "Result", "simulate",
    "simulate_batch", "load", "metric_unit", "assembled_matrices", "irregularity_profile", "paper_config", "paper_irregularity", "crh3_car", "examples", "example_config",
    "moving_load_config", "FeSeaReport", "fesea_report", "tids_around", "sweep", "SweepResult", "pinned_pinned_frequency", "optimize", "OptimizationResult", "__version__",
    "low_pass", "contact_patch_half_length", "resolved_band", "ResolvedBand", "LayerBand", "ResolutionWarning", "receptance", "decay_rate", "deck_band", "spans", "modes", "Modes", "evaluate_design", "evaluate_designs", "DesignEvaluation",
    "metrics_table", "read_parquet", "to_parquet", "plausible_ranges", "study", "StudyResult", "index_names", "get_field", "set_field", "ParetoResult",
    "train", "trains", "TrainInfo", "consist_extent", "track_zones", "bridge_extent",
]
