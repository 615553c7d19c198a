//! A run's outputs: the histories it records and the indices derived from them, with the
//! index catalogue, band levels, the band-limiting filter and ride comfort.

pub mod bands;
pub mod catalog;
pub mod comfort;
pub mod filter;
pub mod indices;

pub use catalog::{DECK, index_layers, index_names, layer_of_index};

use crate::config::Config;
use crate::model::structure::Structure;
use catalog::{
    DECK_ACC_POINT, DECK_DISP_POINT, DECK_MOMENT, DECK_MOMENT_POINT, band_index, car_comfort,
    layer_index, point_index,
};
use filter::low_pass;
use indices::{amplitude, rms, settle_time};
use std::collections::BTreeMap;

/// A period during which a wheel had no contact (P = 0). `t_end` is `None` if contact was
/// not regained before the end of the run.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactLoss {
    pub wheel: usize,
    pub t_start: f64,
    pub t_end: Option<f64>,
}

/// What a run keeps: everything, or only the series its metrics are computed from (the layers
/// its indices need, `catalog::index_layers`, at the first observation point, or at every one
/// when a per-point deck index is reported, `catalog::every_point`; the first car
/// body's bounce; the contact forces): the batch of a study never holds the full histories of
/// all its jobs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Record {
    Full,
    Metrics,
}

impl Record {
    /// The structure's layers a run records, by index.
    pub fn layers(self, cfg: &Config) -> Vec<usize> {
        match self {
            Record::Full => (0..cfg.structure.layers.len()).collect(),
            Record::Metrics => index_layers(cfg),
        }
    }

    /// Whether a run records the bottom layer's bending moment (at its recorded points).
    pub fn moments(self, cfg: &Config) -> bool {
        match self {
            Record::Full => !cfg.structure.layers.is_empty(),
            Record::Metrics => catalog::moments(cfg),
        }
    }

    /// The observation points (m) a run records.
    pub fn points(self, cfg: &Config) -> Vec<f64> {
        let all = cfg.observation_points();
        match self {
            Record::Metrics if !catalog::every_point(cfg) => all[..1].to_vec(),
            _ => all,
        }
    }
}

/// Histories sampled at t = i·dt, i = 0..=n_steps, stored time-major.
#[derive(Clone, Debug)]
pub struct RunResult {
    pub dt: f64,
    pub n_steps: usize,
    pub layer_names: Vec<String>,
    /// Observation points (m).
    pub points: Vec<f64>,
    /// Displacement (m, down positive, from the unloaded structure) at
    /// `[(step·n_layers + layer)·n_points + point]`.
    pub disp: Vec<f64>,
    /// Acceleration (m/s²), same layout as `disp`.
    pub acc: Vec<f64>,
    /// Cars and DOFs per car recorded (all and 10, or the first car's body bounce only).
    pub n_cars: usize,
    pub vehicle_dofs: usize,
    /// Vehicle DOFs relative to the static state at t = 0 (m, rad) at
    /// `[(step·n_cars + car)·vehicle_dofs + dof]`.
    pub vehicle_disp: Vec<f64>,
    /// Vehicle accelerations (m/s², rad/s²), same layout.
    pub vehicle_acc: Vec<f64>,
    pub n_wheels: usize,
    /// Contact force on the modelled rail (N) at `[step·n_wheels + wheel]`.
    pub contact_force: Vec<f64>,
    pub contact_loss: Vec<ContactLoss>,
    /// The metrics' analysis window (s), `output.window`.
    pub window: Option<[f64; 2]>,
    /// Low-pass frequency (Hz) of the acceleration indices, `output.band_limit`.
    pub band_limit: Option<f64>,
    /// Band labels (Hz) of the band-level indices, `output.band_levels`.
    pub band_levels: Vec<f64>,
    /// The indices `metrics` reports, `output.indices` (all without).
    pub indices: Option<Vec<String>>,
    /// The deck among the recorded layers (the structure's bottom layer), if recorded.
    pub deck: Option<usize>,
    /// Low-pass frequency (Hz) of `deck_acc_max`, `output.deck_band`.
    pub deck_band: f64,
    /// Observation points at which the bottom layer's bending moment is recorded (all of
    /// `points`, or none).
    pub n_moments: usize,
    /// Its bending moment (N·m, sagging positive, `Layer::moment_shape`) at
    /// `[step·n_moments + point]`.
    pub moment: Vec<f64>,
    /// Rail fasteners recorded (`output.pad_forces`: the one nearest each observation point).
    pub n_pads: usize,
    /// Force in each of them (N, compression positive) at `[step·n_pads + pad]`.
    pub pad_force: Vec<f64>,
}

