//! What a run records and where its indices are taken.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Observation points (m); empty means x = L/2. The indices of a layer are taken at the
    /// first point; with more than one point, the deck's `deck_acc_max_p{j}` and
    /// `deck_disp_max_p{j}` at every point j.
    #[serde(default)]
    pub points: Vec<f64>,
    /// Analysis window [t0, t1] (s) of the metrics: maxima, r.m.s., contact-force extremes and
    /// contact-loss events are taken over t0 ≤ t ≤ t1 (settle times stay absolute, in s from
    /// the start); t0 must lie within the run, a t1 past its end ends the window with the run.
    /// Empty (the default): the whole run.
    #[serde(default)]
    pub window: Option<[f64; 2]>,
    /// Band limit (Hz) of the acceleration indices: every layer's and the car's acceleration
    /// record is low-passed at this frequency (8th-order Butterworth run forwards and
    /// backwards: zero phase, gain 1/(1 + (f/f_b)¹⁶) at the limit f_b, −6 dB there) before its peak, r.m.s.
    /// and settle time are taken; the raw peak stays as `{layer}_acc_max_raw`. Must lie below
    /// the Nyquist frequency 1/(2·solver.dt). Empty (the default): raw indices.
    #[serde(default)]
    pub band_limit: Option<f64>,
    /// The indices a run reports (names as in its metrics, e.g. `rail_acc_max`,
    /// `slab_acc_rms`, `car_acc_max`, `contact_force_max`; no unit). A batch then records only
    /// the layers these name, at the first observation point, which saves time on every
    /// layer left out. Empty (the default): every index of every layer.
    #[serde(default)]
    pub indices: Option<Vec<String>>,
    /// Band (Hz) of the deck acceleration `deck_acc_max`: the bottom layer's acceleration at
    /// the first observation point, low-passed here (the filter of `band_limit`). EN 1990 A2
    /// (A2.4.4.2.1) limits the peak deck acceleration (3.5 m/s² under ballast, 5 m/s² with
    /// direct fastening) over frequencies up to the greatest of 30 Hz, 1.5 times the deck's
    /// first natural frequency and its third; the default is the 30 Hz that governs decks
    /// below 20 Hz (`vtb.deck_band` gives the rule for a configuration).
    #[serde(default = "default_deck_band")]
    pub deck_band: f64,
    /// One-third-octave bands (nominal midband, Hz: 31.5, 63, …, 1000, …) of the energy-true
    /// band-level indices: each layer's raw acceleration at the first observation point over
    /// the analysis window, as `{layer}_acc_L{band}` (dB re 1e−6 m/s², the band's share of the
    /// record's mean square, docs/spectra.md), with the equivalent level `{layer}_acc_Leq` (dB)
    /// of the same record. A band must lie below the Nyquist frequency and span at least 4
    /// frequency bins of the record. Empty (the default): no band levels.
    #[serde(default)]
    pub band_levels: Vec<f64>,
    /// Record (true/false) the force in the rail fastener nearest each observation point j: the
    /// first discrete coupling point between the top layer and another layer, its spring and
    /// dashpot force (N, compression positive), reported as the index `pad{j}_force_range`
    /// (the load range of a fatigue check). Off by default: it adds two observers per point.
    #[serde(default)]
    pub pad_forces: bool,
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self {
            points: Vec::new(),
            window: None,
            band_limit: None,
            indices: None,
            deck_band: default_deck_band(),
            band_levels: Vec::new(),
            pad_forces: false,
        }
    }
}

fn default_deck_band() -> f64 {
    30.0
}
