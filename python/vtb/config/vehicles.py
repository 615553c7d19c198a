"""Vehicles as configuration classes, one per model of the core (``VehicleConfig``): each
carries its model's own parameters and the wheels' fields, and ``VEHICLE_MODELS`` picks the
class of a table by its ``model`` tag (docs/vehicles.md)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Literal, Optional

from . import gateway
from ..errors import config_error
from .schema import StrictFields
from .schema import default as _default
from .schema import documented


class _Wheeled:
    """What every vehicle model's class shares: its layout in a run's records."""

    @property
    def dofs(self) -> tuple:
        """Names of the model's DOFs, in the order of ``Result.vehicle_disp``."""
        return tuple(gateway.vehicle_models()[self.model][0])

    @property
    def n_wheels(self) -> int:
        """Wheels of the model (the columns of ``Result.contact_force`` per vehicle)."""
        return gateway.vehicle_models()[self.model][1]


@documented("VehicleConfig.car")
@dataclass
class Vehicle(_Wheeled, StrictFields):
    """Zhai's 10-DOF car (docs/vehicles.md): secondary suspension per bogie, primary per
    wheelset (both sides lumped). The modelled top layer is one of ``rails`` identical rails,
    so it carries 1/``rails`` of every axle load. A quarter car is :class:`QuarterCar`
    (:meth:`quarter_car` builds one)."""

    m_c: float
    j_c: float
    m_t: float
    j_t: float
    m_w: float
    k_s: float
    c_s: float
    k_p: float
    c_p: float
    l_c: float
    l_t: float
    wheel_radius: float
    x_front: float
    contact_constant: Optional[float] = _default("VehicleConfig.car", "contact_constant")
    rails: int = _default("VehicleConfig.car", "rails")
    contact_patch: bool = _default("VehicleConfig.car", "contact_patch")
    rail_crown_radius: float = _default("VehicleConfig.car", "rail_crown_radius")
    model: Literal["car"] = _default("VehicleConfig.car", "model")

    @staticmethod
    def quarter_car(sprung_mass: float, wheel_mass: float, stiffness: float, damping: float,
                    x_front: float, wheel_radius: float = 0.46, **kw) -> "QuarterCar":
        """A quarter car: ``sprung_mass`` (kg) on a spring ``stiffness`` (N/m) ∥ dashpot
        ``damping`` (N·s/m) over one wheel of ``wheel_mass`` (kg) at ``x_front`` (m) at t = 0;
        ``kw`` sets the contact fields (``rails``, ``contact_patch``, ...)."""
        return QuarterCar(m_c=sprung_mass, m_w=wheel_mass, k_p=stiffness, c_p=damping, x_front=x_front,
                          wheel_radius=wheel_radius, **kw)

    @property
    def length(self) -> float:
        """Distance from the leading to the trailing wheel (m)."""
        return 2.0 * (self.l_c + self.l_t)


@documented("VehicleConfig.quarter_car")
@dataclass
class QuarterCar(_Wheeled, StrictFields):
    """A quarter car (docs/vehicles.md): a sprung mass ``m_c`` on ``k_p`` ∥ ``c_p`` over one
    wheel ``m_w``."""

    m_c: float
    m_w: float
    k_p: float
    c_p: float
    wheel_radius: float
    x_front: float
    contact_constant: Optional[float] = _default("VehicleConfig.quarter_car", "contact_constant")
    rails: int = _default("VehicleConfig.quarter_car", "rails")
    contact_patch: bool = _default("VehicleConfig.quarter_car", "contact_patch")
    rail_crown_radius: float = _default("VehicleConfig.quarter_car", "rail_crown_radius")
    model: Literal["quarter_car"] = "quarter_car"

    @property
    def length(self) -> float:
        """Distance from the leading to the trailing wheel (m): one wheel."""
        return 0.0


#: The class of each vehicle model, by its ``model`` tag.
VEHICLE_MODELS = {"car": Vehicle, "quarter_car": QuarterCar}


#: The car's own fields, which a quarter car written by vtb before the tagged vehicles held at 0.
_CAR_ONLY = ("j_c", "m_t", "j_t", "k_s", "c_s", "l_c", "l_t")


def vehicle_table(data, path: str) -> tuple:
    """The class of a vehicle table by its ``model`` tag (``"car"`` when absent), and the table.
    A quarter car written before each model carried only its own fields has the car's at 0:
    they are dropped with a :class:`DeprecationWarning`."""
    if not isinstance(data, dict):
        return Vehicle, data
    model = data.get("model", "car")
    cls = VEHICLE_MODELS.get(model) if isinstance(model, str) else None
    if cls is None:
        raise config_error(f"{path}.model", model, f"must be one of {list(VEHICLE_MODELS)}")
    zeros = [k for k in _CAR_ONLY if cls is QuarterCar and data.get(k) == 0]
    if zeros:
        warnings.warn(f"{path}: a quarter car carries only its own fields; dropped the car's {', '.join(zeros)} "
                      "(all 0): remove them from the file", DeprecationWarning, stacklevel=4)
        data = {k: v for k, v in data.items() if k not in zeros}
    return cls, data
