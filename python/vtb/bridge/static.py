"""Static responses of the structure for the bridge check: the deck's influence lines of
deflection and bending moment at an observation point, the static effect a load train or LM71
gives there, and the deck's natural frequencies.

The influence line of the deck's deflection at x₀ for a unit force at x on the loaded layer is,
by Maxwell's reciprocity, the loaded layer's deflection at x under a unit force on the deck at
x₀: one solve of K u = s_deck(x₀), then G(x) = s_load(x)ᵀ u (K the assembled stiffness, s the
shape vectors). The bending moment's is the same with the deck's moment vector m(x₀) (−EI·w″
of the basis, the functional the core's ``deck_moment_max`` records) for s_deck(x₀): by
Betti's theorem, the deflection under the generalised force m(x₀). Every static effect on
either is a sum or an integral of G.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..analysis.eigen import assemble, layer_index, shape_matrix, spd_solver
from ..analysis.track import modes
from ..config.fields import Config
from ..errors import config_error
from .load_trains import LoadTrain, check_share, load_train

#: LM71 of EN 1991-2 §6.3.2 (Fig. 6.2): four 250 kN axles 1.6 m apart and 80 kN/m beyond
#: 0.8 m from the outer axles on either side, over any length where it is unfavourable.
LM71_AXLES = (-2.4, -0.8, 0.8, 2.4)
LM71_AXLE_LOAD = 250e3
LM71_LINE_LOAD = 80e3
LM71_CLEAR = 3.2
#: Most samples of an influence line (a 100 km structure every 0.1 m): a mistyped dx is
#: refused instead of allocating for ever.
MAX_SAMPLES = 1_000_000
#: Highest frequency (Hz) a deck's modes are sought to: far above any bridge check's band (and
#: the eigensolver's shift overflows near 1e300).
MAX_FREQUENCY = 1e5


#: What an influence line gives: the deck's deflection (m per N) or its bending moment (N·m per N).
QUANTITIES = ("deflection", "moment")


@dataclass
class InfluenceLine:
    """G(x): the deck's deflection (m, positive down) or bending moment (N·m, sagging positive;
    ``quantity``) at ``point`` (m) per newton of force at x (m) on the loaded layer ``layer``,
    sampled at ``x`` every ``dx`` over the structure and at ``point`` (where a moment's line
    has its kink)."""

    x: np.ndarray
    g: np.ndarray
    point: float
    layer: str
    dx: float
    quantity: str = "deflection"

    def train(self, train: LoadTrain, share: float = 1.0) -> float:
        """The largest static effect (m or N·m) of the train over every position of its front
        axle (every ``dx``, entering to leaving, and each axle on ``point``, where the peak of a
        line with a kink lies): max Σ P_k·G(x_front − x_k)."""
        train = load_train(train)
        share = check_share(share)
        pos = np.asarray(train.positions)
        loads = np.asarray(train.loads) * share
        fronts = np.arange(self.x[0], self.x[-1] + train.length + self.dx, self.dx)
        fronts = np.concatenate((fronts, self.point + pos))
        xs = fronts[:, None] - pos[None, :]
        g = np.interp(xs, self.x, self.g, left=0.0, right=0.0)
        return float(np.max(g @ loads))

    def lm71(self, alpha: float = 1.0, share: float = 1.0) -> float:
        """The largest static effect (m or N·m) under LM71 × ``alpha``: the axle group at every
        position (each axle on ``point`` among them), and the line load wherever G > 0 beyond
        3.2 m from the group's centre."""
        share = check_share(share)
        if isinstance(alpha, bool) or not isinstance(alpha, (int, float)) or not math.isfinite(alpha) or alpha <= 0:
            raise config_error("alpha", alpha, "LM71's classification factor must be a finite number > 0")
        positive = np.clip(self.g, 0.0, None)
        cum = np.concatenate(([0.0], np.cumsum(0.5 * (positive[1:] + positive[:-1]) * np.diff(self.x))))
        best = 0.0
        for c in np.concatenate((self.x, self.point - np.asarray(LM71_AXLES))):
            axles = LM71_AXLE_LOAD * np.sum(np.interp(c + np.asarray(LM71_AXLES), self.x, self.g, left=0.0, right=0.0))
            lo, hi = np.interp(c - LM71_CLEAR, self.x, cum, left=0.0), np.interp(c + LM71_CLEAR, self.x, cum, right=cum[-1])
            line = LM71_LINE_LOAD * (cum[-1] - (hi - lo))
            best = max(best, axles + line)
        return float(alpha * share * best)


def influence_line(config: Config, point: Optional[float] = None, layer: Optional[str] = None, dx: float = 0.25,
                   quantity: str = "deflection") -> InfluenceLine:
    """The influence line of the deck's (bottom layer's) static ``quantity`` — ``"deflection"``
    or ``"moment"`` (bending moment) — at ``point`` (m; default the first observation point) for
    a force on ``layer`` (default: the top layer, where moving forces act)."""
    length = float(config.structure.length)
    if point is None:
        point = config.output.points[0] if config.output.points else length / 2
    if isinstance(point, bool) or not (isinstance(point, (int, float)) and 0 <= point <= length):
        raise config_error("point", point, f"must lie on the structure, 0 ≤ x ≤ {length:g} m")
    if isinstance(dx, bool) or not (isinstance(dx, (int, float)) and 0 < dx <= length):
        raise config_error("dx", dx, "must be a step (m) > 0")
    if quantity not in QUANTITIES:
        raise config_error("quantity", quantity, f"must be one of {', '.join(QUANTITIES)}")
    if length / dx > MAX_SAMPLES:
        raise config_error("dx", dx, f"samples the {length:g} m structure at more than {MAX_SAMPLES} points")
    system = assemble(config)
    top = layer_index(system, layer if layer is not None else 0, "layer")
    deck = len(system.layers) - 1
    at = shape_matrix(system, deck, np.array([float(point)]), moment=quantity == "moment")
    u = np.asarray(spd_solver(system.k).solve(np.asarray(at.todense()))).ravel()
    grid = np.linspace(0.0, length, int(math.ceil(length / dx)) + 1)
    x = np.union1d(grid, [float(point)])
    g = shape_matrix(system, top, x).T @ u
    return InfluenceLine(x, np.asarray(g).ravel(), float(point), system.layers[top][0], float(grid[1] - grid[0]), quantity)


def deck_frequencies(config: Config, fmax: float = 120.0, share: float = 0.5, cluster: float = 0.03) -> np.ndarray:
    """The deck's distinct natural frequencies (Hz) below ``fmax``: the structure's modes whose
    kinetic energy lies mostly (> ``share``) in the bottom layer, the near-equal ones of
    identical spans (within ``cluster``, relative) counted once, at the lowest of each group."""
    for name, v, ok in (("fmax", fmax, lambda x: 0 < x <= MAX_FREQUENCY), ("share", share, lambda x: 0 <= x < 1),
                        ("cluster", cluster, lambda x: 0 <= x < math.inf)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not ok(v):
            raise config_error(name, v, {"fmax": f"must be a frequency (Hz) > 0 and at most {MAX_FREQUENCY:g}", "share": "must be a fraction of the kinetic energy in [0, 1)",
                                         "cluster": "must be a relative tolerance >= 0"}[name])
    found = modes(config, fmax)
    f = found.frequencies[(found.layer_energy(len(found.layers) - 1) > share) & (found.frequencies > 0)]
    out: list = []
    for v in f:
        if not out or v > out[-1] * (1 + cluster):
            out.append(float(v))
    return np.asarray(out)
