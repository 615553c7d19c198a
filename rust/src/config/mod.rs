//! Run configuration: the serde schema shared with the Python layer (which serialises its
//! dataclasses to this JSON shape) and the up-front validation of every field.
//!
//! Units are SI throughout (m, s, kg, N, Pa). Displacements are positive downward.

use crate::error::{Result, VtbError};
use crate::model::dampers::{DamperKind, DamperParams};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Name used in coupling definitions for the fixed ground below the lowest layer.
pub const GROUND: &str = "ground";

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The track–bridge beam stack: its length, layers and couplings.
    pub structure: StructureConfig,
    /// How the layers are discretised (modal, hybrid FE–SEA or finite elements).
    #[serde(default)]
    pub discretisation: DiscretisationConfig,
    /// Cars of the train, all running at `speed`. Empty for the moving-load mode.
    #[serde(default)]
    pub vehicles: Vec<VehicleConfig>,
    /// Constant moving forces (moving-load mode, bridge checks); may be combined with vehicles.
    #[serde(default)]
    pub forces: Vec<MovingForceConfig>,
    /// Speed of all vehicles and forces (m/s), in the +x direction.
    pub speed: f64,
    /// Time integration, contact iteration, start and end of the run.
    #[serde(default)]
    pub solver: SolverConfig,
    /// Observation points and the metrics' analysis window.
    #[serde(default)]
    pub output: OutputConfig,
    /// The tuned inerter dampers between two layers (optional; none by default): the group
    /// the studies vary.
    #[serde(default)]
    pub tids: Option<DamperGroup>,
    /// Further damper groups, each of its own kind, tuning and positions; their internal
    /// nodes follow those of `tids`.
    #[serde(default)]
    pub dampers: Vec<DamperGroup>,
    /// Field paths (e.g. `"speed"`, `"structure.couplings[3].stiffness"`) whose values may lie
    /// outside their plausible range (docs/limits.md, `vtb.plausible_ranges()`); any other
    /// such value is refused as a likely unit mistake.
    #[serde(default)]
    pub accept_implausible: Vec<String>,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StructureConfig {
    /// Common length L of all layers (m); x runs from 0 to L.
    pub length: f64,
    /// Beam layers from top (the layer the wheels run on) to bottom.
    pub layers: Vec<LayerConfig>,
    /// Spring–dashpot connections between layers, or between a layer and the ground.
    #[serde(default)]
    pub couplings: Vec<CouplingConfig>,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LayerConfig {
    /// Name (no unit) by which couplings, dampers, outputs and metrics refer to the layer.
    pub name: String,
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Cross-section area A (m²).
    pub area: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Second moment of area I (m⁴).
    pub inertia: f64,
    /// Number of sine modes (count) of the modal/hybrid basis (the 4 Hermite DOFs come on top).
    pub modes: usize,
    /// Extra sine modes (count) treated as local (FE–SEA) modes by the hybrid method.
    #[serde(default)]
    pub local_modes: usize,
    /// Shear modulus G (Pa). Given with `shear_coefficient`, the layer is a Timoshenko beam
    /// (shear deformation and rotary inertia ρI); finite-element method only.
    #[serde(default)]
    pub shear_modulus: Option<f64>,
    /// Shear coefficient κ (−) of the cross-section (a rail in vertical bending: ≈ 0.4).
    #[serde(default)]
    pub shear_coefficient: Option<f64>,
    /// Longest element (m) of this layer's finite-element mesh, whose nodes then fall on every
    /// discrete coupling point of the layer (fasteners, piers, damper attachments). `None`:
    /// the uniform mesh of `discretisation.fem_elements` elements.
    #[serde(default)]
    pub element_length: Option<f64>,
    /// Rayleigh damping of the layer: a ratio (−) at two frequencies (Hz), or α (1/s) and β (s).
    pub damping: RayleighConfig,
    /// Where the layer begins (m); 0 when absent. A layer over part of the structure (a
    /// bridge girder between approach embankments) needs finite elements; its ends are free
    /// unless couplings hold them.
    #[serde(default)]
    pub start: Option<f64>,
    /// Where the layer ends (m); `structure.length` when absent.
    #[serde(default)]
    pub end: Option<f64>,
    /// Positions (m) where the layer is cut: a joint between simply supported spans or slabs,
    /// across which no displacement, rotation, shear or moment passes (only the couplings on
    /// either side hold the two ends). Finite elements only; a point exactly at a joint
    /// belongs to the part on its right.
    #[serde(default)]
    pub joints: Vec<f64>,
}

/// Rayleigh damping C = αM + βK of one layer.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RayleighConfig {
    /// Damping ratio `ratio` at the two frequencies `f1` < `f2` (Hz).
    Ratio { ratio: f64, f1: f64, f2: f64 },
    /// Explicit coefficients α (1/s) and β (s).
    Coefficients { alpha: f64, beta: f64 },
}

