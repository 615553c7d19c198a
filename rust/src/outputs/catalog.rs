//! The index catalogue: every index a run can report, with its name pattern, unit, what it is
//! taken of, the band of the record it is taken from and what it means. It is the one
//! definition: `index_names` expands it for a configuration, the checks of `output.indices`
//! and the layers a batch records follow from it, and Python reads it (`vtb.index_catalog()`)
//! for units, journal columns, tables, the CLI and the docs' index table.
//!
//! A new index over quantities a run already records is one row here and its computation in
//! `RunResult::metrics`.

use crate::config::Config;

/// What an index is taken of; its name pattern's placeholder says which one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Subject {
    /// A layer at the first observation point (`{layer}`).
    Layer,
    /// A layer's one-third-octave band at the first observation point (`{layer}`, `{band}`).
    LayerBand,
    /// The bottom layer (the deck) at the first observation point.
    Deck,
    /// The deck at observation point `{j}` (the point's index).
    DeckPoint,
    /// The first car's body.
    Car,
    /// The body of a car after the first (`{k}` ≥ 1).
    OtherCar,
    /// All wheels together.
    Wheels,
    /// One wheel (`{w}`, over the run's wheels: vehicles in order, wheelsets front to rear).
    Wheel,
    /// The rail fastener (pad) nearest an observation point (`{j}`, the point's index).
    Pad,
}

impl Subject {
    pub fn name(self) -> &'static str {
        match self {
            Subject::Layer => "layer",
            Subject::LayerBand => "layer band",
            Subject::Deck => "deck",
            Subject::DeckPoint => "deck point",
            Subject::Car => "car",
            Subject::OtherCar => "car k",
            Subject::Wheels => "wheels",
            Subject::Wheel => "wheel",
            Subject::Pad => "pad",
        }
    }
}

/// The band of the record an index is taken from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Band {
    /// The record as the run gives it.
    Raw,
    /// Low-passed at `output.band_limit` when it is set, else raw.
    Limit,
    /// Low-passed at `output.deck_band` (EN 1990 A2).
    Deck,
    /// One one-third-octave band (`output.band_levels`), energy-true.
    ThirdOctave,
    /// Weighted by ISO 2631-1's Wk (vertical whole-body vibration).
    Wk,
}

impl Band {
    pub fn name(self) -> &'static str {
        match self {
            Band::Raw => "raw",
            Band::Limit => "band_limit",
            Band::Deck => "deck_band",
            Band::ThirdOctave => "third_octave",
            Band::Wk => "iso2631_wk",
        }
    }
}

/// One kind of index.
pub struct IndexKind {
    /// The name, `{layer}`, `{band}`, `{k}`, `{w}` or `{j}` standing for its subject.
    pub pattern: &'static str,
    pub unit: &'static str,
    pub subject: Subject,
    pub band: Band,
    pub description: &'static str,
    /// Whether a run of the configuration reports it.
    present: fn(&Config) -> bool,
}

fn always(_: &Config) -> bool {
    true
}
fn band_limited(c: &Config) -> bool {
    c.output.band_limit.is_some()
}
fn band_levels(c: &Config) -> bool {
    !c.output.band_levels.is_empty()
}
fn deck(c: &Config) -> bool {
    c.structure.layers.len() > 1
}
/// A deck observed at more than one point (at one, `deck_acc_max` and `deck_disp_max` are it).
fn deck_points(c: &Config) -> bool {
    deck(c) && c.observation_points().len() > 1
}
fn vehicles(c: &Config) -> bool {
    !c.vehicles.is_empty()
}
fn comfort(c: &Config) -> bool {
    vehicles(c) && 1.0 / c.solver.dt >= crate::outputs::comfort::MIN_RATE
}
fn pads(c: &Config) -> bool {
    !pads_of(c).is_empty()
}

/// The deck acceleration of EN 1990 A2: the bottom layer's, low-passed at `output.deck_band`.
pub const DECK: &str = "deck_acc_max";
/// The deck's acceleration (as [`DECK`]) and displacement at observation point `{j}`.
pub const DECK_ACC_POINT: &str = "deck_acc_max_p{j}";
pub const DECK_DISP_POINT: &str = "deck_disp_max_p{j}";
/// The bottom layer's bending moment at the first observation point and at point `{j}`.
pub const DECK_MOMENT: &str = "deck_moment_max";
pub const DECK_MOMENT_POINT: &str = "deck_moment_max_p{j}";

