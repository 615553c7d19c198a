"""vtb — vehicle–track–bridge vertical dynamics with a Rust core.

Quick start::

    import vtb
    cfg = vtb.paper_config()          # the article's validation case
    res = vtb.simulate(cfg)           # ~34 500 Newmark steps
    print(res.metrics()["rail_acc_max"])

See ``README.md`` for units and conventions and ``docs/`` for the model and its choices.
"""

import sys
import types

from .analysis import comfort, spectra
from .config import irregularity
from .config.gateway import RESULTS_EPOCH, __version__
from .config.fields import (
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
    QuarterCar,
    Vehicle,
    plausible_ranges,
)
from .errors import ConfigError, ConvergenceError, MissingExtraError, OutputError, SolverError, StaleFileError, VtbError
from .analysis.fesea import FeSeaReport, fesea_report
from .config.irregularity import Irregularity, IrregularityWarning
from .config.presets import crh3_car, example_config, examples, moving_load_config, paper_config, paper_irregularity, tids_around
from .analysis.spectra import low_pass
from .analysis.contact import contact_patch_half_length
from .config.resolution import LayerBand, ResolutionWarning, ResolvedBand, resolved_band
from .config.prepare import irregularity_profile
from .run.indices import metric_unit
from .run.simulate import Result, assembled_matrices, load, simulate, simulate_batch
from .studies.grid import StudyResult, get_field, index_names, set_field, study
from .article.tid_problem import OptimizationResult, SweepResult
from .article.tid_sweep import pinned_pinned_frequency, sweep
from .analysis.track import Modes, decay_rate, deck_band, modes, receptance
from .config.spans import spans
from .config.trains import TrainInfo, consist_extent, train, trains
from .config.zones import bridge_extent, track_zones
from .article.tid_optimize import optimize
from .studies.optimize import ParetoResult
from .article.robust import DesignEvaluation, evaluate_design, evaluate_designs
from .run.tables import metrics_table, read_parquet, to_parquet
from .bridge.load_trains import LoadTrain, apply_load_train, load_train, load_trains
from .bridge.damping import code_damping
from .bridge.scan import ScanResult, scan_speeds, speed_scan
from .bridge.settings import BridgeCheck
from .bridge.assess import Assessment
from .bridge.report import bridge_check

__all__ = [
    "Config", "Coupling", "Discretisation", "Layer", "MovingForce", "Output", "RayleighCoefficients",
    "RayleighRatio", "Solver", "Structure", "TIDs", "DamperGroup", "Vehicle", "QuarterCar", "Irregularity", "IrregularityWarning", "irregularity",
    "ConfigError", "StaleFileError", "OutputError", "MissingExtraError", "ConvergenceError", "SolverError", "VtbError", "Result", "simulate",
    "simulate_batch", "load", "metric_unit", "assembled_matrices", "irregularity_profile", "paper_config", "paper_irregularity", "crh3_car", "examples", "example_config",
    "moving_load_config", "FeSeaReport", "fesea_report", "tids_around", "sweep", "SweepResult", "pinned_pinned_frequency", "optimize", "OptimizationResult", "__version__", "RESULTS_EPOCH",
    "low_pass", "contact_patch_half_length", "resolved_band", "ResolvedBand", "LayerBand", "ResolutionWarning", "receptance", "decay_rate", "deck_band", "spans", "modes", "Modes", "evaluate_design", "evaluate_designs", "DesignEvaluation",
    "metrics_table", "read_parquet", "to_parquet", "plausible_ranges", "study", "StudyResult", "index_names", "get_field", "set_field", "ParetoResult",
    "train", "trains", "TrainInfo", "consist_extent", "track_zones", "bridge_extent",
    "LoadTrain", "load_train", "load_trains", "apply_load_train", "code_damping", "scan_speeds", "speed_scan", "ScanResult",
    "BridgeCheck", "Assessment", "bridge_check",
]


class _Face(types.ModuleType):
    """``vtb`` itself. Importing an old module path whose name is also a function here
    (``import vtb.simulate``, ``vtb.optimize``, ``vtb.spans``, ``vtb.trains``) would set the
    module over the function; the function stays. Goes with the old paths."""

    def __setattr__(self, name, value):
        if isinstance(value, types.ModuleType) and isinstance(self.__dict__.get(name), types.FunctionType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Face
