"""The core's word on a configuration, without running it: the one module of :mod:`vtb.config`
that calls the compiled core (``vtb._core``; its bindings ``api/config.rs`` and the structure's
bands, FE–SEA figures and contact patch).

Functions take the core JSON of a configuration (:meth:`vtb.Config.to_core_json`) and raise
:class:`vtb.ConfigError` naming the field at fault.
"""

from __future__ import annotations

import json

from .. import _core

#: The version of the compiled core (and of vtb).
__version__: str = _core.__version__
#: The results epoch of the core: raised by every change that alters a run's results, and only
#: then; journals and checkpoints carry it and a resume across two epochs is refused.
RESULTS_EPOCH: int = _core.RESULTS_EPOCH

#: Shares of the synthesis and the substructure cut-offs the model resolves (the core's,
#: model/resolution.rs).
SYNTHESIS_BAND_SHARE: float = _core.SYNTHESIS_BAND_SHARE
SUBSTRUCTURE_BAND_SHARE: float = _core.SUBSTRUCTURE_BAND_SHARE


def schema() -> dict:
    """The core's JSON schema of a configuration: every field, type, default and description."""
    return json.loads(_core.schema())


def check_schema(text: str) -> None:
    """Types and ranges of every field, by the schema (the values are checked by :func:`validate`)."""
    _core.check_schema(text)


def check_plausible(text: str) -> None:
    """Every physical field within its plausible range (a likely unit mistake is named)."""
    _core.check_plausible(text)


def validate(text: str, *profile, full: bool = False) -> None:
    """The core's whole validation of a run, against its sampled irregularity ``profile``
    (:meth:`vtb.config.prepare.SampledProfile.core_args`) when given; ``full``: the run records
    full histories (:func:`vtb.simulate`), which must fit the memory budget too."""
    _core.validate(text, *profile, full=full)


def plausible_ranges() -> list:
    """(field, min, max, unit, what it covers) of every physical field the core checks."""
    return list(_core.plausible_ranges())


def vehicle_models() -> dict:
    """model name → (the names of its DOFs, its number of wheels)."""
    return _core.vehicle_models()


def train_library() -> list:
    """The core's library of trains, as plain dicts."""
    return json.loads(_core.train_library())


def preset(name: str) -> dict:
    """A preset configuration of the core (``"paper"``, ``"paper_converged"``, ``"paper_fast"``) as a plain dict."""
    return json.loads(_core.preset(name))


def wheel_travel(text: str):
    """(first, last) position the wheels of a run reach (m), or ``None`` without wheels."""
    return _core.wheel_travel(text)


def index_names(text: str) -> list:
    """Every index a run of the configuration reports, in the core's order."""
    return list(_core.index_names(text))


def index_catalog() -> list:
    """The core's index catalogue: one ``(pattern, unit, subject, band, description)`` row per
    kind of index."""
    return list(_core.index_catalog())


def model_key(text: str) -> str:
    """What the assembled model of a configuration depends on: runs with one key share it."""
    return _core.model_key(text)


def resolved_bands(structure_text: str) -> tuple:
    """([band of each layer as a dict], the rail's pinned–pinned frequency or ``None``) of a
    structure-only configuration (:func:`vtb.config.fields.structure_json`)."""
    return _core.resolved_bands(structure_text)


def fesea(text: str) -> dict:
    """The FE–SEA figures of a hybrid configuration (:func:`vtb.fesea_report`)."""
    return _core.fesea(text)


def patch_half_length(load: float, wheel_radius: float, rail_crown_radius: float) -> float:
    """Half the length of the Hertz contact patch (m) under a wheel load (N)."""
    return _core.patch_half_length(float(load), float(wheel_radius), float(rail_crown_radius))