impl RayleighConfig {
    /// (α, β) of the layer.
    pub fn coefficients(&self) -> (f64, f64) {
        match *self {
            RayleighConfig::Coefficients { alpha, beta } => (alpha, beta),
            RayleighConfig::Ratio { ratio, f1, f2 } => {
                let (w1, w2) = (
                    2.0 * std::f64::consts::PI * f1,
                    2.0 * std::f64::consts::PI * f2,
                );
                (2.0 * ratio * w1 * w2 / (w1 + w2), 2.0 * ratio / (w1 + w2))
            }
        }
    }
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CouplingKind {
    /// Point springs at `positions` (stiffness N/m, damping N·s/m per point).
    Discrete,
    /// Distributed over the whole length (stiffness N/m², damping N·s/m² per unit length).
    Continuous,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CouplingConfig {
    /// The upper layer's name (no unit).
    pub upper: String,
    /// The lower layer's name, or `"ground"` (no unit).
    pub lower: String,
    /// `"discrete"` (point springs at `positions`) or `"continuous"` (along the whole length).
    pub kind: CouplingKind,
    /// Stiffness (N/m per point if discrete, N/m² per unit length if continuous).
    pub stiffness: f64,
    /// Viscous damping (N·s/m per point if discrete, N·s/m² per unit length if continuous).
    #[serde(default)]
    pub damping: f64,
    /// Point positions for discrete couplings (m).
    #[serde(default)]
    pub positions: Vec<f64>,
    /// Where a continuous coupling begins (m); the start of the part both layers cover (of the
    /// upper layer, for the ground) when absent. Finite-element layers only.
    #[serde(default)]
    pub start: Option<f64>,
    /// Where a continuous coupling ends (m); the end of the part both layers cover when absent.
    #[serde(default)]
    pub end: Option<f64>,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Hermite + sine modes, all global, no correction (article §2.1).
    #[default]
    Modal,
    /// Modal plus the FE–SEA correction of the local rail modes (article §2.2).
    Hybrid,
    /// Conventional cubic Hermite beam elements (article §3.3 reference).
    Fem,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DiscretisationConfig {
    /// `"modal"`, `"hybrid"` (modal with the FE–SEA correction of the rail) or `"fem"`.
    #[serde(default)]
    pub method: Method,
    /// Elements per layer (count) of the uniform FEM mesh.
    #[serde(default = "default_fem_elements")]
    pub fem_elements: usize,
    /// Representative excitation frequency ω_r (rad/s) of the FE–SEA correction. `None`: the
    /// geometric centre 2π·v/√(λ_min·λ_max) of the irregularity's excitation band (a
    /// spectrum's band, or the wavelength of a corrugation or dip), else the geometric centre
    /// of the local modes' frequency range (docs/fesea.md).
    #[serde(default)]
    pub omega_r: Option<f64>,
    /// Global–local coupling of the FE–SEA correction: `"full"` or the article's `"mass"`.
    #[serde(default)]
    pub fesea_coupling: FeSeaCoupling,
    /// Add (true/false) the local modes' static deflection to the hybrid rail's displacement outputs
    /// (docs/fesea.md; docs/model.md §6 leaves it out, `false` follows it).
    #[serde(default = "default_true")]
    pub local_deflection: bool,
    /// Finite-element rails (true/false): each wheel also sees the static deflection of the rail element
    /// under it with the element's nodes fixed (in series with the Hertz contact), which the
    /// element's interpolation misses; keeps the static wheel–rail stiffness independent of the
    /// wheel's position in its element (docs/track-models.md).
    #[serde(default = "default_true")]
    pub element_flexibility: bool,
    /// Cut-off (Hz) of the complex-modal synthesis of a finite-element structure: `None` steps
    /// the finite elements (Newmark); f_c keeps the complex modes of modulus below 2π·f_c plus the
    /// rail's static residual, and steps each mode exactly (docs/synthesis.md). Needs
    /// `method = "fem"` and the structure's reduction (`vtb.synthesis.reduction`).
    #[serde(default)]
    pub synthesis_cutoff: Option<f64>,
}

fn default_true() -> bool {
    true
}

/// How the FE–SEA correction couples the rail's global functions to its local modes.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum FeSeaCoupling {
    /// The exact coupling D_gj = K_gj + iωC_gj − ω²M_gj (bending and rail springs included),
    /// split into its exact frequency-independent part and residual resonators classed by
    /// the resonant band (docs/fesea.md).
    #[default]
    Full,
    /// The article's reading: mass coupling only, D_gj ≈ −ω²M_gj (docs/model.md §6).
    Mass,
}

fn default_fem_elements() -> usize {
    251
}

impl Default for DiscretisationConfig {
    fn default() -> Self {
        Self {
            method: Method::Modal,
            fem_elements: default_fem_elements(),
            omega_r: None,
            fesea_coupling: FeSeaCoupling::Full,
            local_deflection: true,
            element_flexibility: true,
            synthesis_cutoff: None,
        }
    }
}

/// Zhai's 10-DOF vertical car (docs/model.md §3). Suspension constants are per bogie (secondary)
/// and per wheelset (primary), both sides lumped.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VehicleConfig {
    /// Car body mass (kg).
    pub m_c: f64,
    /// Car body pitch inertia (kg·m²).
    pub j_c: f64,
    /// Bogie mass (kg).
    pub m_t: f64,
    /// Bogie pitch inertia (kg·m²).
    pub j_t: f64,
    /// Wheelset mass (kg).
    pub m_w: f64,
    /// Secondary suspension stiffness per bogie (N/m).
    pub k_s: f64,
    /// Secondary suspension damping per bogie (N·s/m).
    pub c_s: f64,
    /// Primary suspension stiffness per wheelset (N/m).
    pub k_p: f64,
    /// Primary suspension damping per wheelset (N·s/m).
    pub c_p: f64,
    /// Half the distance between the bogie centres (m).
    pub l_c: f64,
    /// Half the bogie wheelbase (m).
    pub l_t: f64,
    /// Wheel radius (m); sets the Hertz constant G = 4.57·R^−0.149·1e−8 m/N^(2/3).
    pub wheel_radius: f64,
    /// Overrides the Hertz constant G (m/N^(2/3)).
    #[serde(default)]
    pub contact_constant: Option<f64>,
    /// Position of the leading wheelset at t = 0 (m).
    pub x_front: f64,
    /// Identical rails (count) sharing each wheelset's load. The modelled top layer is one of them
    /// and carries 1/`rails` of every axle load through its own Hertz spring (2: a full car
    /// on one of its two rails, which is what the article's 0.97 mm rail / 0.46 mm slab
    /// amplitudes imply).
    #[serde(default = "default_rails")]
    pub rails: usize,
    /// Distributed contact (true/false): each wheel's force is spread along the rail over its
    /// Hertz contact patch, the parabolic line load of an elliptical contact whose half-length
    /// (m) follows from Hertz theory for the static wheel load, `wheel_radius` and
    /// `rail_crown_radius` (steel on steel); the rail displacement the contact sees is the same
    /// load-weighted average. Needs a finite-element rail. `false`: a point contact.
    #[serde(default)]
    pub contact_patch: bool,
    /// Crown radius of the rail head (m) across the rail, for the contact patch.
    #[serde(default = "default_rail_crown_radius")]
    pub rail_crown_radius: f64,
    /// Vehicle model (docs/vehicles.md): `"car"` (Zhai's 10-DOF car) or `"quarter_car"` (a
    /// sprung mass `m_c` on `k_p` ∥ `c_p` over one wheel `m_w`; the bogie and pitch fields 0).
    /// Every vehicle of a run is of the same model.
    #[serde(default)]
    pub model: crate::model::vehicle::VehicleKind,
}

fn default_rails() -> usize {
    2
}

pub(crate) fn default_rail_crown_radius() -> f64 {
    0.3
}

impl VehicleConfig {
    pub fn hertz_constant(&self) -> f64 {
        self.contact_constant
            .unwrap_or_else(|| 4.57e-8 * self.wheel_radius.powf(-0.149))
    }

    /// Wheel positions at t = 0, front to rear.
    pub fn wheel_offsets(&self) -> Vec<f64> {
        self.model.model(self).wheel_offsets(self.x_front)
    }

    /// Number of degrees of freedom of this vehicle's model.
    pub fn n_dofs(&self) -> usize {
        self.model.model(self).dofs().len()
    }

