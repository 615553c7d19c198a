"""Running configurations: :func:`simulate` for one run, :func:`simulate_batch` for many in
parallel inside the Rust core (all cores, GIL released)."""

from __future__ import annotations

import dataclasses
import sys
import warnings
from dataclasses import dataclass
from typing import Callable, Optional, Sequence, Union

import numpy as np

from .. import _core
from ..analysis.comfort import iso2631, sperling
from ..analysis.spectra import psd, third_octave, welch_third_octave
from ..config import args, gateway
from ..config.fields import Config, structure_json
from ..config.prepare import prepare
from ..config.resolution import warn_beyond
from ..errors import VtbError, config_error
from .indices import metric_unit
from . import substructures
from .synthesis import check_build, in_memory, reduction
from .tables import frame, to_parquet


@dataclass(eq=False)
class Result:
    """Histories of one run, sampled at ``t`` (s).

    Arrays (numpy), all in SI units:

    * ``disp`` (m) and ``acc`` (m/s²): shape (n_t, n_layers, n_points) — vertical displacement
      (positive down, measured from the unloaded structure, so the static deflection under
      the wheels is included) and acceleration of each layer at each observation point;
    * ``vehicle_disp`` (m, rad) and ``vehicle_acc`` (m/s², rad/s²): shape (n_t, n_cars, n_dofs),
      the DOFs of the run's vehicle model (``config.vehicles[0].dofs``: [Z_c, β_c, Z_t1, β_t1,
      Z_t2, β_t2, Z_w1..Z_w4] for the 10-DOF car, [Z_c, Z_w] for a quarter car), displacements
      relative to the static equilibrium at t = 0;
    * ``contact_force`` (N): shape (n_t, n_wheels), force on the modelled rail per wheel;
    * ``pad_force`` (N): shape (n_t, n_pads), with ``output.pad_forces`` the force (spring and
      dashpot, compression positive) in the rail fastener nearest each observation point, else
      shape (n_t, 0);
    * ``contact_loss``: list of (wheel, t_start, t_end or None) periods without contact.
    """

    t: np.ndarray
    disp: np.ndarray
    acc: np.ndarray
    vehicle_disp: np.ndarray
    vehicle_acc: np.ndarray
    contact_force: np.ndarray
    pad_force: np.ndarray
    contact_loss: list
    layer_names: list
    points: list
    config: Config
    _metrics: dict

    def metrics(self) -> dict[str, float]:
        """Indices in SI units at the first observation point (docs/model.md §8):

        ``{layer}_disp_max`` (m), ``{layer}_acc_max`` (m/s²), ``{layer}_acc_rms`` (m/s²),
        ``{layer}_acc_settle`` (s, time after which ``|a|`` stays below 5 % of its peak) for each
        layer; ``car_disp_max`` (m), ``car_acc_max``, ``car_acc_rms`` (m/s²) of the first car
        body; ``contact_force_max``/``_min`` (N) and ``contact_loss_events``.

        With ``output.band_limit`` (Hz) every acceleration index is that of the record low-passed
        at the band limit (:func:`vtb.low_pass`) and each layer's raw peak is kept as
        ``{layer}_acc_max_raw`` (m/s²).
        """
        return dict(self._metrics)

    #: The array fields compared by value in ``==``.
    _ARRAYS = ("t", "disp", "acc", "vehicle_disp", "vehicle_acc", "contact_force", "pad_force")

    def __eq__(self, other) -> bool:
        """Equal by value: the same configuration, the same histories bit for bit (``np.array_equal``),
        contact-loss periods, layers, points and metrics. A result is mutable: it has no hash."""
        if not isinstance(other, Result):
            return NotImplemented
        return (all(np.array_equal(getattr(self, f), getattr(other, f)) for f in self._ARRAYS)
                and self.contact_loss == other.contact_loss and list(self.layer_names) == list(other.layer_names)
                and list(self.points) == list(other.points) and self._metrics == other._metrics and self.config == other.config)

    __hash__ = None

    def to_pandas(self):
        """The histories as a :class:`pandas.DataFrame` indexed by ``t`` (s): per layer and
        observation point ``{layer}_disp@{x}`` (m) and ``{layer}_acc@{x}`` (m/s²); per car
        ``car{i}_{dof}`` displacement (m or rad, relative to the static state) and
        ``car{i}_{dof}_acc`` (m/s² or rad/s²) for the DOFs of the vehicle model
        (``config.vehicles[0].dofs``); ``contact_force_{w}`` (N) per wheel. Units in ``attrs["units"]``
        (needs pandas)."""
        cols, units = {}, {}
        for li, name in enumerate(self.layer_names):
            for pi, x in enumerate(self.points):
                for q, arr, unit in (("disp", self.disp, "m"), ("acc", self.acc, "m/s²")):
                    key = f"{name}_{q}@{x:g}"
                    cols[key], units[key] = arr[:, li, pi], unit
        for ci in range(self.vehicle_disp.shape[1]):
            for di, dof in enumerate(self.config.vehicles[0].dofs):
                rot = dof.startswith("beta")
                for key, arr, unit in ((f"car{ci}_{dof}", self.vehicle_disp, "rad" if rot else "m"),
                                       (f"car{ci}_{dof}_acc", self.vehicle_acc, "rad/s²" if rot else "m/s²")):
                    cols[key], units[key] = arr[:, ci, di], unit
        for w in range(self.contact_force.shape[1]):
            cols[f"contact_force_{w}"], units[f"contact_force_{w}"] = self.contact_force[:, w], "N"
        df = frame(cols, units)
        df.index = self.t
        df.index.name = "t"
        df.attrs["units"]["t"] = "s"
        return df

    def to_parquet(self, path) -> None:
        """The histories of :meth:`to_pandas` as a Parquet file, units in its metadata
        (needs pyarrow; :func:`vtb.read_parquet` reads it back)."""
        to_parquet(self.to_pandas(), path)

    def __repr__(self) -> str:
        top = self.layer_names[0] if self.layer_names else ""
        shown = ", ".join(f"{k} = {self._metrics[k]:.4g} {metric_unit(k)}" for k in (f"{top}_acc_max", f"{top}_disp_max") if k in self._metrics)
        return (f"Result({len(self.t) - 1} steps of {self.t[1] - self.t[0] if len(self.t) > 1 else 0:g} s, layers {self.layer_names}, "
                f"points {list(self.points)}, {self.vehicle_acc.shape[1]} car(s), {len(self.contact_loss)} contact-loss period(s); {shown})")

    def layer(self, name: str) -> int:
        try:
            return self.layer_names.index(name)
        except ValueError:
            raise config_error("layer", name, f"no layer of that name (layers: {self.layer_names})") from None

    def displacement(self, layer: str, point: int = 0) -> np.ndarray:
        """Displacement history (m) of a layer at an observation point."""
        return self.disp[:, self.layer(layer), point]

    def acceleration(self, layer: str, point: int = 0) -> np.ndarray:
        """Acceleration history (m/s²) of a layer at an observation point."""
        return self.acc[:, self.layer(layer), point]

    @property
    def car_body_disp(self) -> np.ndarray:
        """Car-body bounce of the first car relative to t = 0 (m)."""
        return self.vehicle_disp[:, 0, 0]

    @property
    def car_body_acc(self) -> np.ndarray:
        """Car-body bounce acceleration of the first car (m/s²)."""
        return self.vehicle_acc[:, 0, 0]

    def series(self, layer: str, quantity: str = "acc", point: int = 0, window: Optional[tuple] = None) -> tuple[np.ndarray, np.ndarray]:
        """(t, x) of a layer's ``quantity`` (``"acc"`` m/s², ``"disp"`` m) at an observation
        point, or of the first car body's bounce with ``layer="car_body"``, cut to the
        analysis ``window`` (t0, t1) in s when given."""
        if quantity not in ("acc", "disp"):
            raise config_error("quantity", quantity, 'must be "acc" or "disp"')
        if layer == "car_body":
            x = self.car_body_acc if quantity == "acc" else self.car_body_disp
        else:
            x = (self.acceleration if quantity == "acc" else self.displacement)(layer, point)
        t = self.t
        if window is not None:
            t0, t1 = window
            keep = (t >= t0) & (t <= t1)
            if keep.sum() < 8:
                raise config_error("window", window, f"holds fewer than 8 samples of the run [0, {t[-1]:g}] s")
            t, x = t[keep], x[keep]
        return t, x

    def spectrum(self, layer: str, quantity: str = "acc", point: int = 0, window: Optional[tuple] = None, nperseg: Optional[int] = None) -> tuple[np.ndarray, np.ndarray]:
        """One-sided PSD (Welch, Hann window, half-overlapping segments; :mod:`vtb.analysis.spectra`) of
        :meth:`series`: (f in Hz, PSD in (m/s²)²/Hz or m²/Hz)."""
        t, x = self.series(layer, quantity, point, window)
        return psd(x, 1.0 / self.config.solver.dt, nperseg)

    def third_octave(self, layer: str, quantity: str = "acc", point: int = 0, window: Optional[tuple] = None, **options) -> dict:
        """Energy-true IEC 61260-1 one-third-octave band levels of :meth:`series` over the
        analysis ``window`` (s; the whole run by default), in dB re 1e−6 m/s² (acceleration) or
        1e−9 m (displacement), with the equivalent level ``leq`` and the exposure level
        ``exposure`` (dB) over it; see :func:`vtb.analysis.spectra.third_octave`. A passage is a
        transient, so these (not Welch's, :meth:`welch_third_octave`) are its band levels. Bands
        beyond the band the run resolves for the layer (:func:`vtb.resolved_band`) warn
        (:class:`vtb.ResolutionWarning`)."""
        return self._bands(third_octave, layer, quantity, point, window, **options)

    def welch_third_octave(self, layer: str, quantity: str = "acc", point: int = 0, window: Optional[tuple] = None, **options) -> dict:
        """One-third-octave band levels of :meth:`series` by Welch's PSD, for a stationary part
        of a run (:func:`vtb.analysis.spectra.welch_third_octave`); warns as :meth:`third_octave`."""
        return self._bands(welch_third_octave, layer, quantity, point, window, **options)

    def _bands(self, method, layer: str, quantity: str, point: int, window, **options) -> dict:
        t, x = self.series(layer, quantity, point, window)
        bands = method(x, 1.0 / self.config.solver.dt, quantity, **options)
        if len(bands["upper"]):
            warn_beyond(self.config, layer, float(bands["upper"][-1]), "the top band", stepped=True)
        return bands

    def comfort(self, car: int = 0, window: Optional[tuple] = None) -> dict:
        """Ride-comfort indices of a car body's vertical acceleration, optionally over an
        analysis ``window`` (t0, t1) in s: ISO 2631-1's Wk-weighted r.m.s. ``a_w`` and ``mtvv``
        (m/s², with ``mtvv_ratio`` and ``duration`` in s; :func:`vtb.analysis.comfort.iso2631`) and
        Sperling's ``wz`` (dimensionless; :func:`vtb.analysis.comfort.sperling`). Short records warn
        (:class:`vtb.analysis.comfort.ComfortWarning`)."""
        if isinstance(car, bool) or not isinstance(car, int) or not 0 <= car < self.vehicle_acc.shape[1]:
            raise config_error("car", car, f"must index one of the {self.vehicle_acc.shape[1]} cars")
        a, t = self.vehicle_acc[:, car, 0], self.t
        if window is not None:
            keep = (t >= window[0]) & (t <= window[1])
            if keep.sum() < 8:
                raise config_error("window", window, f"holds fewer than 8 samples of the run [0, {t[-1]:g}] s")
            a = a[keep]
        fs = 1.0 / self.config.solver.dt
        return {**iso2631(a, fs), "wz": sperling(a, fs)["wz"]}

    def save(self, path) -> None:
        """Writes the histories, metrics, contact-loss periods and the configuration that made
        them (as TOML) to a compressed ``.npz`` file; :func:`load` reads it back."""
        np.savez_compressed(
            path,
            format=np.array(RESULT_FORMAT),
            config=np.array(self.config.to_toml()),
            contact_loss=np.array([(w, s, np.nan if e is None else e) for w, s, e in self.contact_loss], dtype=float).reshape(-1, 3),
            t=self.t,
            disp=self.disp,
            acc=self.acc,
            vehicle_disp=self.vehicle_disp,
            vehicle_acc=self.vehicle_acc,
            contact_force=self.contact_force,
            pad_force=self.pad_force,
            layer_names=np.array(self.layer_names),
            points=np.array(self.points),
            metric_names=np.array(list(self._metrics)),
            metric_values=np.array(list(self._metrics.values())),
        )


