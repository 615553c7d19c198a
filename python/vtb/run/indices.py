"""What Python knows about the core's indices, in one place.

The core names every index it computes (:func:`index_names`: ``{layer}_{quantity}`` per layer,
``car_*`` for the first car body, ``contact_*`` for the wheels). This module adds their units
(:func:`metric_unit`) and the lists the article's studies keep, built from layer names and
quantities rather than spelled out.

The units come from :data:`METRIC_UNITS`, a table of name endings. When the core exports its
catalogue of indices (name pattern, unit, layer, band, description per index), :func:`metric_unit`
is the one function to read it instead.
"""

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


def index(where: str, quantity: str) -> str:
    """The core's name of ``quantity`` (``"acc_max"``, ``"disp_max"``, …) of a layer, of
    ``"car"`` (the first car body) or of ``"contact"`` (the wheels)."""
    return f"{where}_{quantity}"


#: The article's layers: the rail (the top layer) and the slab under it.
RAIL, SLAB = "rail", "slab"
#: The article's indices in its symbols: the rail's acceleration amplitude a_rm, r.m.s. a_rRMS and
#: settling time a_rst, the slab's amplitude a_sm; beside them the displacement amplitudes of
#: the rail, the slab and the car body, the car body's acceleration amplitude, the wheels' largest
#: and smallest contact force and their contact-loss events.
A_RM, A_RRMS, A_RST, A_SM = index(RAIL, "acc_max"), index(RAIL, "acc_rms"), index(RAIL, "acc_settle"), index(SLAB, "acc_max")
D_RM, D_SM, D_CM, A_CM = index(RAIL, "disp_max"), index(SLAB, "disp_max"), index("car", "disp_max"), index("car", "acc_max")
F_MAX, F_MIN, LOSS = index("contact", "force_max"), index("contact", "force_min"), index("contact", "loss_events")


def rate(name: str) -> str:
    """The column of an index's reduction rate η = (X0 − X)/X0 in the studies' tables."""
    return f"eta_{name}"

#: The indices the article's studies journal per case: each of its layers' peak, r.m.s. and
#: settling time of the acceleration and peak displacement, the car body's, and the contacts'.
METRICS = (
    tuple(index(layer, q) for layer in (RAIL, SLAB) for q in ("acc_max", "acc_rms", "acc_settle", "disp_max"))
    + tuple(index("car", q) for q in ("acc_max", "acc_rms", "disp_max"))
    + tuple(index("contact", q) for q in ("force_max", "force_min", "loss_events"))
)
#: The article's objectives (a_rm, a_sm) and its constraints, each against its uncontrolled value.
ARTICLE_OBJECTIVES = (A_RM, A_SM)
CONSTRAINTS = (A_RM, A_SM, A_RRMS, A_RST)
#: The rail indices whose mean reduction is the article's comprehensive rate η_r.
RAIL_RATE = (A_RM, A_RRMS, A_RST)
#: Indices whose reduction rate η = (X0 − X)/X0 a study reports (the rest are counts or signed).
REDUCED = tuple(m for m in METRICS if m not in (F_MIN, LOSS))