/// Every kind of index, in the order `index_names` lists them (a layer's all together).
pub const CATALOG: &[IndexKind] = &[
    IndexKind {
        pattern: "{layer}_disp_max",
        unit: "m",
        subject: Subject::Layer,
        band: Band::Raw,
        description: "peak |displacement| (from the unloaded structure, static deflection included)",
        present: always,
    },
    IndexKind {
        pattern: "{layer}_acc_max",
        unit: "m/s²",
        subject: Subject::Layer,
        band: Band::Limit,
        description: "peak |acceleration|",
        present: always,
    },
    IndexKind {
        pattern: "{layer}_acc_rms",
        unit: "m/s²",
        subject: Subject::Layer,
        band: Band::Limit,
        description: "r.m.s. acceleration over the analysis window",
        present: always,
    },
    IndexKind {
        pattern: "{layer}_acc_settle",
        unit: "s",
        subject: Subject::Layer,
        band: Band::Limit,
        description: "time after which |acceleration| stays below 5 % of its peak, from t = 0",
        present: always,
    },
    IndexKind {
        pattern: "{layer}_acc_max_raw",
        unit: "m/s²",
        subject: Subject::Layer,
        band: Band::Raw,
        description: "peak |acceleration| of the raw record, beside a band-limited one",
        present: band_limited,
    },
    IndexKind {
        pattern: "{layer}_acc_Leq",
        unit: "dB",
        subject: Subject::Layer,
        band: Band::Raw,
        description: "equivalent acceleration level re 1e-6 m/s² over the analysis window",
        present: band_levels,
    },
    IndexKind {
        pattern: "{layer}_acc_L{band}",
        unit: "dB",
        subject: Subject::LayerBand,
        band: Band::ThirdOctave,
        description: "acceleration level re 1e-6 m/s² in the one-third-octave band (nominal midband, Hz)",
        present: band_levels,
    },
    IndexKind {
        pattern: DECK,
        unit: "m/s²",
        subject: Subject::Deck,
        band: Band::Deck,
        description: "peak |acceleration| of the bottom layer in the deck band (EN 1990 A2.4.4.2.1)",
        present: deck,
    },
    IndexKind {
        pattern: "deck_disp_max",
        unit: "m",
        subject: Subject::Deck,
        band: Band::Raw,
        description: "peak |displacement| of the bottom layer (static deflection included): the \
                      deck's deflection for EN 1990 A2.4.4.3",
        present: deck,
    },
    IndexKind {
        pattern: DECK_MOMENT,
        unit: "N·m",
        subject: Subject::Deck,
        band: Band::Raw,
        description: "peak |bending moment| of the bottom layer (a single layer's own), M = −EI·w″ \
                      of the model's basis (sagging positive; the moving loads' static moment \
                      included): the moment of EN 1991-2 §6.4.6.5(3)'s φ'dyn",
        present: always,
    },
    IndexKind {
        pattern: DECK_ACC_POINT,
        unit: "m/s²",
        subject: Subject::DeckPoint,
        band: Band::Deck,
        description: "peak |acceleration| of the bottom layer at observation point j in the deck band: \
                      the deck's acceleration searched along it (the largest over j governs)",
        present: deck_points,
    },
    IndexKind {
        pattern: DECK_DISP_POINT,
        unit: "m",
        subject: Subject::DeckPoint,
        band: Band::Raw,
        description: "peak |displacement| of the bottom layer at observation point j (static \
                      deflection included)",
        present: deck_points,
    },
    IndexKind {
        pattern: DECK_MOMENT_POINT,
        unit: "N·m",
        subject: Subject::DeckPoint,
        band: Band::Raw,
        description: "peak |bending moment| of the bottom layer at observation point j (as \
                      deck_moment_max)",
        present: deck_points,
    },
    IndexKind {
        pattern: "car_disp_max",
        unit: "m",
        subject: Subject::Car,
        band: Band::Raw,
        description: "peak |bounce| of the first car body from its static state",
        present: vehicles,
    },
    IndexKind {
        pattern: "car_acc_max",
        unit: "m/s²",
        subject: Subject::Car,
        band: Band::Limit,
        description: "peak |bounce acceleration| of the first car body",
        present: vehicles,
    },
    IndexKind {
        pattern: "car_acc_rms",
        unit: "m/s²",
        subject: Subject::Car,
        band: Band::Limit,
        description: "r.m.s. bounce acceleration of the first car body",
        present: vehicles,
    },
    IndexKind {
        pattern: "car_comfort_aw",
        unit: "m/s²",
        subject: Subject::Car,
        band: Band::Wk,
        description: "ride comfort a_w of the first car body (ISO 2631-1, Wk-weighted r.m.s.)",
        present: comfort,
    },
    IndexKind {
        pattern: "car{k}_comfort_aw",
        unit: "m/s²",
        subject: Subject::OtherCar,
        band: Band::Wk,
        description: "ride comfort a_w of car k's body (ISO 2631-1, Wk-weighted r.m.s.)",
        present: comfort,
    },
    IndexKind {
        pattern: "contact_force_max",
        unit: "N",
        subject: Subject::Wheels,
        band: Band::Raw,
        description: "largest wheel–rail contact force on the modelled rail, over all wheels",
        present: vehicles,
    },
    IndexKind {
        pattern: "contact_force_min",
        unit: "N",
        subject: Subject::Wheels,
        band: Band::Raw,
        description: "smallest wheel–rail contact force on the modelled rail (0: a loss of contact)",
        present: vehicles,
    },
    IndexKind {
        pattern: "contact_loss_events",
        unit: "–",
        subject: Subject::Wheels,
        band: Band::Raw,
        description: "periods without contact that overlap the analysis window (count)",
        present: vehicles,
    },
    IndexKind {
        pattern: "wheel{w}_force_max",
        unit: "N",
        subject: Subject::Wheel,
        band: Band::Raw,
        description: "largest contact force of wheel w",
        present: vehicles,
    },
    IndexKind {
        pattern: "wheel{w}_force_min",
        unit: "N",
        subject: Subject::Wheel,
        band: Band::Raw,
        description: "smallest contact force of wheel w",
        present: vehicles,
    },
    IndexKind {
        pattern: "pad{j}_force_range",
        unit: "N",
        subject: Subject::Pad,
        band: Band::Raw,
        description: "range (max − min) of the force in the rail fastener nearest observation point j \
                      (spring and dashpot, compression positive; output.pad_forces): the load \
                      range of a fatigue check",
        present: pads,
    },
];