#: The tag :meth:`Result.save` writes and :func:`load` checks.
RESULT_FORMAT = "vtb.Result 1"


def load(path) -> Result:
    """A :class:`Result` written by :meth:`Result.save` (histories, metrics, contact-loss
    periods and its configuration); anything else raises :class:`~vtb.errors.ConfigError`."""
    try:
        with np.load(path, allow_pickle=False) as d:
            if "format" not in d or str(d["format"]) != RESULT_FORMAT:
                raise config_error("path", str(path), f"is not a file written by vtb.Result.save ({RESULT_FORMAT})")
            loss = [(int(w), float(s), None if np.isnan(e) else float(e)) for w, s, e in d["contact_loss"]]
            return Result(
                t=d["t"], disp=d["disp"], acc=d["acc"], vehicle_disp=d["vehicle_disp"], vehicle_acc=d["vehicle_acc"],
                contact_force=d["contact_force"], contact_loss=loss, layer_names=[str(n) for n in d["layer_names"]],
                pad_force=d["pad_force"] if "pad_force" in d else np.zeros((d["t"].size, 0)),
                points=[float(p) for p in d["points"]], config=Config.from_toml_text(str(d["config"])),
                _metrics={str(k): float(v) for k, v in zip(d["metric_names"], d["metric_values"])},
            )
    except FileNotFoundError:
        raise config_error("path", str(path), "no such file") from None
    except (OSError, ValueError, KeyError) as e:
        raise config_error("path", str(path), f"cannot be read as a vtb result: {e}") from None


