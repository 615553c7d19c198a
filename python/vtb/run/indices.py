"""What Python knows about the core's indices, in one place.

The core holds the one catalogue of indices (:func:`index_catalog`: name pattern, unit, subject,
band and description of every kind) and names every index a configuration reports
(:func:`index_names`: ``{layer}_{quantity}`` per layer, ``car_*`` for the first car body,
``contact_*`` for the wheels, ``pad{j}_*`` for the fasteners). This module reads units from the
catalogue (:func:`metric_unit`) and builds the lists the article's studies keep from layer names
and quantities rather than spelling them out.
"""

from __future__ import annotations

import functools
import re
from typing import NamedTuple

from ..config import gateway
from ..config.fields import Config
from ..errors import config_error

class IndexKind(NamedTuple):
    """One kind of index of the core's catalogue: its name ``pattern`` (``{layer}``, ``{band}``,
    ``{k}``, ``{w}`` or ``{j}`` standing for its subject), ``unit``, ``subject`` (what it is taken
    of), ``band`` (of the record it is taken from: ``raw``, ``band_limit``, ``deck_band``,
    ``third_octave``, ``iso2631_wk``) and ``description``."""

    pattern: str
    unit: str
    subject: str
    band: str
    description: str


@functools.lru_cache(maxsize=None)
def index_catalog() -> tuple:
    """Every kind of index the core computes (:class:`IndexKind` rows, in its order)."""
    return tuple(IndexKind(*row) for row in gateway.index_catalog())


_PLACEHOLDER = {"{layer}": ".+", "{band}": r"[0-9.eE+-]+", "{k}": r"[0-9]+", "{w}": r"[0-9]+", "{j}": r"[0-9]+"}


@functools.lru_cache(maxsize=None)
def _patterns() -> tuple:
    def regex(pattern: str):
        parts = re.split(r"(\{[a-z]+\})", pattern)
        return re.compile("^" + "".join(_PLACEHOLDER.get(p, re.escape(p)) for p in parts) + "$")

    return tuple((regex(k.pattern), k) for k in index_catalog())


def kind_of(name: str) -> IndexKind:
    """The catalogue's kind of the index ``name`` (``rail_acc_max`` → ``{layer}_acc_max``)."""
    if isinstance(name, str):
        for rx, kind in _patterns():
            if rx.match(name):
                return kind
    raise config_error("metric", name, "no such metric")


def catalog_table() -> str:
    """The catalogue as the Markdown table of docs/indices.md (one row per kind of index)."""
    rows = ["| index | unit | of | band | meaning |", "|---|---|---|---|---|"]
    cell = lambda text: text.replace("|", "\\|")  # noqa: E731 - a table cell holds no bare bar
    rows += [f"| `{k.pattern}` | {k.unit} | {k.subject} | {k.band} | {cell(k.description)} |" for k in index_catalog()]
    return "\n".join(rows) + "\n"


def metric_unit(name: str) -> str:
    """The unit of a metric (``"m/s²"`` for ``rail_acc_max``), from the core's catalogue."""
    return kind_of(name).unit


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
