"""The substructured engine's reductions: a finite-element structure with
``discretisation.substructure_cutoff`` cut into substructures and reduced
(:mod:`vtb.analysis.substructures`, docs/substructures.md), built once per structure in a
process and handed to the core, which steps it by Newmark with the vehicles, the contact and
the dampers as on the finite elements.

The reduction keeps each distinct interior's fixed-interface modes below the cut-off and every
DOF on the cuts; the dampers are not part of it (the core stamps them on its shapes), so the
designs of a damper study share one. A build costs the distinct substructures' eigensolves —
as many for 100 equal spans as for 5 — plus work linear in the length.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import threading
import time

from threadpoolctl import threadpool_limits

from ..analysis.eigen import assemble, core_substructures
from ..analysis.substructures import Substructuring, reduce, residual_bands
from ..config.fields import Config, structure_json
from ..errors import config_error

#: Reductions built in this process, by the structure's key (the core's copies alongside).
_MEMORY: dict = {}
_LOCK = threading.Lock()


@dataclasses.dataclass
class Built:
    """A structure's substructured reduction and its core copy."""

    substructuring: Substructuring
    core: object
    seconds: float

    def to_core(self):
        return self.core


def _structure(config: Config) -> Config:
    """The configuration whose structure is reduced: without its dampers (stamped by the core)."""
    return dataclasses.replace(config, dampers=[])


def reduction(config: Config, progress="auto") -> Built:
    """The substructured reduction of ``config``'s structure (built on first use in this
    process, then shared). ``progress``: ``"auto"`` announces a build on stderr and shows a tqdm
    bar of its substructures once it has lasted 2 s, on a terminal only; ``True`` anywhere;
    ``False`` neither.

    Raises :class:`vtb.ConfigError` naming ``discretisation.substructure_cutoff`` when it is not
    set or not a finite frequency > 0, or when the structure cannot be cut (a modal or hybrid
    layer)."""
    fc = config.discretisation.substructure_cutoff
    if fc is None or isinstance(fc, bool) or not isinstance(fc, (int, float)) or not (math.isfinite(fc) and fc > 0):
        raise config_error("discretisation.substructure_cutoff", fc, "must be a finite cut-off > 0 (Hz)")
    if config.discretisation.method != "fem":
        raise config_error("discretisation.method", config.discretisation.method, "substructures reduce a finite-element structure (\"fem\")")
    cfg = _structure(config)
    key = (structure_json(cfg), float(fc))
    with _LOCK:
        if key in _MEMORY:
            return _MEMORY[key]
        t0 = time.perf_counter()
        system = assemble(cfg)
        show = progress is True or (progress == "auto" and hasattr(sys.stderr, "isatty") and sys.stderr.isatty())
        if progress is not False:
            print(f"vtb: reducing this structure ({system.n} DOFs) to substructures below {fc:g} Hz once in this process",
                  file=sys.stderr, flush=True)
        bar = None
        if show:
            from tqdm.auto import tqdm

            bar = tqdm(desc="vtb substructures", unit="substructure", file=sys.stderr, delay=0.0 if progress is True else 2.0)

        def note(done: int, total: int) -> None:
            bar.total = total
            bar.update(done - bar.n)

        # One BLAS thread: OpenBLAS splits its sums by thread count, and a build must give the
        # same bits in every process (as the synthesis' does, vtb.run.synthesis.build).
        try:
            with threadpool_limits(limits=1):
                sub = reduce(system, float(fc), ratio=1.0, progress=note if bar is not None else None)
                if sub is not None:
                    residual_bands(system, sub)
                    c = sub.project(system.c)
        finally:
            if bar is not None:
                bar.close()
        if sub is None:
            raise config_error("discretisation.substructure_cutoff", fc, "the structure cannot be cut into substructures (every layer must be finite elements)")
        built = Built(sub, core_substructures(sub, c), time.perf_counter() - t0)
        _MEMORY[key] = built
        return built