def _result(out: dict, config: Config) -> Result:
    n = out["n_steps"]
    return Result(
        t=np.arange(n + 1) * out["dt"],
        disp=out["disp"],
        acc=out["acc"],
        vehicle_disp=out["vehicle_disp"],
        vehicle_acc=out["vehicle_acc"],
        contact_force=out["contact_force"],
        pad_force=out["pad_force"],
        contact_loss=out["contact_loss"],
        layer_names=out["layer_names"],
        points=out["points"],
        config=config,
        _metrics=out["metrics"],
    )


#: Seconds a single run lasts before its progress bar appears (``progress="auto"``).
PROGRESS_DELAY = 2.0


def simulate(config: Config, progress: Union[bool, str, Callable] = "auto") -> Result:
    """Runs one configuration. Ctrl-C stops it within a fraction of a second (the core polls
    every 64 steps; the caller checks every 50 ms) with ``KeyboardInterrupt``.

    ``progress``: ``"auto"`` (default) shows a tqdm bar of the time steps once the run has
    lasted :data:`PROGRESS_DELAY` s, on a terminal only (not in logs, pipes or worker
    processes), so quick runs print nothing; ``True`` from the start, anywhere; ``False`` none;
    or a callable ``f(done, total)`` (steps) called every 50 ms."""
    if not (progress in ("auto", True, False) or callable(progress)):
        raise config_error("progress", progress, 'must be "auto", True, False or a callable f(done, total)')
    building = "auto" if callable(progress) else progress  # a reduction's build announces itself unless False
    if progress == "auto" and not (hasattr(sys.stderr, "isatty") and sys.stderr.isatty()):
        progress = False
    if isinstance(config, Config):
        check_build(config)  # a build beyond the budget is refused before the profile is sampled
    text, profile = prepare(config, full=True)
    red = _reduction(config, building, text, profile.core_args())
    bar = None

    def tick(done, total):
        nonlocal bar
        if callable(progress):
            return progress(done, total)
        if total and bar is None:
            from tqdm.auto import tqdm

            bar = tqdm(total=total, desc="vtb simulate", unit="step", unit_scale=True, delay=0.0 if progress is True else PROGRESS_DELAY)
        if bar is not None:
            bar.update(done - bar.n)

    try:
        out = _core.simulate(text, *profile.core_args(), reduction=red, progress=None if progress is False else tick)
        if bar is not None:
            bar.update(bar.total - bar.n)
    finally:
        if bar is not None:
            bar.close()
    return _result(out, config)