impl IndexKind {
    /// This kind's names in a run of `cfg` (none when it does not report it).
    fn names(&self, cfg: &Config) -> Vec<String> {
        if !(self.present)(cfg) {
            return Vec::new();
        }
        let p = self.pattern;
        match self.subject {
            Subject::Layer | Subject::LayerBand => Vec::new(), // by layer, in `index_names`
            Subject::Deck | Subject::Car | Subject::Wheels => vec![p.to_string()],
            Subject::OtherCar => (1..cfg.vehicles.len())
                .map(|k| p.replace("{k}", &k.to_string()))
                .collect(),
            Subject::Wheel => (0..cfg.vehicles.iter().map(|v| v.n_wheels()).sum::<usize>())
                .map(|w| p.replace("{w}", &w.to_string()))
                .collect(),
            Subject::Pad | Subject::DeckPoint => (0..cfg.observation_points().len())
                .map(|j| p.replace("{j}", &j.to_string()))
                .collect(),
        }
    }

    /// This kind's names for the layer `layer`.
    fn layer_names(&self, cfg: &Config, layer: &str) -> Vec<String> {
        if !(self.present)(cfg) {
            return Vec::new();
        }
        let p = self.pattern.replace("{layer}", layer);
        match self.subject {
            Subject::Layer => vec![p],
            Subject::LayerBand => cfg
                .output
                .band_levels
                .iter()
                .map(|f| p.replace("{band}", &f.to_string()))
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// Every index a run of `cfg` can report (`output.indices` names a subset of these): each
/// layer's, then the others in the catalogue's order.
pub fn index_names(cfg: &Config) -> Vec<String> {
    let mut out: Vec<String> = cfg
        .structure
        .layers
        .iter()
        .flat_map(|l| CATALOG.iter().flat_map(|k| k.layer_names(cfg, &l.name)))
        .collect();
    out.extend(CATALOG.iter().flat_map(|k| k.names(cfg)));
    out
}

/// The name of layer `layer`'s index `suffix` (`rail`, `acc_max` → `rail_acc_max`).
pub fn layer_index(layer: &str, suffix: &str) -> String {
    format!("{layer}_{suffix}")
}

/// A layer's band-level index for the band labelled `nominal` (Hz).
pub fn band_index(layer: &str, nominal: f64) -> String {
    format!("{layer}_acc_L{nominal}")
}

/// The ride comfort index of car `k` (the first car's is `car_comfort_aw`).
pub fn car_comfort(k: usize) -> String {
    if k == 0 {
        "car_comfort_aw".to_string()
    } else {
        format!("car{k}_comfort_aw")
    }
}

/// Whether `name` is an index of the layer `layer`.
pub fn layer_of_index(name: &str, layer: &str) -> bool {
    name.strip_prefix(layer)
        .and_then(|s| s.strip_prefix('_'))
        .is_some_and(|s| {
            CATALOG.iter().any(|k| {
                let suffix = k.pattern.strip_prefix("{layer}_");
                match (k.subject, suffix) {
                    (Subject::Layer, Some(x)) => x == s,
                    (Subject::LayerBand, Some(x)) => {
                        let head = x.split("{band}").next().unwrap_or(x);
                        s.strip_prefix(head)
                            .is_some_and(|f| f.parse::<f64>().is_ok())
                    }
                    _ => false,
                }
            })
        })
}

/// The layers a run's metrics need (`output.indices`; every layer without them), by index.
pub fn index_layers(cfg: &Config) -> Vec<usize> {
    let layers = &cfg.structure.layers;
    match &cfg.output.indices {
        None => (0..layers.len()).collect(),
        Some(names) => (0..layers.len())
            .filter(|&li| {
                names.iter().any(|n| {
                    layer_of_index(n, &layers[li].name)
                        || (li + 1 == layers.len()
                            && kind_of(cfg, n).is_some_and(|k| {
                                matches!(k.subject, Subject::Deck | Subject::DeckPoint)
                            }))
                })
            })
            .collect(),
    }
}

/// Whether a run's metrics read every observation point (a per-point deck index is reported:
/// `output.indices` names one, or is empty and the structure has a deck), not only the first.
pub fn every_point(cfg: &Config) -> bool {
    let per_point = |n: &str| kind_of(cfg, n).is_some_and(|k| k.subject == Subject::DeckPoint);
    cfg.observation_points().len() > 1
        && match &cfg.output.indices {
            None => deck(cfg),
            Some(names) => names.iter().any(|n| per_point(n)),
        }
}

/// Whether a run's metrics need the bottom layer's bending moment (`output.indices` names a
/// moment index, or is empty).
pub fn moments(cfg: &Config) -> bool {
    let moment = |n: &str| {
        n == DECK_MOMENT || kind_of(cfg, n).is_some_and(|k| k.pattern == DECK_MOMENT_POINT)
    };
    match &cfg.output.indices {
        None => !cfg.structure.layers.is_empty(),
        Some(names) => names.iter().any(|n| moment(n)),
    }
}

/// The name of a per-point index `pattern` (`{j}`) at observation point `j`.
pub fn point_index(pattern: &str, j: usize) -> String {
    pattern.replace("{j}", &j.to_string())
}

/// A rail fastener (pad) whose force a run records: a point spring ∥ dashpot between the top
/// layer and the layer below it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pad {
    /// Its position (m).
    pub x: f64,
    /// The lower layer (the top layer is the upper one).
    pub lower: usize,
    /// Stiffness (N/m) and damping (N·s/m).
    pub stiffness: f64,
    pub damping: f64,
}

impl Pad {
    /// The pad's force (N, compression positive) at relative displacement `du` (m) and
    /// velocity `dv` (m/s) of the top layer over the lower one (down positive).
    pub fn force(&self, du: f64, dv: f64) -> f64 {
        self.stiffness * du + self.damping * dv
    }
}

/// The pads a run of `cfg` records (`output.pad_forces`): at each observation point the point
/// of a discrete coupling from the top layer to another layer nearest to it (its fasteners);
/// none without such a coupling.
pub fn pads_of(cfg: &Config) -> Vec<Pad> {
    let Some(top) = cfg.structure.layers.first() else {
        return Vec::new();
    };
    let fasteners: Vec<(f64, &crate::config::CouplingConfig)> = cfg
        .structure
        .couplings
        .iter()
        .filter(|c| {
            c.upper == top.name
                && c.lower != crate::config::GROUND
                && c.kind == crate::config::CouplingKind::Discrete
        })
        .flat_map(|c| c.positions.iter().map(move |&x| (x, c)))
        .collect();
    if !cfg.output.pad_forces || fasteners.is_empty() {
        return Vec::new();
    }
    cfg.observation_points()
        .iter()
        .map(|&p| {
            let &(x, c) = fasteners
                .iter()
                .min_by(|a, b| (a.0 - p).abs().total_cmp(&(b.0 - p).abs()))
                .expect("fasteners exist");
            Pad {
                x,
                lower: cfg.layer_index(&c.lower).unwrap_or(1),
                stiffness: c.stiffness,
                damping: c.damping,
            }
        })
        .collect()
}

/// The kind of index `name` is, if it is one.
pub fn kind_of(cfg: &Config, name: &str) -> Option<&'static IndexKind> {
    let layers = &cfg.structure.layers;
    CATALOG.iter().find(|k| match k.subject {
        Subject::Layer | Subject::LayerBand => layers
            .iter()
            .any(|l| k.layer_names(cfg, &l.name).iter().any(|n| n == name)),
        _ => k.names(cfg).iter().any(|n| n == name),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A train's indices: every car's comfort, every wheelset's force extremes and the deck's
    /// acceleration; a single layer has no deck; the pads follow the observation points.
    #[test]
    fn a_train_has_indices_per_car_and_per_wheel() {
        let mut cfg = crate::library::presets::paper();
        let mut second = cfg.vehicles[0].clone();
        second.wheels.x_front += 25.0;
        cfg.vehicles.push(second);
        cfg.output.points = vec![40.0, 80.0];
        cfg.output.pad_forces = true;
        let names = index_names(&cfg);
        for n in [
            "car_comfort_aw",
            "car1_comfort_aw",
            "wheel0_force_max",
            "wheel7_force_min",
            "pad0_force_range",
            "pad1_force_range",
            DECK,
            "deck_acc_max_p1",
            "deck_disp_max_p0",
        ] {
            assert!(names.iter().any(|k| k == n), "{n}");
        }
        assert!(!names.iter().any(|k| k == "car2_comfort_aw"
            || k == "wheel8_force_max"
            || k == "pad2_force_range"
            || k == "deck_acc_max_p2"));
        assert!(every_point(&cfg), "every index asked: every point recorded");
        assert!(kind_of(&cfg, "rail_acc_rms").is_some_and(|k| k.unit == "m/s²"));
        assert!(kind_of(&cfg, "pad1_force_range").is_some_and(|k| k.unit == "N"));
        assert!(kind_of(&cfg, "rail_acc_L1000").is_none());
        cfg.output.indices = Some(vec![DECK.into()]);
        assert_eq!(index_layers(&cfg), vec![cfg.structure.layers.len() - 1]);
        assert!(
            !every_point(&cfg),
            "the first point's deck index: the first point only"
        );
        cfg.output.indices = Some(vec!["deck_disp_max_p1".into()]);
        assert_eq!(index_layers(&cfg), vec![cfg.structure.layers.len() - 1]);
        assert!(every_point(&cfg));
        cfg.structure.layers.truncate(1);
        assert!(!index_names(&cfg).iter().any(|k| k == DECK));
    }

    #[test]
    fn band_levels_and_raw_peaks_belong_to_their_layer() {
        let mut cfg = crate::library::presets::paper();
        cfg.output.band_levels = vec![500.0, 1000.0];
        cfg.output.band_limit = Some(2000.0);
        let names = index_names(&cfg);
        for n in [
            "rail_acc_L500",
            "slab_acc_L1000",
            "rail_acc_Leq",
            "bridge_acc_max_raw",
        ] {
            assert!(names.iter().any(|k| k == n), "{n}");
            assert!(layer_of_index(n, n.split('_').next().unwrap()), "{n}");
        }
        assert!(!layer_of_index("rail_acc_Lx", "rail"));
        assert!(!layer_of_index("railx_acc_max", "rail"));
        assert_eq!(
            kind_of(&cfg, "rail_acc_L500").map(|k| k.band),
            Some(Band::ThirdOctave)
        );
    }
}
