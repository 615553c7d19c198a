"""Load trains: trains as rows of constant axle forces, for the moving-load analyses of
EN 1991-2 §6.4.6.

A :class:`LoadTrain` is a list of axles — positions (m, the first axle at 0 and the others
behind it) and loads (N, one axle of the whole train on both rails) — and what the check needs
to know of it: its name, where its numbers come from and its regular spacing D (m), from which
the resonant speeds n0·D/i follow. :func:`load_train` makes one by name:

- ``"HSLM-A1"`` … ``"HSLM-A10"``: the ten trains of the high-speed load model of EN 1991-2
  §6.4.6.1.1 (Fig. 6.12, Table 6.3): N coaches of length D on articulated bogies with axle
  spacing d, axle load P, a power car and an end coach at each end, 2N + 14 axles;
- ``"HSLM-B"``: N forces of 170 kN at a spacing d (§6.4.6.1.1, Fig. 6.13, for spans below
  7 m); N and d are read from Fig. 6.13 for the span by the user (``n=``, ``d=``), because this
  module does not encode that figure;
- the library's real trains (:func:`vtb.trains`): each car's axle load from its masses,
  (m_c/4 + m_t/2 + m_w)·g, at its wheelsets' positions in the formation;
- a CSV file of ``position, load`` rows (m, N): :func:`read_load_train`.

:func:`load_trains` lists the named ones with their sources, and :func:`apply_load_train`
makes a train the moving forces of any configuration.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional, Sequence, Union

import numpy as np

from ..config.fields import Config, MovingForce
from ..config.schema import properties
from ..config.trains import train as library_train
from ..config.trains import trains as library_trains
from ..errors import config_error

#: EN 1991-2 Table 6.3 (Annex E): the ten HSLM-A trains as (N coaches, coach length D in m,
#: bogie axle spacing d in m, axle load P in kN).
HSLM_A = {
    1: (18, 18.0, 2.0, 170.0), 2: (17, 19.0, 3.5, 200.0), 3: (16, 20.0, 2.0, 180.0), 4: (15, 21.0, 3.0, 190.0),
    5: (14, 22.0, 2.0, 170.0), 6: (13, 23.0, 2.0, 180.0), 7: (13, 24.0, 2.0, 190.0), 8: (12, 25.0, 2.5, 190.0),
    9: (11, 26.0, 2.0, 210.0), 10: (11, 27.0, 2.0, 210.0),
}
#: The power car's axles (m from the train's front) and its distance to the end coach's first
#: axle: EN 1991-2 Fig. 6.12 (3 m + 11 m + 3 m, then 3.525 m).
POWER_CAR = (0.0, 3.0, 14.0, 17.0)
END_COACH_FIRST_AXLE = 20.525
#: How far the first articulated bogie's centre stands behind the end coach's first axle, less
#: one coach length: Fig. 6.12 (the end coach is D − 1.7625 m + its bogie's d/2 long
#: between its bogie centre and the first articulated bogie's).
ARTICULATION = -1.7625
HSLM_SOURCE = ("EN 1991-2:2003 §6.4.6.1.1, Table 6.3 and Fig. 6.12 (Annex E): HSLM-A{i}, N = {n} coaches of "
               "D = {D:g} m, bogie axle spacing d = {d:g} m, P = {P:g} kN")
HSLM_B_LOAD = 170e3
#: Most axles a load train may have: a 2 km freight train has some 300; the limit keeps a
#: mistyped count (HSLM-B's n, a user's table) from building a table for minutes.
MAX_AXLES = 10_000
GRAVITY = float(properties("SolverConfig")["gravity"]["default"])


@dataclass(frozen=True)
class LoadTrain:
    """A train of constant axle forces.

    Attributes
    ----------
    name
        What :func:`load_train` takes (or the CSV file's stem).
    positions
        Axle positions (m) along the train, the first axle at 0, increasing towards the rear.
    loads
        Axle loads (N, positive downward), one per position, of the whole axle (both rails).
    source
        Where the numbers come from.
    spacing
        The regular spacing D (m) of its axle groups (coach length), from which the resonant
        speeds v_i = n0·D/i follow; ``None`` when the train has none.
    """

    name: str
    positions: tuple
    loads: tuple
    source: str
    spacing: Optional[float] = None
    title: str = field(default="", compare=False)

    def __post_init__(self):
        # a user's table is checked as a CSV file's rows are: a bad axle fails here, not as a
        # NaN or a TypeError deep in a scan
        positions, loads = _axles("positions", self.positions), _axles("loads", self.loads)
        if not positions:
            raise config_error("positions", self.positions, "a load train needs at least one axle")
        if len(loads) != len(positions):
            raise config_error("loads", self.loads, f"needs one load per position ({len(positions)})")
        if any(b < a for a, b in zip(positions, positions[1:])):
            raise config_error("positions", self.positions, "positions must increase from the first axle to the last")
        if any(p <= 0 for p in loads):
            raise config_error("loads", self.loads, "axle loads (N) must be > 0")
        if self.spacing is not None:
            _finite_number("spacing", self.spacing, "must be a length (m) > 0", positive=True)
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "loads", loads)

    @property
    def length(self) -> float:
        """Distance (m) from the first to the last axle."""
        return float(self.positions[-1] - self.positions[0])

    @property
    def axles(self) -> int:
        """Number of axles."""
        return len(self.positions)

    def forces(self, x_front: float = 0.0, layer: Optional[str] = None, share: float = 1.0) -> list:
        """The axles as :class:`vtb.MovingForce` s, the first at ``x_front`` (m) and the others
        behind it, each carrying ``share`` of its axle load (N): 1 when the structure is the
        whole deck under one track, 1/2 when it models one of two rails (``Vehicle.rails``)."""
        check_share(share)
        _finite_number("x_front", x_front, "must be a position (m)")
        if layer is not None and not isinstance(layer, str):
            raise config_error("layer", layer, "must be a layer's name, or None for the top layer")
        return [MovingForce(float(p) * share, float(x_front) - float(x), layer) for x, p in zip(self.positions, self.loads)]


def _finite_number(name: str, v, why: str, positive: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v) or (positive and v <= 0):
        raise config_error(name, v, why)
    return float(v)


def _axles(name: str, values) -> tuple:
    """``values`` as a tuple of finite floats, or a ConfigError naming ``name``."""
    if isinstance(values, (str, bytes, dict)) or not hasattr(values, "__len__"):
        raise config_error(name, values, "expected a sequence of numbers, one per axle")
    if len(values) > MAX_AXLES:
        raise config_error(name, f"{len(values)} axles", f"a load train has at most {MAX_AXLES} axles")
    return tuple(_finite_number(f"{name}[{i}]", v, "must be a finite number") for i, v in enumerate(values))


def check_share(share) -> float:
    """``share`` of an axle load on the modelled track, in (0, 1], or a ConfigError."""
    if isinstance(share, bool) or not isinstance(share, (int, float)) or not 0 < share <= 1:
        raise config_error("share", share, "must be a fraction of the axle load in (0, 1]")
    return float(share)


def hslm_a(i: int) -> LoadTrain:
    """HSLM-A``i`` (i = 1 … 10) of EN 1991-2 Fig. 6.12: its 2N + 14 axles front to rear.

    Front: the power car's four axles (0, 3, 14, 17 m) and the end coach's leading bogie (d
    apart from 20.525 m); then N + 1 articulated bogies of two axles d apart, their centres D
    apart, the first at 20.525 + D − 1.7625 m; the rear mirrors the front (the train is
    symmetric, 37.525 + (N + 2)·D m long)."""
    if isinstance(i, bool) or not isinstance(i, int) or i not in HSLM_A:
        raise config_error("name", f"HSLM-A{i}", "HSLM-A trains are numbered 1 to 10")
    n, coach, d, p = HSLM_A[i]
    total = 37.525 + (n + 2) * coach
    front = [*POWER_CAR, END_COACH_FIRST_AXLE, END_COACH_FIRST_AXLE + d]
    first = END_COACH_FIRST_AXLE + coach + ARTICULATION
    middle = [c + s * d / 2 for k in range(n + 1) for c in [first + k * coach] for s in (-1, 1)]
    positions = front + middle + [total - x for x in reversed(front)]
    return LoadTrain(f"HSLM-A{i}", tuple(positions), (p * 1e3,) * len(positions), HSLM_SOURCE.format(i=i, n=n, D=coach, d=d, P=p),
                     spacing=coach, title=f"HSLM-A{i}")


def hslm_b(n: int, d: float) -> LoadTrain:
    """HSLM-B of EN 1991-2 §6.4.6.1.1: ``n`` point forces of 170 kN at a uniform spacing ``d``
    (m), both read by the user from Fig. 6.13 for the span L (< 7 m) under check."""
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_AXLES:
        raise config_error("n", n, f"HSLM-B needs its number of forces N (a whole number from 1 to {MAX_AXLES}, from EN 1991-2 Fig. 6.13)")
    if isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d) or d <= 0:
        raise config_error("d", d, "HSLM-B needs its force spacing d (m > 0, from EN 1991-2 Fig. 6.13)")
    return LoadTrain("HSLM-B", tuple(k * float(d) for k in range(n)), (HSLM_B_LOAD,) * n,
                     f"EN 1991-2:2003 §6.4.6.1.1, Fig. 6.13: HSLM-B, N = {n} forces of 170 kN at d = {d:g} m (N and d as read by the user)",
                     spacing=float(d), title="HSLM-B")


def library_load_train(name: str, cars: Optional[int] = None) -> LoadTrain:
    """A train of the library (:func:`vtb.trains`) as axle forces: each wheelset of each car
    carries (m_c/4 + m_t/2 + m_w)·g (N), the car body's weight shared by its four axles and
    each bogie's by its two, at the wheelsets' positions in the formation (``cars``: as
    :func:`vtb.train`). Its spacing D is the most common car length."""
    vehicles = library_train(name, cars=cars)
    x0 = vehicles[0].x_front
    xs, ps = [], []
    for v in vehicles:
        load = (v.m_c / 4 + v.m_t / 2 + v.m_w) * GRAVITY
        for offset in (0.0, 2 * v.l_t, 2 * v.l_c, 2 * v.l_c + 2 * v.l_t):
            xs.append(x0 - (v.x_front - offset))
            ps.append(load)
    order = np.argsort(xs, kind="stable")
    info = library_trains()[name]
    lengths = [round(length, 6) for length in info.lengths]
    spacing = max(set(lengths), key=lengths.count)
    return LoadTrain(name, tuple(float(xs[i]) for i in order), tuple(float(ps[i]) for i in order),
                     f"{info.title}: {info.source}; axle loads (m_c/4 + m_t/2 + m_w)·g of each car", spacing=float(spacing),
                     title=info.title)


def read_load_train(path: Union[str, Path], name: Optional[str] = None, spacing: Optional[float] = None) -> LoadTrain:
    """A user's train from a CSV file of ``position, load`` rows (m, N; a header row of text
    is skipped; positions shifted so that the first axle is at 0). ``spacing``: its regular
    spacing D (m), if it has one. A missing file, a malformed row, a non-finite or negative
    value or unsorted positions raise :class:`vtb.ConfigError` naming the file, row and value."""
    p = Path(path)
    if not p.is_file():
        raise config_error("path", str(p), "no such CSV file of axle positions and loads")
    xs, ps = [], []
    with p.open(newline="") as f:
        for row_no, row in enumerate(csv.reader(f), start=1):
            cells = [c.strip() for c in row if c.strip()]
            if not cells or cells[0].startswith("#"):
                continue
            try:
                x, load = (float(c) for c in cells[:2]) if len(cells) >= 2 else (math.nan, math.nan)
            except ValueError:
                if row_no == 1 and not xs:
                    continue  # the header
                raise config_error(f"{p.name}:{row_no}", ",".join(row), "expected two numbers: position (m), load (N)") from None
            if len(cells) != 2 or not (math.isfinite(x) and math.isfinite(load)) or load <= 0:
                raise config_error(f"{p.name}:{row_no}", ",".join(row), "expected a finite position (m) and a load (N) > 0")
            if xs and x < xs[-1]:
                raise config_error(f"{p.name}:{row_no}", x, "positions must increase from the first axle to the last")
            xs.append(x)
            ps.append(load)
    if not xs:
        raise config_error("path", str(p), "has no axle rows (position, load)")
    if spacing is not None and (isinstance(spacing, bool) or not isinstance(spacing, (int, float)) or not spacing > 0):
        raise config_error("spacing", spacing, "must be a length (m) > 0")
    return LoadTrain(name or p.stem, tuple(x - xs[0] for x in xs), tuple(ps), f"user file {p.name}", spacing=spacing, title=name or p.stem)


def load_train(name: Union[str, LoadTrain], *, n: Optional[int] = None, d: Optional[float] = None, cars: Optional[int] = None) -> LoadTrain:
    """A load train by name: ``"HSLM-A1"`` … ``"HSLM-A10"``, ``"HSLM-B"`` (with ``n`` and
    ``d`` read from EN 1991-2 Fig. 6.13), a train of the library (``"crh3"``, ``"velaro_e"``;
    ``cars`` as :func:`vtb.train`), or a path to a CSV file (``*.csv``). A :class:`LoadTrain`
    is returned as it is. An unknown name raises :class:`vtb.ConfigError` listing the known."""
    if isinstance(name, LoadTrain):
        return name
    if not isinstance(name, (str, Path)):
        raise config_error("name", name, "expected a train's name or a CSV file's path")
    text = str(name)
    if text.upper().startswith("HSLM-A"):
        tail = text[6:]
        if not tail.isdigit():
            raise config_error("name", text, "HSLM-A trains are HSLM-A1 to HSLM-A10")
        return hslm_a(int(tail))
    if text.upper() == "HSLM-B":
        if n is None or d is None:
            raise config_error("name", text, "HSLM-B needs n and d (its number of forces and their spacing for the span, from EN 1991-2 Fig. 6.13)")
        return hslm_b(n, d)
    if text.lower().endswith(".csv"):
        return read_load_train(text)
    if text in library_trains():
        return library_load_train(text, cars=cars)
    raise config_error("name", text, f"unknown load train (known: {', '.join(load_trains())}, 'HSLM-B', or a CSV file)")


def load_trains() -> dict:
    """The named load trains: name → source (the HSLM-A trains and the library's trains;
    HSLM-B and CSV files take parameters)."""
    out = {f"HSLM-A{i}": HSLM_SOURCE.format(i=i, n=n, D=D, d=d, P=P) for i, (n, D, d, P) in HSLM_A.items()}
    for name, info in library_trains().items():
        out[name] = f"{info.title}: {info.source}; axle loads from the cars' masses"
    return out


def apply_load_train(config: Config, train: Union[str, LoadTrain], share: float = 1.0, layer: Optional[str] = None,
                     tail: Optional[float] = None, gap: float = 0.0) -> Config:
    """A copy of ``config`` loaded by ``train`` alone (its moving forces; no vehicles): the
    first axle at x = −``gap`` (m) at t = 0, so that the train enters the structure from its
    start, and the run ends ``tail`` (s; default: the config's, or 0) after the last axle has
    left it. ``share`` and ``layer``: as :meth:`LoadTrain.forces`."""
    t = load_train(train)
    if isinstance(gap, bool) or not isinstance(gap, (int, float)) or not math.isfinite(gap) or gap < 0:
        raise config_error("gap", gap, "must be a distance (m) >= 0")
    if tail is not None and (_finite_number("tail", tail, "must be a duration (s) >= 0") < 0):
        raise config_error("tail", tail, "must be a duration (s) >= 0")
    out = config.copy()
    out.vehicles = []
    out.forces = t.forces(-float(gap), layer, share)
    out.solver.t_end = None
    out.solver.tail = float(tail) if tail is not None else (out.solver.tail if out.solver.tail is not None else 0.0)
    return out


def resonant_speeds(frequency: float, spacing: float, v_max: float, orders: Sequence[int] = range(1, 11)) -> list:
    """The resonant speeds v_i = n0·D/i (m/s) up to ``v_max``: the i-th is the speed at which
    the axle groups D (m) apart pass every i periods of the frequency n0 (Hz)."""
    for name, v in (("frequency", frequency), ("spacing", spacing), ("v_max", v_max)):
        _finite_number(name, v, "must be a finite number > 0", positive=True)
    if isinstance(orders, (str, bytes)) or not all(isinstance(i, int) and not isinstance(i, bool) and i >= 1 for i in orders):
        raise config_error("orders", orders, "must be whole numbers >= 1")
    return [frequency * spacing / i for i in orders if frequency * spacing / i <= v_max]