def _reduction(config: Config, progress="auto", text: Optional[str] = None, profile: tuple = ()):
    """The core reduction a configuration with ``discretisation.synthesis_cutoff`` (or
    ``substructure_cutoff``: its substructures) runs on.
    Before a reduction is loaded or built, the core validates the whole run (``text``, its core
    JSON, against ``profile``, its sampled irregularity's core arguments): every check that needs no
    model comes before the costly part."""
    if config.discretisation.substructure_cutoff is not None:
        if text is not None:
            gateway.validate(text, *profile)
        return substructures.reduction(config, progress).to_core()
    if config.discretisation.synthesis_cutoff is None:
        return None
    if text is not None and not in_memory(config):
        gateway.validate(text, *profile)
    return reduction(config, progress).to_core()


#: The widest lockstep group by default (measured: ``cargo bench --bench lockstep``), and on a
#: synthesis reduction (docs/synthesis.md).
DEFAULT_LANES = _core.DEFAULT_LANES
SYNTHESIS_LANES = _core.SYNTHESIS_LANES


def _prepare_all(configs, on_error: str, results: list) -> tuple:
    """Every configuration of a batch prepared (checked; one sample's runs share its profile):
    the core JSONs, each run's profile index, the profiles and the indices into ``configs`` of
    the runs; a refused one is kept in ``results`` (``on_error="return"``). A warning's cause
    is said once per batch, not once per run."""
    jsons, profile_index, profiles, keys = [], [], [], {}
    order = []
    said: dict = {}
    for i, cfg in enumerate(configs):
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                text, profile = prepare(cfg)
        except VtbError as e:
            if on_error == "raise":
                raise
            results[i] = e
            continue
        finally:
            for w in caught:
                said.setdefault((str(w.message), w.category), w)
        if id(profile) not in keys:  # (held in keys: an id is not reused while the batch runs)
            keys[id(profile)] = (len(profiles), profile)
            profiles.append(profile.core_args())
        profile_index.append(keys[id(profile)][0])
        jsons.append(text)
        order.append(i)
    for w in said.values():
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return jsons, profile_index, profiles, order