impl RunResult {
    pub fn new(
        cfg: &Config,
        st: &Structure,
        n_steps: usize,
        points: &[f64],
        n_cars: usize,
        n_wheels: usize,
        record: Record,
    ) -> Self {
        let layers = record.layers(cfg);
        let nl = layers.len();
        let len = n_steps + 1;
        let n_moments = if record.moments(cfg) { points.len() } else { 0 };
        let (n_cars, vehicle_dofs) = match record {
            Record::Full => (
                n_cars,
                cfg.vehicles
                    .first()
                    .map_or(0, |v| crate::model::vehicle::model_of(v).dofs().len()),
            ),
            Record::Metrics => (n_cars, 1),
        };
        Self {
            dt: cfg.solver.dt,
            n_steps,
            layer_names: layers.iter().map(|&l| st.layers[l].name.clone()).collect(),
            points: points.to_vec(),
            disp: vec![0.0; len * nl * points.len()],
            acc: vec![0.0; len * nl * points.len()],
            n_cars,
            vehicle_dofs,
            vehicle_disp: vec![0.0; len * n_cars * vehicle_dofs],
            vehicle_acc: vec![0.0; len * n_cars * vehicle_dofs],
            n_wheels,
            contact_force: vec![0.0; len * n_wheels],
            contact_loss: Vec::new(),
            window: cfg.output.window,
            band_limit: cfg.output.band_limit,
            band_levels: cfg.output.band_levels.clone(),
            indices: cfg.output.indices.clone(),
            deck: (st.layers.len() > 1)
                .then(|| layers.iter().position(|&l| l + 1 == st.layers.len()))
                .flatten(),
            deck_band: cfg.output.deck_band,
            n_moments,
            moment: vec![0.0; len * n_moments],
            n_pads: catalog::pads_of(cfg).len(),
            pad_force: vec![0.0; len * catalog::pads_of(cfg).len()],
        }
    }

    fn column(data: &[f64], stride: usize, offset: usize) -> Vec<f64> {
        data.iter().skip(offset).step_by(stride).copied().collect()
    }

    /// Displacement history of `layer` at observation point `point`.
    pub fn layer_disp(&self, layer: usize, point: usize) -> Vec<f64> {
        let np = self.points.len();
        Self::column(&self.disp, self.layer_names.len() * np, layer * np + point)
    }

    pub fn layer_acc(&self, layer: usize, point: usize) -> Vec<f64> {
        let np = self.points.len();
        Self::column(&self.acc, self.layer_names.len() * np, layer * np + point)
    }

    pub fn vehicle_dof_disp(&self, car: usize, dof: usize) -> Vec<f64> {
        let d = self.vehicle_dofs;
        Self::column(&self.vehicle_disp, self.n_cars * d, car * d + dof)
    }

    pub fn vehicle_dof_acc(&self, car: usize, dof: usize) -> Vec<f64> {
        let d = self.vehicle_dofs;
        Self::column(&self.vehicle_acc, self.n_cars * d, car * d + dof)
    }

    pub fn wheel_force(&self, wheel: usize) -> Vec<f64> {
        Self::column(&self.contact_force, self.n_wheels, wheel)
    }

