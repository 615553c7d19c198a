"""What Python knows about the core's indices: their units (:func:`metric_unit`) and the lists
of indices the article's studies keep."""

from __future__ import annotations

from ..config import gateway
from ..config.fields import Config
from ..errors import config_error

#: Units of the metrics by the ending of their names (``{layer}_acc_max`` → m/s²).
METRIC_UNITS = (("_disp_max", "m"), ("_acc_max", "m/s²"), ("_acc_max_raw", "m/s²"), ("_acc_rms", "m/s²"), ("_acc_settle", "s"), ("_comfort_aw", "m/s²"), ("_force_max", "N"), ("_force_min", "N"), ("contact_loss_events", "–"))


def metric_unit(name: str) -> str:
    """The unit of a metric (``"m/s²"`` for ``rail_acc_max``)."""
    for ending, unit in METRIC_UNITS:
        if name.endswith(ending):
            return unit
    raise config_error("metric", name, "no such metric")


def index_names(config: Config) -> list:
    """Every index a run of ``config`` reports (the core's list; ``output.indices`` names a
    subset): per layer ``{layer}_disp_max``, ``_acc_max``, ``_acc_rms``, ``_acc_settle`` (and
    ``_acc_max_raw`` with a band limit), the first car's and the contacts' indices."""
    return gateway.index_names(config.to_core_json())
