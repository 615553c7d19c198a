//! How the layers are discretised: modal, hybrid FE–SEA or finite elements, and the
//! complex-modal synthesis of a finite-element structure.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

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
    /// The shortest and longest wavelength (m) the irregularity excites, [λ_min, λ_max] (a
    /// spectrum's band; a corrugation's or a dip's one wavelength twice), from which the
    /// default ω_r follows; the Python layer fills it from `Config.irregularity`.
    #[serde(default)]
    pub excitation_wavelengths: Option<[f64; 2]>,
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
    /// Cut-off (Hz) of the substructured coordinates of a finite-element structure: `None`
    /// steps the finite elements; f_c cuts the structure at its joints and every 32 m, keeps
    /// each substructure's fixed-interface modes below f_c and the DOFs on the cuts, and steps
    /// that banded system by Newmark (docs/substructures.md). Needs `method = "fem"` and the
    /// structure's substructures (`vtb.run.substructures.reduction`).
    #[serde(default)]
    pub substructure_cutoff: Option<f64>,
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
            excitation_wavelengths: None,
            fesea_coupling: FeSeaCoupling::Full,
            local_deflection: true,
            element_flexibility: true,
            synthesis_cutoff: None,
            substructure_cutoff: None,
        }
    }
}