    /// Metrics in SI units at the first observation point: for every layer
    /// `{name}_disp_max`, `{name}_acc_max`, `{name}_acc_rms`, `{name}_acc_settle` (s, 5 %
    /// rule); for the first car `car_disp_max`, `car_acc_max`, `car_acc_rms` and its ride
    /// comfort `car_comfort_aw` (ISO 2631-1 a_w of the raw record, at sampling rates ≥ 400 Hz),
    /// and each further car's `car{k}_comfort_aw`; the deck acceleration `deck_acc_max` (the
    /// bottom layer's, low-passed at `output.deck_band`, EN 1990 A2); `contact_force_max`,
    /// the bottom layer's bending moment `deck_moment_max` (N·m), and at each observation point j
    /// (recorded) `deck_acc_max_p{j}`, `deck_disp_max_p{j}` and `deck_moment_max_p{j}`;
    /// `contact_force_min`, `contact_loss_events` over all wheels and each wheel's
    /// `wheel{w}_force_max`, `wheel{w}_force_min`; with `output.pad_forces`, the force range
    /// `pad{j}_force_range` of the rail fastener nearest each observation point j. The
    /// catalogue ([`catalog`]) lists them all with their units and bands.
    ///
    /// With an analysis window ([`RunResult::window`]) every metric is taken over the steps
    /// inside it; settle times are still counted from t = 0.
    ///
    /// With a band limit ([`RunResult::band_limit`]) every acceleration index is taken of the
    /// whole record low-passed at that frequency (zero phase, [`crate::outputs::filter`]) before the
    /// window is applied, and each layer's raw peak is kept as `{name}_acc_max_raw`.
    ///
    /// With band levels ([`RunResult::band_levels`]) every layer adds its energy-true
    /// one-third-octave levels `{name}_acc_L{band}` and its equivalent level `{name}_acc_Leq`
    /// (dB re 1e−6 m/s², [`crate::outputs::bands`]) of the raw record over the window.
    ///
    /// With `output.indices` ([`RunResult::indices`]) only those are reported.
    pub fn metrics(&self) -> BTreeMap<String, f64> {
        let steps = self.window_steps();
        let mut m = BTreeMap::new();
        self.layer_metrics(&steps, &mut m);
        self.car_metrics(&steps, &mut m);
        if let Some(d) = self.deck.filter(|_| self.wants(DECK)) {
            let a = low_pass(&self.layer_acc(d, 0), self.deck_band, self.dt);
            m.insert(DECK.to_string(), amplitude(&a[steps.clone()]));
        }
        if let Some(d) = self.deck.filter(|_| self.wants("deck_disp_max")) {
            let u = &self.layer_disp(d, 0)[steps.clone()];
            m.insert("deck_disp_max".to_string(), amplitude(u));
        }
        if self.n_moments > 0 && self.wants(DECK_MOMENT) {
            let mo = &Self::column(&self.moment, self.n_moments, 0)[steps.clone()];
            m.insert(DECK_MOMENT.to_string(), amplitude(mo));
        }
        self.deck_point_metrics(&steps, &mut m);
        self.contact_metrics(&steps, &mut m);
        for j in 0..self.n_pads {
            let f = &Self::column(&self.pad_force, self.n_pads, j)[steps.clone()];
            let (lo, hi) = extremes(f);
            m.insert(format!("pad{j}_force_range"), hi - lo);
        }
        if let Some(keep) = &self.indices {
            m.retain(|k, _| keep.contains(k));
        }
        m
    }

    /// The deck's peak acceleration (in the deck band) and displacement at every recorded
    /// observation point, when more than one is recorded.
    fn deck_point_metrics(&self, steps: &Steps, m: &mut BTreeMap<String, f64>) {
        let Some(d) = self.deck.filter(|_| self.points.len() > 1) else {
            return;
        };
        for j in 0..self.points.len() {
            let acc = point_index(DECK_ACC_POINT, j);
            if self.wants(&acc) {
                let a = low_pass(&self.layer_acc(d, j), self.deck_band, self.dt);
                m.insert(acc, amplitude(&a[steps.clone()]));
            }
            let disp = point_index(DECK_DISP_POINT, j);
            if self.wants(&disp) {
                m.insert(disp, amplitude(&self.layer_disp(d, j)[steps.clone()]));
            }
            let moment = point_index(DECK_MOMENT_POINT, j);
            if self.n_moments > j && self.wants(&moment) {
                let mo = &Self::column(&self.moment, self.n_moments, j)[steps.clone()];
                m.insert(moment, amplitude(mo));
            }
        }
    }

    /// A record low-passed at the band limit (as it is without one).
    fn limited(&self, a: Vec<f64>) -> Vec<f64> {
        match self.band_limit {
            Some(fc) => low_pass(&a, fc, self.dt),
            None => a,
        }
    }