    /// Number of wheels of this vehicle's model.
    pub fn n_wheels(&self) -> usize {
        self.model.model(self).wheel_dofs().len()
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MovingForceConfig {
    /// Force (N), positive downward.
    pub magnitude: f64,
    /// Position at t = 0 (m).
    pub x0: f64,
    /// Name of the layer the force acts on (no unit); the top layer when absent.
    #[serde(default)]
    pub layer: Option<String>,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum InitialState {
    /// Static equilibrium of the loaded system (contact included).
    #[default]
    Static,
    /// Structure at rest and undeformed (Frýba's zero initial conditions); vehicles still
    /// start in their own static equilibrium on the undeformed track.
    Rest,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolverConfig {
    /// Newmark time step (s).
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// End time (s). Default: when the leading wheel (or force) reaches L − `end_margin`, or
    /// `tail` after the last one has left the structure.
    #[serde(default)]
    pub t_end: Option<f64>,
    /// Free vibration (s) recorded after the last wheel or force has left the structure
    /// (passed x = L): the default end time becomes that moment plus `tail`. Wheels beyond
    /// x = L run on a rigid track and no longer load the structure; as they cross the rail's
    /// end, a tail needs `edge_ramp` (or `vtb.track_zones`) or `edge_step`.
    #[serde(default)]
    pub tail: Option<f64>,
    /// Length (m) at each end of the rail over which a wheel's force is handed between the
    /// rail and the rigid track beyond the structure: the rail carries a raised-cosine share
    /// of it, 0 at the rail's end and 1 at `edge_ramp` from it, so that wheels join and leave
    /// the structure without a step (docs/zones.md; `vtb.track_zones` sets 10 m). 0: no
    /// hand-over, and a wheel that would cross an end of the rail during the run is refused
    /// unless `edge_step` asks for the step it meets there. Finite-element or modal rails.
    #[serde(default = "default_edge_ramp")]
    pub edge_ramp: f64,
    /// true/false: with `edge_ramp` = 0, let wheels cross an end of the rail and meet the
    /// track's static deflection there as a step (an impact no real track has; the FE–SEA
    /// hybrid, which takes no ramp, needs it for wheels that leave the rail).
    #[serde(default)]
    pub edge_step: bool,
    /// Distance kept between the leading wheel and the end of the structure for the default
    /// end time (m).
    #[serde(default = "default_end_margin")]
    pub end_margin: f64,
    /// Gravitational acceleration (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity: f64,
    /// Contact iteration stops when every wheel's residual `|P − h(δ)|` (force against the Hertz
    /// law at its compression) is at most `contact_tol` (−) × (static wheel load).
    #[serde(default = "default_contact_tol")]
    pub contact_tol: f64,
    /// Newton iterations (count) of the contact per step before a `ConvergenceError`.
    #[serde(default = "default_contact_max_iter")]
    pub contact_max_iter: usize,
    /// `"static"`: the static equilibrium of the loaded system; `"rest"`: the structure
    /// undeformed and at rest (docs/model.md §7).
    #[serde(default)]
    pub initial_state: InitialState,
    /// Memory a run may allocate (bytes): a run whose matrices or histories are estimated to
    /// need more is refused up front (docs/limits.md).
    #[serde(default = "default_memory_budget")]
    pub memory_budget: f64,
    /// Distance (m) over which the irregularity under every wheel grows from zero to its full
    /// value, a raised cosine in the distance travelled since t = 0 (docs/model.md §4): the
    /// run starts in the static equilibrium of the smooth track, with the wheels' vertical
    /// velocity in step with the profile. 0 applies the profile in full from t = 0; the wheels
    /// then start at rest on a profile that moves under them at the running speed, a start-up
    /// impact that sets the car body's maximum acceleration.
    #[serde(default = "default_fade_in")]
    pub fade_in: f64,
}

fn default_dt() -> f64 {
    5e-5
}
fn default_edge_ramp() -> f64 {
    0.0
}
fn default_end_margin() -> f64 {
    1.0
}
fn default_gravity() -> f64 {
    9.81
}
fn default_contact_tol() -> f64 {
    1e-10
}
fn default_contact_max_iter() -> usize {
    50
}
fn default_fade_in() -> f64 {
    2.0
}

fn default_memory_budget() -> f64 {
    8e9
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            dt: default_dt(),
            t_end: None,
            tail: None,
            edge_ramp: default_edge_ramp(),
            edge_step: false,
            end_margin: default_end_margin(),
            fade_in: default_fade_in(),
            gravity: default_gravity(),
            contact_tol: default_contact_tol(),
            contact_max_iter: default_contact_max_iter(),
            initial_state: InitialState::Static,
            memory_budget: default_memory_budget(),
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Observation points (m); empty means x = L/2. Metrics use the first point.
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
        }
    }
}

fn default_deck_band() -> f64 {
    30.0
}

/// A group of identical dampers of one kind between `upper` and `lower` (docs/dampers.md), at
/// `positions` or at x0 + i·spacing, i < count.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DamperGroup {
    /// `"tid"` (spring ∥ dashpot, then inerter), `"tvmd"` (spring, then inerter ∥ dashpot)
    /// or `"tmd"` (a mass `inertance` on spring ∥ dashpot; `lower` must be `"ground"`).
    #[serde(default)]
    pub kind: DamperKind,
    /// Inertance b (kg) of each damper (a TMD's mass), from its internal node to the lower layer.
    pub inertance: f64,
    /// Spring stiffness k (N/m) of each damper, from the upper layer to its internal node.
    pub stiffness: f64,
    /// Dashpot damping c (N·s/m) of each damper: parallel to the spring (TID, TMD) or to the
    /// inerter (TVMD).
    pub damping: f64,
    /// Number of dampers (count) of the pattern x0 + i·spacing; omitted with `positions`.
    #[serde(default)]
    pub count: Option<usize>,
    /// Position of the pattern's first damper (m).
    #[serde(default)]
    pub x0: Option<f64>,
    /// Distance between neighbouring dampers of the pattern (m); needed when count > 1.
    #[serde(default)]
    pub spacing: Option<f64>,
    /// Explicit positions of the dampers (m), instead of the pattern.
    #[serde(default)]
    pub positions: Option<Vec<f64>>,
    /// The layer the springs attach to (name, no unit).
    #[serde(default = "default_tid_upper")]
    pub upper: String,
    /// The layer the inerters attach to (name, no unit), or `"ground"`: an inerter to the
    /// fixed ground is a mass b on the internal node (a TID to the ground is a TMD).
    #[serde(default = "default_tid_lower")]
    pub lower: String,
}

impl DamperGroup {
    /// The dampers' positions (m), from `positions` or the pattern (validated configs).
    pub fn locations(&self) -> Vec<f64> {
        match &self.positions {
            Some(p) => p.clone(),
            None => {
                let (x0, h) = (self.x0.unwrap_or(0.0), self.spacing.unwrap_or(0.0));
                (0..self.count.unwrap_or(0))
                    .map(|i| x0 + i as f64 * h)
                    .collect()
            }
        }
    }

    /// The parameters of each of its dampers.
    pub fn params(&self) -> DamperParams {
        DamperParams {
            kind: self.kind,
            stiffness: self.stiffness,
            damping: self.damping,
            inertance: self.inertance,
        }
    }
}

fn default_tid_upper() -> String {
    "rail".into()
}
fn default_tid_lower() -> String {
    "slab".into()
}

/// What the wheels roll on, sampled on a uniform grid x0 + i·dx and linearly interpolated:
/// the rail's irregularity r(x) (m, positive = dip) and each wheel's own tread irregularity
/// as a function of the wheel's position x (m, positive = the wheel centre drops, as over a
/// dip; a wheel flat repeats once per wheel circumference).
#[derive(Debug, Clone, Default)]
pub struct Profile {
    pub x0: f64,
    pub dx: f64,
    pub values: Vec<f64>,
    /// Empty (round wheels), or one row per wheel of the run (vehicles in order, wheelsets
    /// front to rear) on the grid of `values`; an empty row is a round wheel.
    pub treads: Vec<Vec<f64>>,
}

impl Profile {
    pub fn flat() -> Self {
        Self {
            x0: 0.0,
            dx: 1.0,
            values: Vec::new(),
            treads: Vec::new(),
        }
    }

    /// The grid interval holding x and the weight of its right end.
    #[inline]
    fn locate(&self, x: f64) -> (usize, f64) {
        let s = (x - self.x0) / self.dx;
        let i = (s.floor() as isize).clamp(0, self.values.len() as isize - 2) as usize;
        (i, s - i as f64)
    }

    /// r(x) of the rail; an empty profile is a perfectly smooth rail.
    #[inline]
    pub fn at(&self, x: f64) -> f64 {
        if self.values.is_empty() {
            return 0.0;
        }
        let (i, w) = self.locate(x);
        self.values[i] * (1.0 - w) + self.values[i + 1] * w
    }

    /// The irregularity under wheel `wheel` at position x: the rail's plus the wheel's tread.
    #[inline]
    pub fn under(&self, wheel: usize, x: f64) -> f64 {
        match self.treads.get(wheel) {
            Some(t) if !t.is_empty() => {
                let (i, w) = self.locate(x);
                (self.values[i] + t[i]) * (1.0 - w) + (self.values[i + 1] + t[i + 1]) * w
            }
            _ => self.at(x),
        }
    }

