"""The wheel–rail contact (docs/model.md §4): the Hertz contact patch of the distributed contact
(``Vehicle.contact_patch``)."""

from __future__ import annotations

from ..config import gateway
from ..config.schema import default


def contact_patch_half_length(load: float, wheel_radius: float, rail_crown_radius: float = default("VehicleConfig.car", "rail_crown_radius")) -> float:
    """Half-length (m) along the rail of the Hertz contact ellipse of a steel wheel of rolling
    radius ``wheel_radius`` (m) on a steel rail head of crown radius ``rail_crown_radius`` (m)
    under ``load`` (N): the patch a wheel spreads its force over with
    ``Vehicle.contact_patch`` (there, of its static load). 6.42 mm for 72 kN on a 0.46 m
    wheel and a 0.3 m crown. Raises :class:`vtb.ConfigError` naming a non-positive or
    non-finite argument."""
    return gateway.patch_half_length(load, wheel_radius, rail_crown_radius)