    /// Every recorded layer's indices at the first observation point.
    fn layer_metrics(&self, steps: &Steps, m: &mut BTreeMap<String, f64>) {
        let t0 = *steps.start() as f64 * self.dt;
        for (li, name) in self.layer_names.iter().enumerate() {
            let d = &self.layer_disp(li, 0)[steps.clone()];
            let raw = self.layer_acc(li, 0);
            if self.band_limit.is_some() {
                let peak = amplitude(&raw[steps.clone()]);
                m.insert(layer_index(name, "acc_max_raw"), peak);
            }
            let a = &self.limited(raw)[steps.clone()];
            let values = [
                ("disp_max", amplitude(d)),
                ("acc_max", amplitude(a)),
                ("acc_rms", rms(a)),
                ("acc_settle", t0 + settle_time(a, self.dt, 0.05)),
            ];
            for (s, v) in values {
                m.insert(layer_index(name, s), v);
            }
            let leq = layer_index(name, "acc_Leq");
            let wanted = std::iter::once(leq.clone())
                .chain(self.band_levels.iter().map(|&f| band_index(name, f)))
                .any(|s| self.wants(&s));
            if !self.band_levels.is_empty() && wanted {
                let raw = &self.layer_acc(li, 0)[steps.clone()];
                let powers = bands::band_powers(raw, self.dt, &self.band_levels);
                for (&f, p) in self.band_levels.iter().zip(powers) {
                    m.insert(band_index(name, f), bands::level(p, bands::ACC_REFERENCE));
                }
                let ms = rms(raw).powi(2);
                m.insert(leq, bands::level(ms, bands::ACC_REFERENCE));
            }
        }
    }

    /// The first car body's indices and every car's ride comfort.
    fn car_metrics(&self, steps: &Steps, m: &mut BTreeMap<String, f64>) {
        if self.n_cars == 0 {
            return;
        }
        let d = &self.vehicle_dof_disp(0, 0)[steps.clone()];
        let a = &self.limited(self.vehicle_dof_acc(0, 0))[steps.clone()];
        for (s, v) in [
            ("car_disp_max", amplitude(d)),
            ("car_acc_max", amplitude(a)),
            ("car_acc_rms", rms(a)),
        ] {
            m.insert(s.to_string(), v);
        }
        for k in 0..self.n_cars {
            let name = car_comfort(k);
            if self.wants(&name) && 1.0 / self.dt >= comfort::MIN_RATE {
                // weighted from the window's start, as vtb.comfort weights a windowed record
                let raw = &self.vehicle_dof_acc(k, 0)[steps.clone()];
                m.insert(name, comfort::weighted_rms(raw, self.dt));
            }
        }
    }

    /// The contact forces' extremes over all wheels and each wheel's, and the losses of
    /// contact within the window.
    fn contact_metrics(&self, steps: &Steps, m: &mut BTreeMap<String, f64>) {
        if self.n_wheels == 0 {
            return;
        }
        let nw = self.n_wheels;
        let (lo, hi) = extremes(&self.contact_force[*steps.start() * nw..(*steps.end() + 1) * nw]);
        let (ta, tb) = (
            *steps.start() as f64 * self.dt,
            *steps.end() as f64 * self.dt,
        );
        let events = self
            .contact_loss
            .iter()
            .filter(|e| e.t_start <= tb && e.t_end.is_none_or(|t| t >= ta))
            .count();
        for (s, v) in [
            ("contact_force_max", hi),
            ("contact_force_min", lo),
            ("contact_loss_events", events as f64),
        ] {
            m.insert(s.to_string(), v);
        }
        for w in 0..nw {
            let (lo, hi) = extremes(&self.wheel_force(w)[steps.clone()]);
            m.insert(format!("wheel{w}_force_max"), hi);
            m.insert(format!("wheel{w}_force_min"), lo);
        }
    }

    /// Whether `output.indices` asks for `name` (every index without it).
    fn wants(&self, name: &str) -> bool {
        self.indices
            .as_ref()
            .is_none_or(|k| k.iter().any(|n| n == name))
    }

    /// The steps inside the analysis window (all steps without one).
    fn window_steps(&self) -> std::ops::RangeInclusive<usize> {
        window_steps(self.window, self.dt, self.n_steps)
    }
}

/// The steps of a run inside its analysis window.
type Steps = std::ops::RangeInclusive<usize>;

/// (min, max) of a record.
fn extremes(x: &[f64]) -> (f64, f64) {
    x.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        })
}

/// The steps of a run of `n_steps` steps of `dt` s inside the analysis window `window` (all
/// steps without one).
pub fn window_steps(
    window: Option<[f64; 2]>,
    dt: f64,
    n_steps: usize,
) -> std::ops::RangeInclusive<usize> {
    match window {
        None => 0..=n_steps,
        Some([t0, t1]) => {
            // A window edge within 1e-9 steps of a sample includes it.
            let first = ((t0 / dt) - 1e-9).ceil().max(0.0) as usize;
            let last = ((t1 / dt) + 1e-9).floor() as usize;
            first.min(n_steps)..=last.min(n_steps).max(first.min(n_steps))
        }
    }
}