    fn x_last(&self) -> f64 {
        self.x0 + self.dx * (self.values.len() as f64 - 1.0)
    }
}

// ---------------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------------

/// Largest magnitude accepted for any parameter: beyond it products of parameters overflow.
pub const MAX_MAGNITUDE: f64 = 1e30;

fn finite(field: &str, v: f64) -> Result<f64> {
    if !v.is_finite() {
        Err(VtbError::config(
            field,
            format!("{v:?}"),
            "must be a finite number",
        ))
    } else if v.abs() > MAX_MAGNITUDE {
        Err(VtbError::config(
            field,
            format!("{v:?}"),
            format!("magnitude beyond {MAX_MAGNITUDE:e} is not physical"),
        ))
    } else {
        Ok(v)
    }
}

pub(crate) fn positive(field: &str, v: f64) -> Result<f64> {
    finite(field, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(VtbError::config(field, format!("{v:?}"), "must be > 0"))
    }
}

pub(crate) fn non_negative(field: &str, v: f64) -> Result<f64> {
    finite(field, v)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(VtbError::config(field, format!("{v:?}"), "must be >= 0"))
    }
}

fn within(field: &str, v: f64, lo: f64, hi: f64, what: &str) -> Result<f64> {
    finite(field, v)?;
    if v >= lo - 1e-12 && v <= hi + 1e-12 {
        Ok(v)
    } else {
        Err(VtbError::config(
            field,
            format!("{v:?}"),
            format!("must lie within [{lo}, {hi}] ({what})"),
        ))
    }
}

/// Upper bound on time steps of one run (guards against hangs and memory blow-ups).
pub const MAX_STEPS: usize = 20_000_000;
/// Upper bound on sine modes of one layer.
pub const MAX_MODES: usize = 20_000;
/// Upper bound on the dampers of a run: their coupling is a dense count × count matrix,
/// inverted once per run (O(count³)) and applied every step (O(count²)).
pub const MAX_TIDS: usize = 2_000;
/// Time-step counts within this of a whole number are whole (t_end is a multiple of dt).
const STEP_TOL: f64 = 1e-6;
/// Upper bound on FEM elements per layer.
pub const MAX_ELEMENTS: usize = 200_000;

impl Config {
    /// Parses the JSON form; a field of the wrong type or range is reported with its dotted
    /// path (`tids.count`, `structure.layers[0].modes`) and the value found there.
    pub fn from_json(text: &str) -> Result<Config> {
        let tree: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| VtbError::config("<json>", "(text)", e.to_string()))?;
        serde_path_to_error::deserialize(&tree).map_err(|e| {
            let reason = e.inner().to_string();
            let mut path = e.path().to_string();
            // An unknown field is reported at its parent: name the field itself.
            if let Some(name) = reason
                .strip_prefix("unknown field `")
                .and_then(|r| r.split('`').next())
            {
                path = if path == "." {
                    name.to_string()
                } else {
                    format!("{path}.{name}")
                };
            }
            let value =
                value_at(&tree, &path).map_or_else(|| "(missing)".to_string(), |v| v.to_string());
            let field = if path == "." {
                "<config>".to_string()
            } else {
                path
            };
            VtbError::config(field, value, reason)
        })
    }

    /// The JSON schema of the configuration (fields, types, defaults, documentation): the
    /// one definition the Python layer derives its defaults from and is tested against.
    pub fn schema() -> String {
        serde_json::to_string(&schemars::schema_for!(Config)).expect("schema serialises")
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("config serialises")
    }

    pub fn layer_index(&self, name: &str) -> Option<usize> {
        self.structure.layers.iter().position(|l| l.name == name)
    }

    /// Number of time steps and the step actually used (the end time is rounded to a whole
    /// number of steps).
    pub fn n_steps(&self) -> usize {
        let t_end = self.t_end();
        (t_end / self.solver.dt).round().max(1.0) as usize
    }

    /// End time of the run (s), where its last step lands: explicit (validated to be a whole
    /// number of steps), or the whole step nearest to the leading wheel/force reaching
    /// L − end_margin.
    pub fn t_end(&self) -> f64 {
        if let Some(t) = self.solver.t_end {
            return t;
        }
        let dt = self.solver.dt;
        let t = self.lead_time();
        if dt > 0.0 && t.is_finite() {
            (t / dt).round() * dt
        } else {
            t
        }
    }

    /// Time (s) at which the leading wheel/force reaches L − end_margin, or with
    /// `solver.tail` the last one has passed L plus the tail.
    fn lead_time(&self) -> f64 {
        let positions = || {
            self.vehicles
                .iter()
                .flat_map(|v| v.wheel_offsets())
                .chain(self.forces.iter().map(|f| f.x0))
        };
        let (lead, last) = (
            positions().fold(f64::NEG_INFINITY, f64::max),
            positions().fold(f64::INFINITY, f64::min),
        );
        if !(self.speed > 0.0 && lead.is_finite()) {
            return 0.0;
        }
        let l = self.structure.length;
        match self.solver.tail {
            Some(tail) => ((l - last) / self.speed).max(0.0) + tail,
            None => ((l - self.solver.end_margin - lead) / self.speed).max(0.0),
        }
    }

    /// The share of the irregularity under the wheels at time `t` (s): a raised cosine in the
    /// distance travelled, v·t, over `solver.fade_in`. A stationary run (speed 0) has nothing
    /// moving under its wheels and takes the profile in full from its static state.
    pub fn irregularity_share(&self, t: f64) -> f64 {
        let s = self.speed * t;
        if self.speed == 0.0 || s >= self.solver.fade_in {
            1.0
        } else {
            0.5 * (1.0 - (std::f64::consts::PI * s / self.solver.fade_in).cos())
        }
    }

    /// The layers a run's metrics need (`output.indices`; every layer without them), by index.
    pub fn index_layers(&self) -> Vec<usize> {
        let layers = &self.structure.layers;
        match &self.output.indices {
            None => (0..layers.len()).collect(),
            Some(names) => (0..layers.len())
                .filter(|&li| {
                    names.iter().any(|n| {
                        crate::outputs::layer_of_index(n, &layers[li].name)
                            || (n == crate::outputs::DECK && li + 1 == layers.len())
                    })
                })
                .collect(),
        }
    }