def simulate_batch(
    configs: Sequence[Config],
    threads: Optional[int] = None,
    progress: Union[bool, object] = False,
    on_error: str = "raise",
    histories: bool = False,
    lanes: Optional[int] = None,
    on_result: Optional[Callable] = None,
) -> list:
    """Runs many configurations in parallel in Rust and returns each run's metrics dict (or,
    with ``histories=True``, its full :class:`Result`).

    Configurations that differ only in their dampers' parameters (``inertance``,
    ``stiffness``, ``damping`` of ``tids`` or of any group in ``dampers``) or in their irregularity share one assembled model and run in
    lockstep groups of up to ``lanes`` jobs (1, 2, 4 or 8; 1 runs every job alone; None: the
    measured default of the engine, :data:`DEFAULT_LANES` or on a synthesis
    :data:`SYNTHESIS_LANES`): a job's
    result is bit for bit the one it gives alone, a failing job leaves its group running, and
    without ``histories`` a job keeps only the series its metrics need.

    ``threads``: worker threads (default: all cores; at most :data:`vtb.config.args.MAX_THREADS`). ``progress``: ``True`` for a tqdm bar,
    or a callable ``f(done)``. ``on_error``: ``"raise"`` raises the first failure,
    ``"return"`` puts the exception object in its place and continues. Configurations that
    share an irregularity sample share one generated profile (:func:`irregularity_profile`). Ctrl-C interrupts the
    batch within a fraction of a second.

    ``on_result``: ``f(i, item)``, called from the calling thread as soon as each run's
    lockstep group finishes, with the index into ``configs`` and what the returned list will
    hold there (a metrics dict, a :class:`Result`, or the exception object): a study journals
    its finished cases with it, so that an interrupted batch keeps them.
    """
    if on_error not in ("raise", "return"):
        raise config_error("on_error", on_error, "must be \"raise\" or \"return\"")
    if lanes is not None and (not isinstance(lanes, int) or isinstance(lanes, bool) or lanes not in (1, 2, 4, 8)):
        raise config_error("lanes", lanes, "must be 1, 2, 4 or 8")
    threads = args.threads(threads)
    results: list = [None] * len(configs)
    jsons, profile_index, profiles, order = _prepare_all(configs, on_error, results)
    bar, callback = None, None
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(jsons), desc="vtb runs", unit="run")

        def callback(done, _bar=bar):
            _bar.update(done - _bar.n)

    elif callable(progress):
        callback = progress
    # One core batch per reduction (the jobs on the Newmark engine form one of their own).
    groups: dict = {}
    for j, i in enumerate(order):
        cfg = configs[i]
        key = cfg.discretisation.synthesis_cutoff
        try:
            red = _reduction(cfg, "auto" if progress is not False else False, jsons[j], profiles[profile_index[j]])
        except VtbError as e:
            if on_error == "raise":
                raise
            results[i] = e
            continue
        groups.setdefault(id(red) if red is not None else key, (red, []))[1].append(j)
    out: list = [None] * len(jsons)
    offset = 0

    def shifted(done, _cb=callback):
        if _cb is not None:
            _cb(offset + done)

    def item(j, r):
        """What the returned list holds for job j's raw result r."""
        i = order[j]
        return _result(r, configs[i]) if histories and isinstance(r, dict) else r

    try:
        for red, members in groups.values():
            def each(k, r, _members=members):
                j = _members[k]
                out[j] = item(j, r)
                on_result(order[j], out[j])

            got = _core.batch([jsons[j] for j in members], profiles, [profile_index[j] for j in members], threads or 0,
                              shifted if callback else None, histories,
                              lanes or (SYNTHESIS_LANES if isinstance(red, _core.Reduction) else DEFAULT_LANES), reduction=red,
                              on_result=each if on_result is not None else None)
            for j, r in zip(members, got):
                if out[j] is None:
                    out[j] = item(j, r)
            offset += len(members)
    finally:
        if bar is not None:
            bar.close()
    for i, r in zip(order, out):
        if r is None:  # its reduction failed (kept above)
            continue
        if isinstance(r, BaseException) and on_error == "raise":
            raise r
        results[i] = r
    return results


def with_changes(config: Config, **changes) -> Config:
    """A copy of ``config`` with top-level fields replaced (see :func:`dataclasses.replace`)."""
    return dataclasses.replace(config.copy(), **changes)


def assembled_matrices(config: Config) -> dict:
    """The assembled structure matrices of a configuration as dense numpy arrays:
    ``{"m", "k", "c"}`` (kg, N/m, N·s/m in generalised coordinates) and ``"layers"``, a list
    of (name, first DOF, number of DOFs). Only the structure (and its dampers) is validated:
    the loads, speed, solver and outputs play no part (:func:`vtb.config.fields.structure_json`)."""
    out = _core.matrices(structure_json(config))
    n = out["n"]
    dense = {}
    for name in ("m", "k", "c"):
        r, c, v = out[name]
        a = np.zeros((n, n))
        np.add.at(a, (r, c), v)
        dense[name] = a
    dense["layers"] = out["layer_offsets"]
    return dense
