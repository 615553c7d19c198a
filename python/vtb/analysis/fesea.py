"""The FE–SEA hybrid correction of the rail, as a report (docs/fesea.md).

The hybrid method keeps the rail's first ``modes`` sines (plus its four cubic functions) in the
time-domain model and condenses the next ``local_modes`` sines — the *local modes* — into
corrections ΔM, ΔK, ΔC of the rail's cubic DOFs and into force terms, at a representative
excitation frequency ω_r with the resonant band B = [ω_r·2^(−1/6), ω_r·2^(1/6)].
:func:`fesea_report` shows what the correction is for a configuration: each local mode's
frequency, loss factor and class (below, resonant or above B), the modal density in B and the
correction matrices.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import gateway
from ..config.fields import Config
from ..config.prepare import prepare


@dataclass
class FeSeaReport:
    """The FE–SEA correction of one configuration.

    ``omega_r`` (rad/s) and ``band`` (rad/s, the resonant band B); ``modal_density`` (local
    modes per rad/s in B); ``coupling`` (``"full"`` or ``"mass"``); ``delta_m`` (kg),
    ``delta_k`` (N/m), ``delta_c`` (N·s/m): 4×4 corrections on the rail's cubic DOFs g1..g4
    (structure DOFs ``dofs``); ``modes``: numpy columns ``index`` (sine number n),
    ``frequency`` (Hz), ``omega`` (rad/s), ``mass`` (kg), ``stiffness`` (N/m), ``damping``
    (N·s/m), ``loss_factor`` (η = c/(m·ω)) and ``class`` (``"below"``, ``"resonant"``,
    ``"above"``).
    """

    omega_r: float
    band: tuple
    modal_density: float
    coupling: str
    dofs: list
    delta_m: np.ndarray
    delta_k: np.ndarray
    delta_c: np.ndarray
    modes: dict

    def counts(self) -> dict:
        """Number of local modes per class."""
        cls = list(self.modes["class"])
        return {c: cls.count(c) for c in ("below", "resonant", "above")}

    def to_pandas(self):
        """The local modes as a :class:`pandas.DataFrame` (needs pandas: the ``vtb[io]`` extra)."""
        from ..run.tables import require_pandas

        return require_pandas().DataFrame({k: list(v) if k == "class" else np.asarray(v) for k, v in self.modes.items()})

    def __str__(self) -> str:
        f_r = self.omega_r / (2 * np.pi)
        lo, hi = (w / (2 * np.pi) for w in self.band)
        c = self.counts()
        lines = [
            f"FE–SEA correction ({self.coupling} coupling): f_r = {f_r:.1f} Hz, band {lo:.1f}–{hi:.1f} Hz, "
            f"{c['below']} below / {c['resonant']} resonant / {c['above']} above, "
            f"modal density {self.modal_density * 2 * np.pi:.3f} modes/Hz",
            f"{'n':>5} {'f (Hz)':>9} {'loss factor':>12} {'class':>9}",
        ]
        for n, f, eta, k in zip(self.modes["index"], self.modes["frequency"], self.modes["loss_factor"], self.modes["class"]):
            lines.append(f"{n:>5} {f:>9.1f} {eta:>12.4f} {k:>9}")
        return "\n".join(lines)


def fesea_report(config: Config) -> FeSeaReport:
    """The FE–SEA correction of a hybrid configuration (``config.discretisation.method ==
    "hybrid"``); raises :class:`~vtb.errors.ConfigError` for other methods."""
    text, _ = prepare(config)
    d = gateway.fesea(text)
    return FeSeaReport(
        omega_r=d["omega_r"],
        band=tuple(d["band"]),
        modal_density=d["modal_density"],
        coupling=d["coupling"],
        dofs=list(d["dofs"]),
        delta_m=np.asarray(d["delta_m"]),
        delta_k=np.asarray(d["delta_k"]),
        delta_c=np.asarray(d["delta_c"]),
        modes={k: (np.asarray(v) if k != "class" else list(v)) for k, v in d["modes"].items()},
    )