    /// The stretch (m) the wheels roll over during the run, from the rearmost wheel's start
    /// to the leading wheel's end; `None` without vehicles or with a non-finite end time.
    pub fn wheel_travel(&self) -> Option<(f64, f64)> {
        let travel = self.speed * self.n_steps() as f64 * self.solver.dt;
        let offsets = self.vehicles.iter().flat_map(|v| v.wheel_offsets());
        let lo = offsets.clone().fold(f64::INFINITY, f64::min);
        let hi = offsets.fold(f64::NEG_INFINITY, f64::max) + travel;
        (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
    }

    /// [start, end] of layer `i` (m).
    pub fn extent(&self, i: usize) -> (f64, f64) {
        let l = &self.structure.layers[i];
        (
            l.start.unwrap_or(0.0),
            l.end.unwrap_or(self.structure.length),
        )
    }

    /// [start, end] (m) over which a continuous coupling of validated layers acts.
    pub fn coupling_range(&self, c: &CouplingConfig) -> (f64, f64) {
        let (a0, a1) = self.extent(self.layer_index(&c.upper).expect("validated"));
        let (b0, b1) = self
            .layer_index(&c.lower)
            .map_or((a0, a1), |l| self.extent(l));
        (c.start.unwrap_or(a0.max(b0)), c.end.unwrap_or(a1.min(b1)))
    }

    /// `x` (field `field`) lies on layer `i`, and not on one of its joints.
    fn on_layer(&self, field: &str, x: f64, i: usize) -> Result<f64> {
        let (a, b) = self.extent(i);
        let layer = &self.structure.layers[i];
        let name = &layer.name;
        within(field, x, a, b, &format!("layer {name:?}"))?;
        if layer
            .joints
            .iter()
            .any(|&j| (x - j).abs() <= 1e-9 * (1.0 + j.abs()))
        {
            return Err(VtbError::config(
                field,
                x,
                format!("lies on a joint of layer {name:?}: place it on one side"),
            ));
        }
        Ok(x)
    }

    /// Observation points, defaulting to mid-length.
    pub fn observation_points(&self) -> Vec<f64> {
        if self.output.points.is_empty() {
            vec![0.5 * self.structure.length]
        } else {
            self.output.points.clone()
        }
    }

    /// Checks every field; the first problem found is returned with its dotted path. Each
    /// sub-configuration checks its own fields (`validate(&self, path)`); the phases here add
    /// what relates one part to another: names, positions on layers, the method, the run.
    pub fn validate(&self, profile: &Profile) -> Result<()> {
        crate::check::plausibility::check(self)?;
        let length = self.validate_structure()?;
        self.validate_discretisation()?;
        let (dt, travel) = self.validate_run()?;
        self.validate_loads(travel, profile)?;
        self.validate_output(dt)?;
        self.validate_profile(profile)?;
        self.validate_treads(profile)?;
        self.validate_dampers(length)?;
        crate::check::budget::check_model(self)
    }

    /// Layers (names, meshes, extents, bases) and couplings (layers, positions, ranges);
    /// returns the structure's length.
    fn validate_structure(&self) -> Result<f64> {
        let s = &self.structure;
        let length = positive("structure.length", s.length)?;
        if s.layers.is_empty() {
            return Err(VtbError::config(
                "structure.layers",
                "[]",
                "at least one layer is required",
            ));
        }
        for (i, l) in s.layers.iter().enumerate() {
            let p = format!("structure.layers[{i}]");
            l.validate(&p)?;
            if s.layers[..i].iter().any(|o| o.name == l.name) {
                return Err(VtbError::config(
                    format!("{p}.name"),
                    format!("{:?}", l.name),
                    "layer names must be unique",
                ));
            }
            self.validate_layer_mesh(l, &p, length)?;
            self.validate_extent(l, &p, length)?;
            if self.discretisation.method != Method::Fem {
                if l.modes == 0 {
                    return Err(VtbError::config(
                        format!("{p}.modes"),
                        0,
                        "at least one sine mode is required",
                    ));
                }
                if l.modes + l.local_modes > MAX_MODES {
                    return Err(VtbError::config(
                        format!("{p}.modes"),
                        l.modes + l.local_modes,
                        format!("modes + local_modes must be <= {MAX_MODES}"),
                    ));
                }
            }
        }
        for (i, c) in s.couplings.iter().enumerate() {
            let p = format!("structure.couplings[{i}]");
            let (upper, _) = self.layer_pair(
                &p,
                &c.upper,
                &c.lower,
                "a layer cannot be coupled to itself",
            )?;
            c.validate(&p)?;
            match c.kind {
                CouplingKind::Discrete => {
                    for (j, &x) in c.positions.iter().enumerate() {
                        let field = format!("{p}.positions[{j}]");
                        self.on_layer(&field, x, upper)?;
                        if let Some(lower) = self.layer_index(&c.lower) {
                            self.on_layer(&field, x, lower)?;
                        }
                    }
                }
                CouplingKind::Continuous => self.validate_coupling_range(c, &p, upper)?,
            }
        }
        Ok(length)
    }

    /// The discretisation against the structure.
    fn validate_discretisation(&self) -> Result<()> {
        let s = &self.structure;
        let d = &self.discretisation;
        if let Some(fc) = d.synthesis_cutoff {
            let fc = positive("discretisation.synthesis_cutoff", fc)?;
            if d.method != Method::Fem {
                return Err(VtbError::config(
                    "discretisation.synthesis_cutoff",
                    fc,
                    format!(
                        "the synthesis reduces a finite-element structure (discretisation.method = \
                         \"fem\", not {:?})",
                        d.method
                    ),
                ));
            }
        }
        if d.method == Method::Fem && !(2..=MAX_ELEMENTS).contains(&d.fem_elements) {
            return Err(VtbError::config(
                "discretisation.fem_elements",
                d.fem_elements,
                format!("must be within [2, {MAX_ELEMENTS}]"),
            ));
        }
        if let Some(w) = d.omega_r {
            positive("discretisation.omega_r", w)?;
        }
        if d.method == Method::Hybrid && s.layers[0].local_modes == 0 {
            return Err(VtbError::config(
                "structure.layers[0].local_modes",
                0,
                "the hybrid method needs local modes on the top layer",
            ));
        }
        Ok(())
    }

    /// Speed, solver and the run's end; returns the time step and the distance travelled.
    fn validate_run(&self) -> Result<(f64, f64)> {
        let speed = non_negative("speed", self.speed)?;
        let sv = &self.solver;
        sv.validate()?;
        let dt = sv.dt;
        if sv.edge_ramp > 0.0 && self.discretisation.method == Method::Hybrid {
            return Err(VtbError::config(
                "solver.edge_ramp",
                sv.edge_ramp,
                "the FE–SEA hybrid's rail terms take a wheel's whole force: use 0 (with \
                 solver.edge_step = true for wheels that cross an end of the rail), or \
                 discretisation.method = \"fem\" or \"modal\"",
            ));
        }
        if sv.t_end.is_none() && speed == 0.0 {
            return Err(VtbError::config(
                "solver.t_end",
                "None",
                "an end time is required when speed = 0",
            ));
        }
        let t_end = self.t_end();
        if !(t_end > 0.0) {
            return Err(VtbError::config(
                "solver.t_end",
                t_end,
                "the run would have no duration: the leading wheel/force starts within end_margin of the end of the structure",
            ));
        }
        let steps = t_end / dt;
        if steps > MAX_STEPS as f64 {
            return Err(VtbError::config(
                "solver.dt",
                dt,
                format!("t_end / dt = {steps:.3e} steps exceeds the limit of {MAX_STEPS}"),
            ));
        }
        let travel = speed * self.n_steps() as f64 * dt;
        Ok((dt, travel))
    }

    /// Vehicles and moving forces: their own fields, the method, the profile under them.
    fn validate_loads(&self, travel: f64, profile: &Profile) -> Result<()> {
        for (i, v) in self.vehicles.iter().enumerate() {
            let p = format!("vehicles[{i}]");
            v.validate(&p)?;
            // The engines and the records hold one vehicle model per run.
            if v.model != self.vehicles[0].model {
                return Err(VtbError::config(
                    format!("{p}.model"),
                    v.model.name(),
                    format!(
                        "every vehicle of a run is of one model; vehicles[0] is a {:?}",
                        self.vehicles[0].model.name()
                    ),
                ));
            }
            if v.contact_patch && self.discretisation.method != Method::Fem {
                return Err(VtbError::config(
                    format!("{p}.contact_patch"),
                    true,
                    format!(
                        "a distributed contact needs a finite-element rail (discretisation.method \
                         = \"fem\"), not {:?}",
                        self.discretisation.method
                    ),
                ));
            }
            let offs = v.wheel_offsets();
            // Wheels may start before x = 0 and end beyond L: off the structure they run on a
            // rigid track (docs/model.md §4).
            let (rear, front) = (offs[offs.len() - 1], offs[0] + travel);
            if !profile.values.is_empty()
                && (rear < profile.x0 - 1e-9 || front > profile.x_last() + 1e-9)
            {
                return Err(VtbError::config(
                    "irregularity",
                    format!("[{}, {}]", profile.x0, profile.x_last()),
                    format!(
                        "the profile must cover the wheel travel [{rear:.4}, {front:.4}] m of vehicle {i}"
                    ),
                ));
            }
            if self.solver.edge_ramp == 0.0 && !self.solver.edge_step {
                let (a, b) = self.extent(0);
                // The engine's rule (`Structure::edge_share`): a wheel is on the rail for a ≤ x ≤ b.
                // Where it ends may exceed an end by rounding (t_end = L/v reaches x = L in
                // n·Δt), which crosses nothing.
                let on = |x: f64| a <= x && x <= b;
                let crossing = offs.iter().find_map(|&w| {
                    let end = w + travel;
                    let end = if (end - b).abs() <= 1e-9 * b.abs().max(1.0) {
                        end.min(b)
                    } else {
                        end
                    };
                    if !on(w) && on(end) || w < a && end > b {
                        Some(("start", a))
                    } else if on(w) && !on(end) {
                        Some(("end", b))
                    } else {
                        None
                    }
                });
                if let Some((which, x)) = crossing {
                    let tail = if which == "end" && self.solver.tail.is_some() {
                        " (solver.tail runs the vehicles off it)"
                    } else {
                        ""
                    };
                    return Err(VtbError::config(
                        format!("{p}.x_front"),
                        v.x_front,
                        format!(
                            "a wheel of this vehicle crosses the rail's {which} at x = {x} m during the run{tail}, \
                             where it would meet the track's static deflection as a step (a spurious impact): model \
                             the track beyond with vtb.track_zones (embankments with a 10 m hand-over), or set \
                             solver.edge_ramp (m; on a bare structure the hand-over lies on the bridge), or \
                             solver.edge_step = true to keep the step (the FE–SEA hybrid's only choice), or keep \
                             the vehicles on the rail"
                        ),
                    ));
                }
            }
        }
        for (i, f) in self.forces.iter().enumerate() {
            let p = format!("forces[{i}]");
            f.validate(&p)?;
            if let Some(layer) = &f.layer {
                if self.layer_index(layer).is_none() {
                    return Err(VtbError::config(
                        format!("{p}.layer"),
                        format!("{layer:?}"),
                        "no layer of that name",
                    ));
                }
            }
        }
        if self.vehicles.is_empty() && self.forces.is_empty() {
            return Err(VtbError::config(
                "vehicles",
                "[]",
                "nothing loads the structure: give at least one vehicle or moving force",
            ));
        }
        Ok(())
    }

    /// Observation points on their layers, the metrics' window, bands and index names.
    fn validate_output(&self, dt: f64) -> Result<()> {
        for (i, &x) in self.output.points.iter().enumerate() {
            for li in self.index_layers() {
                self.on_layer(&format!("output.points[{i}]"), x, li)?;
            }
        }
        if let Some([t0, t1]) = self.output.window {
            non_negative("output.window[0]", t0)?;
            finite("output.window[1]", t1)?;
            let end = self.n_steps() as f64 * dt;
            if !(t1 > t0) || t0 >= end {
                return Err(VtbError::config(
                    "output.window",
                    format!("[{t0:?}, {t1:?}]"),
                    format!(
                        "must be an interval t0 < t1 that starts within the run [0, {end:?}] s"
                    ),
                ));
            }
        }
        if let Some(fc) = self.output.band_limit {
            crate::outputs::filter::check("output.band_limit", fc, dt)?;
        }
        crate::outputs::filter::check("output.deck_band", self.output.deck_band, dt)?;
        let steps = crate::outputs::window_steps(self.output.window, dt, self.n_steps());
        for (i, &f) in self.output.band_levels.iter().enumerate() {
            let n = steps.clone().count();
            crate::outputs::bands::check(&format!("output.band_levels[{i}]"), f, dt, n)?;
        }
        if let Some(names) = &self.output.indices {
            let known = crate::outputs::index_names(self);
            for (i, n) in names.iter().enumerate() {
                if !known.contains(n) {
                    return Err(VtbError::config(
                        format!("output.indices[{i}]"),
                        n,
                        format!(
                            "is not an index of this configuration; it has {}",
                            known.join(", ")
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The sampled rail profile.
    fn validate_profile(&self, profile: &Profile) -> Result<()> {
        if !profile.values.is_empty() {
            positive("irregularity.dx", profile.dx)?;
            finite("irregularity.x0", profile.x0)?;
            if profile.values.len() < 2 {
                return Err(VtbError::config(
                    "irregularity",
                    profile.values.len(),
                    "a sampled profile needs at least 2 samples",
                ));
            }
            if let Some((j, v)) = profile
                .values
                .iter()
                .enumerate()
                .find(|(_, v)| !v.is_finite())
            {
                return Err(VtbError::config(
                    format!("irregularity[{j}]"),
                    v,
                    "must be finite",
                ));
            }
        }
        Ok(())
    }

    /// A layer's start and end: within the structure, in order, finite elements only.
    fn validate_extent(&self, l: &LayerConfig, p: &str, length: f64) -> Result<()> {
        let start = within(
            &format!("{p}.start"),
            l.start.unwrap_or(0.0),
            0.0,
            length,
            "the structure",
        )?;
        let end = within(
            &format!("{p}.end"),
            l.end.unwrap_or(length),
            0.0,
            length,
            "the structure",
        )?;
        if end <= start {
            return Err(VtbError::config(
                format!("{p}.end"),
                end,
                format!("must be greater than the layer's start {start}"),
            ));
        }
        let mut last = start;
        for (j, &x) in l.joints.iter().enumerate() {
            let field = format!("{p}.joints[{j}]");
            within(&field, x, start, end, "the layer")?;
            if x <= last || x >= end {
                return Err(VtbError::config(
                    field,
                    x,
                    "joints must lie inside the layer, in increasing order",
                ));
            }
            last = x;
            if self.discretisation.method != Method::Fem {
                return Err(VtbError::config(
                    field,
                    x,
                    "a joint needs finite elements (discretisation.method = \"fem\")",
                ));
            }
        }
        if (start > 0.0 || end < length) && self.discretisation.method != Method::Fem {
            let field = if start > 0.0 { "start" } else { "end" };
            return Err(VtbError::config(
                format!("{p}.{field}"),
                if start > 0.0 { start } else { end },
                format!(
                    "a layer over part of the structure needs finite elements                      (discretisation.method = \"fem\", not {:?}): a modal basis spans the whole length",
                    self.discretisation.method
                ),
            ));
        }
        Ok(())
    }

    /// A continuous coupling's range: within the layers it joins, in order; finite elements
    /// for a range other than the default.
    fn validate_coupling_range(&self, c: &CouplingConfig, p: &str, upper: usize) -> Result<()> {
        let (a0, a1) = self.extent(upper);
        let (b0, b1) = self
            .layer_index(&c.lower)
            .map_or((a0, a1), |l| self.extent(l));
        let (lo, hi) = (a0.max(b0), a1.min(b1));
        if hi <= lo {
            return Err(VtbError::config(
                format!("{p}.lower"),
                format!("{:?}", c.lower),
                format!("layers {:?} and {:?} do not overlap", c.upper, c.lower),
            ));
        }
        let what = "the part of the structure both layers cover";
        let start = within(&format!("{p}.start"), c.start.unwrap_or(lo), lo, hi, what)?;
        let end = within(&format!("{p}.end"), c.end.unwrap_or(hi), lo, hi, what)?;
        if end <= start {
            return Err(VtbError::config(
                format!("{p}.end"),
                end,
                format!("must be greater than the coupling's start {start}"),
            ));
        }
        if (c.start.is_some() || c.end.is_some()) && self.discretisation.method != Method::Fem {
            return Err(VtbError::config(
                format!("{p}.{}", if c.start.is_some() { "start" } else { "end" }),
                c.start.or(c.end).expect("one is set"),
                "a continuous coupling over part of the structure needs finite elements \
                 (discretisation.method = \"fem\")",
            ));
        }
        Ok(())
    }

    /// Timoshenko properties (both or neither, finite elements only) and the element length.
    fn validate_layer_mesh(&self, l: &LayerConfig, p: &str, length: f64) -> Result<()> {
        let fem = self.discretisation.method == Method::Fem;
        match (l.shear_modulus, l.shear_coefficient) {
            (None, None) => {}
            (Some(g), Some(k)) => {
                positive(&format!("{p}.shear_modulus"), g)?;
                positive(&format!("{p}.shear_coefficient"), k)?;
                if !fem {
                    return Err(VtbError::config(
                        format!("{p}.shear_modulus"),
                        format!("{g:?}"),
                        "Timoshenko layers need discretisation.method = \"fem\" (the modal \
                         basis is Euler–Bernoulli)",
                    ));
                }
            }
            (g, _) => {
                let (field, other) = if g.is_none() {
                    ("shear_modulus", "shear_coefficient")
                } else {
                    ("shear_coefficient", "shear_modulus")
                };
                return Err(VtbError::config(
                    format!("{p}.{field}"),
                    "None",
                    format!(
                        "a Timoshenko layer needs both shear_modulus and shear_coefficient ({other} is set)"
                    ),
                ));
            }
        }
        if let Some(h) = l.element_length {
            let h = positive(&format!("{p}.element_length"), h)?;
            if length / h > MAX_ELEMENTS as f64 {
                return Err(VtbError::config(
                    format!("{p}.element_length"),
                    format!("{h:?}"),
                    format!("gives more than {MAX_ELEMENTS} elements"),
                ));
            }
        }
        Ok(())
    }

    /// Tread irregularities: none, or one row per wheel, each empty or on the rail's grid.
    fn validate_treads(&self, profile: &Profile) -> Result<()> {
        if profile.treads.is_empty() {
            return Ok(());
        }
        let wheels: usize = self.vehicles.iter().map(VehicleConfig::n_wheels).sum();
        if profile.treads.len() != wheels {
            return Err(VtbError::config(
                "irregularity.treads",
                format!("{} rows", profile.treads.len()),
                format!("needs one row per wheel of the run ({wheels})"),
            ));
        }
        for (k, row) in profile.treads.iter().enumerate() {
            if row.is_empty() {
                continue;
            }
            if row.len() != profile.values.len() {
                return Err(VtbError::config(
                    format!("irregularity.treads[{k}]"),
                    format!("{} samples", row.len()),
                    format!(
                        "must be sampled on the rail profile's grid ({} samples)",
                        profile.values.len()
                    ),
                ));
            }
            if let Some((j, v)) = row.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(VtbError::config(
                    format!("irregularity.treads[{k}][{j}]"),
                    v,
                    "must be finite",
                ));
            }
        }
        Ok(())
    }

    /// Every damper group (`damper_groups`), and their total count.
    fn validate_dampers(&self, length: f64) -> Result<()> {
        let mut total = 0;
        for (path, g) in self.damper_groups() {
            g.validate(&path, length)?;
            self.dampers_on_layers(&path, g)?;
            total += g.locations().len();
        }
        if total > MAX_TIDS {
            let (path, g) = self.damper_groups().pop().expect("dampers counted");
            return Err(VtbError::config(
                if g.positions.is_some() {
                    format!("{path}.positions")
                } else {
                    format!("{path}.count")
                },
                total,
                format!(
                    "all groups together hold {total} dampers, more than {MAX_TIDS}: their \
                     coupling is a dense matrix inverted once per run and applied every step"
                ),
            ));
        }
        Ok(())
    }

    /// The damper groups with their field paths: `tids` first, then `dampers[i]`.
    pub fn damper_groups(&self) -> Vec<(String, &DamperGroup)> {
        self.tids
            .iter()
            .map(|g| ("tids".to_string(), g))
            .chain(
                self.dampers
                    .iter()
                    .enumerate()
                    .map(|(i, g)| (format!("dampers[{i}]"), g)),
            )
            .collect()
    }

    /// Every damper of every group, in node order.
    pub fn damper_params(&self) -> Vec<DamperParams> {
        self.damper_groups()
            .into_iter()
            .flat_map(|(_, g)| vec![g.params(); g.locations().len()])
            .collect()
    }

    /// The layers `path.upper` and `path.lower` name (`None`: the ground), refused when one does
    /// not exist or both are the same (`same`: the reason given).
    fn layer_pair(
        &self,
        path: &str,
        upper: &str,
        lower: &str,
        same: &str,
    ) -> Result<(usize, Option<usize>)> {
        let u = self.layer_index(upper).ok_or_else(|| {
            VtbError::config(
                format!("{path}.upper"),
                format!("{upper:?}"),
                "no layer of that name",
            )
        })?;
        if lower == GROUND {
            return Ok((u, None));
        }
        let l = self.layer_index(lower).ok_or_else(|| {
            VtbError::config(
                format!("{path}.lower"),
                format!("{lower:?}"),
                "no layer of that name (or \"ground\")",
            )
        })?;
        if l == u {
            return Err(VtbError::config(
                format!("{path}.lower"),
                format!("{lower:?}"),
                same,
            ));
        }
        Ok((u, Some(l)))
    }

    /// A group's layers exist, differ, and hold every one of its dampers.
    fn dampers_on_layers(&self, path: &str, g: &DamperGroup) -> Result<()> {
        let same = format!("must differ from {path}.upper");
        let (upper, lower) = self.layer_pair(path, &g.upper, &g.lower, &same)?;
        let field = match g.positions {
            Some(_) => format!("{path}.positions"),
            None => format!("{path}.x0"),
        };
        for i in std::iter::once(upper).chain(lower) {
            for x in g.locations() {
                self.on_layer(&field, x, i)?;
            }
        }
        Ok(())
    }
}

impl DamperGroup {
    /// Parameters, kind and positions (on [0, length]; layers are checked by the config).
    pub fn validate(&self, path: &str, length: f64) -> Result<()> {
        let at = |f: &str| format!("{path}.{f}");
        positive(&at("inertance"), self.inertance)?;
        // Without a spring the internal node has no static position (the inerter carries no
        // static force): k → 0 is a limit, not a value.
        positive(&at("stiffness"), self.stiffness)?;
        non_negative(&at("damping"), self.damping)?;
        if self.kind.grounded() && self.lower != GROUND {
            return Err(VtbError::config(
                at("lower"),
                format!("{:?}", self.lower),
                format!(
                    "a {} hangs from one layer: lower must be \"ground\"",
                    self.kind.name()
                ),
            ));
        }
        match (&self.positions, self.count, self.x0, self.spacing) {
            (Some(p), None, None, None) => {
                if p.is_empty() {
                    return Err(VtbError::config(
                        at("positions"),
                        "[]",
                        "must hold at least one position (omit the group for no dampers)",
                    ));
                }
                if p.len() > MAX_TIDS {
                    return Err(VtbError::config(
                        at("positions"),
                        p.len(),
                        format!("must hold at most {MAX_TIDS} positions"),
                    ));
                }
                for (i, &x) in p.iter().enumerate() {
                    within(
                        &format!("{path}.positions[{i}]"),
                        x,
                        0.0,
                        length,
                        "the structure",
                    )?;
                }
                Ok(())
            }
            (None, Some(count), Some(x0), spacing) => {
                if count == 0 {
                    return Err(VtbError::config(
                        at("count"),
                        0,
                        "must be >= 1 (omit the group for no dampers)",
                    ));
                }
                if count > MAX_TIDS {
                    return Err(VtbError::config(
                        at("count"),
                        count,
                        format!(
                            "must be <= {MAX_TIDS}: the dampers' coupling is a dense count × count \
                             matrix inverted once per run and applied every step"
                        ),
                    ));
                }
                within(&at("x0"), x0, 0.0, length, "the structure")?;
                if count > 1 {
                    let h = spacing.ok_or_else(|| {
                        VtbError::config(at("spacing"), "None", "is needed when count > 1")
                    })?;
                    positive(&at("spacing"), h)?;
                    let last = x0 + h * (count - 1) as f64;
                    if last > length + 1e-9 {
                        return Err(VtbError::config(
                            at("count"),
                            count,
                            format!(
                                "the last damper would sit at x = {last:.4} m, beyond the structure length {length}"
                            ),
                        ));
                    }
                } else if let Some(h) = spacing {
                    finite(&at("spacing"), h)?;
                }
                Ok(())
            }
            (Some(_), ..) => Err(VtbError::config(
                at("positions"),
                "given",
                "give either positions or the pattern count, x0, spacing, not both",
            )),
            (None, None, ..) => Err(VtbError::config(
                at("count"),
                "None",
                "give the pattern count, x0 (and spacing), or positions",
            )),
            (None, Some(_), None, _) => {
                Err(VtbError::config(at("x0"), "None", "is needed with count"))
            }
        }
    }
}

// Each sub-configuration checks its own fields under its path; `Config::validate` adds the
// checks that relate one part to another (names, positions on layers, the method, the run).

impl RayleighConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        match *self {
            RayleighConfig::Ratio { ratio, f1, f2 } => {
                let r = non_negative(&format!("{p}.ratio"), ratio)?;
                if r >= 1.0 {
                    return Err(VtbError::config(format!("{p}.ratio"), r, "must be < 1"));
                }
                positive(&format!("{p}.f1"), f1)?;
                positive(&format!("{p}.f2"), f2)?;
                if f2 <= f1 {
                    return Err(VtbError::config(
                        format!("{p}.f2"),
                        f2,
                        format!("must be > f1 = {f1}"),
                    ));
                }
            }
            RayleighConfig::Coefficients { alpha, beta } => {
                non_negative(&format!("{p}.alpha"), alpha)?;
                non_negative(&format!("{p}.beta"), beta)?;
            }
        }
        Ok(())
    }
}

impl LayerConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        if self.name.is_empty() || self.name == GROUND {
            return Err(VtbError::config(
                format!("{p}.name"),
                format!("{:?}", self.name),
                "must be a non-empty name other than \"ground\"",
            ));
        }
        positive(&format!("{p}.density"), self.density)?;
        positive(&format!("{p}.area"), self.area)?;
        positive(&format!("{p}.youngs_modulus"), self.youngs_modulus)?;
        positive(&format!("{p}.inertia"), self.inertia)?;
        self.damping.validate(&format!("{p}.damping"))
    }
}

impl CouplingConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        non_negative(&format!("{p}.stiffness"), self.stiffness)?;
        non_negative(&format!("{p}.damping"), self.damping)?;
        match self.kind {
            CouplingKind::Discrete => {
                if self.positions.is_empty() {
                    return Err(VtbError::config(
                        format!("{p}.positions"),
                        "[]",
                        "a discrete coupling needs at least one position",
                    ));
                }
                for (name, v) in [("start", self.start), ("end", self.end)] {
                    if let Some(v) = v {
                        return Err(VtbError::config(
                            format!("{p}.{name}"),
                            v,
                            "a discrete coupling acts at its positions; start and end are for continuous ones",
                        ));
                    }
                }
            }
            CouplingKind::Continuous => {
                if !self.positions.is_empty() {
                    return Err(VtbError::config(
                        format!("{p}.positions"),
                        format!("{:?}", self.positions),
                        "a continuous coupling takes no positions",
                    ));
                }
            }
        }
        Ok(())
    }
}

impl VehicleConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        let v = self;
        self.model.model(v).validate(p)?;
        positive(&format!("{p}.wheel_radius"), v.wheel_radius)?;
        if v.rails == 0 {
            return Err(VtbError::config(format!("{p}.rails"), 0, "must be >= 1"));
        }
        if let Some(g) = v.contact_constant {
            positive(&format!("{p}.contact_constant"), g)?;
        }
        positive(&format!("{p}.rail_crown_radius"), v.rail_crown_radius)?;
        // Wheels may start before x = 0 and end beyond L: off the structure they run on a
        // rigid track (docs/zones.md).
        finite(&format!("{p}.x_front"), v.x_front)?;
        Ok(())
    }
}

impl MovingForceConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        finite(&format!("{p}.magnitude"), self.magnitude)?;
        // Off its layer a force loads nothing.
        finite(&format!("{p}.x0"), self.x0)?;
        Ok(())
    }
}

impl SolverConfig {
    pub fn validate(&self) -> Result<()> {
        let dt = positive("solver.dt", self.dt)?;
        non_negative("solver.end_margin", self.end_margin)?;
        non_negative("solver.edge_ramp", self.edge_ramp)?;
        if self.edge_step && self.edge_ramp > 0.0 {
            return Err(VtbError::config(
                "solver.edge_step",
                true,
                format!(
                    "asks for the step of a rail end without a hand-over, but edge_ramp = {} m hands the force over",
                    self.edge_ramp
                ),
            ));
        }
        non_negative("solver.gravity", self.gravity)?;
        positive("solver.contact_tol", self.contact_tol)?;
        if self.contact_max_iter == 0 {
            return Err(VtbError::config(
                "solver.contact_max_iter",
                0,
                "must be >= 1",
            ));
        }
        positive("solver.memory_budget", self.memory_budget)?;
        non_negative("solver.fade_in", self.fade_in)?;
        if let Some(t) = self.t_end {
            positive("solver.t_end", t)?;
            let steps = t / dt;
            if (steps - steps.round()).abs() > STEP_TOL && steps < MAX_STEPS as f64 {
                let (lo, hi) = (steps.floor().max(1.0) * dt, steps.ceil() * dt);
                return Err(VtbError::config(
                    "solver.t_end",
                    format!("{t:?}"),
                    format!(
                        "is not a whole number of time steps dt = {dt:?} (t_end/dt = {steps:.6}): \
                         the nearest valid end times are {lo:?} and {hi:?} s"
                    ),
                ));
            }
        }
        if let Some(tail) = self.tail {
            non_negative("solver.tail", tail)?;
            if self.t_end.is_some() {
                return Err(VtbError::config(
                    "solver.tail",
                    tail,
                    "give either solver.t_end or solver.tail, not both",
                ));
            }
        }
        Ok(())
    }
}

/// The value at a dotted path (`a.b[2].c`) of a JSON tree.
fn value_at<'v>(tree: &'v serde_json::Value, path: &str) -> Option<&'v serde_json::Value> {
    let mut v = tree;
    for part in path.split('.').filter(|p| !p.is_empty()) {
        let (name, indices) = part.split_once('[').map_or((part, ""), |(n, r)| (n, r));
        if !name.is_empty() {
            v = v.get(name)?;
        }
        for idx in indices.split('[').filter(|s| !s.is_empty()) {
            v = v.get(idx.trim_end_matches(']').parse::<usize>().ok()?)?;
        }
    }
    Some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused_field(cfg: &Config) -> Option<String> {
        match cfg.validate(&Profile::flat()) {
            Ok(()) => None,
            Err(VtbError::Config { field, .. }) => Some(field),
            Err(e) => panic!("not a ConfigError: {e}"),
        }
    }

    #[test]
    fn a_wheel_crossing_a_rail_end_needs_the_hand_over_set() {
        // The article car started 5 m before the rail: its wheels cross x = 0 at 80 m/s.
        let mut cfg = crate::library::presets::paper();
        cfg.vehicles[0].x_front = -5.0;
        assert_eq!(refused_field(&cfg).as_deref(), Some("vehicles[0].x_front"));
        cfg.solver.edge_step = true; // the step, on request (the hybrid takes no ramp)
        assert_eq!(refused_field(&cfg), None);
        cfg.solver.edge_ramp = 5.0; // a step and a hand-over at once: refused
        assert_eq!(refused_field(&cfg).as_deref(), Some("solver.edge_step"));
        // Wheels that stay off the rail for the whole run need nothing.
        cfg.solver.edge_step = false;
        cfg.solver.edge_ramp = 0.0;
        cfg.vehicles[0].x_front = -500.0;
        cfg.solver.t_end = Some(0.1);
        assert_eq!(refused_field(&cfg), None);
    }

    #[test]
    fn a_band_limit_must_lie_below_the_nyquist_frequency() {
        // Δt = 5e-5 s: Nyquist 10 kHz.
        let mut cfg = crate::library::presets::paper();
        for (fc, ok) in [
            (2000.0, true),
            (9999.0, true),
            (10000.0, false),
            (0.0, false),
            (-1.0, false),
            (f64::NAN, false),
        ] {
            cfg.output.band_limit = Some(fc);
            let got = refused_field(&cfg);
            assert_eq!(got.is_none(), ok, "{fc}: {got:?}");
            if let Some(f) = got {
                assert_eq!(f, "output.band_limit");
            }
        }
    }

    #[test]
    fn a_contact_patch_needs_a_finite_element_rail() {
        let mut cfg = crate::library::presets::paper();
        cfg.vehicles[0].contact_patch = true;
        assert_eq!(
            refused_field(&cfg).as_deref(),
            Some("vehicles[0].contact_patch")
        );
        assert_eq!(
            refused_field(&crate::library::presets::paper_converged()),
            None
        );
        cfg.discretisation.method = Method::Fem;
        cfg.vehicles[0].rail_crown_radius = 0.0;
        assert_eq!(
            refused_field(&cfg).as_deref(),
            Some("vehicles[0].rail_crown_radius")
        );
    }

    #[test]
    fn irregularity_share_is_a_smooth_ramp_over_the_fade_distance() {
        let mut cfg = crate::library::presets::paper();
        cfg.speed = 80.0;
        cfg.solver.fade_in = 2.0;
        let t_full = 2.0 / 80.0;
        assert_eq!(cfg.irregularity_share(0.0), 0.0);
        assert!((cfg.irregularity_share(t_full / 2.0) - 0.5).abs() < 1e-15);
        assert_eq!(cfg.irregularity_share(t_full), 1.0);
        assert_eq!(cfg.irregularity_share(1.0), 1.0);
        // C¹: the slope vanishes at both ends of the ramp
        let h = 1e-7 * t_full;
        assert!(cfg.irregularity_share(h) < 1e-12);
        assert!(1.0 - cfg.irregularity_share(t_full - h) < 1e-12);
        cfg.solver.fade_in = 0.0;
        assert_eq!(cfg.irregularity_share(0.0), 1.0);
        cfg.solver.fade_in = 2.0;
        cfg.speed = 0.0;
        assert_eq!(cfg.irregularity_share(0.0), 1.0);
    }
}
