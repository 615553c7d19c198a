//! Published parameter sets. The Python layer takes its presets from here, so each number
//! lives in one place.

use crate::config::*;

/// CRH3 car, parameter set A (Zeng et al., Shock Vib. 2014, Table 1):
/// `motor = false` for the trailer, `true` for the motor car. Wheel radius 0.46 m.
pub fn crh3(motor: bool, x_front: f64) -> VehicleConfig {
    let (m_c, m_t, j_t, k_s, c_s, k_p, c_p) = if motor {
        (4.8e4, 3.2e3, 7.2e3, 8.0e5, 9.0e4, 2.08e6, 6.0e4)
    } else {
        (4.4e4, 2.4e3, 2.2e3, 6.0e5, 8.0e4, 1.4e6, 8.0e4)
    };
    VehicleConfig {
        model: VehicleModel::Car(CarConfig {
            m_c,
            j_c: 2.7e6,
            m_t,
            j_t,
            m_w: 2.4e3,
            k_s,
            c_s,
            k_p,
            c_p,
            l_c: 8.6875,
            l_t: 1.25,
        }),
        wheels: Wheels {
            wheel_radius: 0.46,
            contact_constant: None,
            x_front,
            rails: 2,
            contact_patch: false,
            rail_crown_radius: crate::config::default_rail_crown_radius(),
        },
    }
}

/// Default Rayleigh damping of each layer of the article's structure (the article gives no
/// α, β). Ratios: steel rail 1 %, concrete slab and base 5 %, prestressed box girder 2 %,
/// each fitted at two frequencies bracketing the band the layer responds in: rail 100–1000 Hz
/// (rail on fasteners ≈ 200 Hz up to the highest local mode ≈ 1 kHz), slab and base 20–1000 Hz
/// (slab and base on the support layer ≈ 27 Hz, slab on the CA mortar ≈ 134 Hz), girder
/// 5–50 Hz (first bending ≈ 6 Hz).
pub fn table1_damping() -> [RayleighConfig; 4] {
    [
        RayleighConfig::Ratio {
            ratio: 0.01,
            f1: 100.0,
            f2: 1000.0,
        },
        RayleighConfig::Ratio {
            ratio: 0.05,
            f1: 20.0,
            f2: 1000.0,
        },
        RayleighConfig::Ratio {
            ratio: 0.05,
            f1: 20.0,
            f2: 1000.0,
        },
        RayleighConfig::Ratio {
            ratio: 0.02,
            f1: 5.0,
            f2: 50.0,
        },
    ]
}

/// The article's track–bridge (Table 1): CRTS II slab track on five 32 m spans, one rail
/// (with its own fasteners) on the full-width slab, base and girder; rail 120 (+100 local),
/// slab 120, base 120, girder 50 sine modes.
pub fn table1_structure() -> StructureConfig {
    let length = 160.0;
    let damping = table1_damping();
    let layer = |name: &str, density, area, e, i, modes, local_modes, damping| LayerConfig {
        name: name.into(),
        density,
        area,
        youngs_modulus: e,
        inertia: i,
        modes,
        local_modes,
        shear_modulus: None,
        shear_coefficient: None,
        element_length: None,
        joints: Vec::new(),
        damping,
        start: None,
        end: None,
    };
    let fasteners: Vec<f64> = (0..=250).map(|i| 0.64 * i as f64).collect();
    let piers: Vec<f64> = (0..=5).map(|i| 32.0 * i as f64).collect();
    StructureConfig {
        length,
        layers: vec![
            layer(
                "rail", 7800.0, 7.745e-3, 2.1e11, 3.217e-5, 120, 100, damping[0],
            ),
            layer("slab", 2500.0, 0.51, 3.9e10, 1.7e-3, 120, 0, damping[1]),
            layer(
                "base", 2500.0, 0.885, 3.62e10, 6.6375e-3, 120, 0, damping[2],
            ),
            layer("bridge", 2500.0, 8.75, 3.945e10, 9.25, 50, 0, damping[3]),
        ],
        couplings: vec![
            CouplingConfig {
                upper: "rail".into(),
                lower: "slab".into(),
                kind: CouplingKind::Discrete,
                stiffness: 6e7,
                damping: 4.77e4,
                positions: fasteners,
                start: None,
                end: None,
            },
            CouplingConfig {
                upper: "slab".into(),
                lower: "base".into(),
                kind: CouplingKind::Continuous,
                stiffness: 9e8,
                damping: 8.3e4,
                positions: vec![],
                start: None,
                end: None,
            },
            CouplingConfig {
                upper: "base".into(),
                lower: "bridge".into(),
                kind: CouplingKind::Continuous,
                stiffness: 1e8,
                damping: 2.48e5,
                positions: vec![],
                start: None,
                end: None,
            },
            CouplingConfig {
                upper: "bridge".into(),
                lower: GROUND.into(),
                kind: CouplingKind::Discrete,
                stiffness: 1e15,
                damping: 0.0,
                positions: piers,
                start: None,
                end: None,
            },
        ],
    }
}

/// The article's §3.3 validation case: Table 1 structure in the article's hybrid (FE–SEA)
/// discretisation, one CRH3 trailer (set A) whose rear wheelset starts 1 m onto the bridge,
/// 80 m/s, Δt = 5e−5 s, run until the leading wheelset is 1 m from the end (≈ 34 500 steps),
/// observation at mid-length. The irregularity is supplied separately; ω_r is the centre of
/// its 0.01–1 m band at 80 m/s, 2π·80/sqrt(0.01·1) rad/s (800 Hz).
pub fn paper() -> Config {
    let car = crh3(false, 0.0);
    // The rear wheelset 1 m onto the bridge: the front one the car's length further on.
    let x_front = 1.0 + (car.wheel_offsets()[0] - car.wheel_offsets()[3]);
    Config {
        structure: table1_structure(),
        discretisation: DiscretisationConfig {
            method: Method::Hybrid,
            omega_r: Some(2.0 * std::f64::consts::PI * 800.0),
            ..DiscretisationConfig::default()
        },
        vehicles: vec![crh3(false, x_front)],
        forces: vec![],
        speed: 80.0,
        solver: SolverConfig::default(),
        output: OutputConfig {
            points: vec![80.0],
            ..OutputConfig::default()
        },
        dampers: Vec::new(),
        accept_implausible: Vec::new(),
    }
}

/// Shear modulus of rail steel (Pa): G = E/2(1 + ν) with E = 2.1e11 Pa, ν = 0.3.
pub const RAIL_SHEAR_MODULUS: f64 = 8.1e10;
/// Shear coefficient of a 60 kg rail in vertical bending, the value usual in rail dynamics
/// (Grassie et al. 1982; Thompson, *Railway Noise and Vibration*, 2009). With it the
/// pinned–pinned frequency of the article's rail on 0.64 m bays is ≈ 1.0 kHz, as measured on
/// tracks of this bay length, instead of Euler–Bernoulli's 1.28 kHz.
pub const RAIL_SHEAR_COEFFICIENT: f64 = 0.4;
/// Rail elements per fastener bay of the converged preset (docs/validation.md: the cheapest
/// mesh within the error bounds against the refined reference).
pub const CONVERGED_RAIL_ELEMENTS_PER_BAY: usize = 20;
/// Time step (s) of the converged preset: halving it moves the rail's band levels up to
/// 2 kHz by under 1 % (at 5e−5 s, Newmark's period elongation shifts the pinned–pinned
/// resonance by 0.8 % and its band levels by ≈ 2–3 %).
pub const CONVERGED_TIME_STEP: f64 = 2.5e-5;
/// Element length (m) of the slab, base and girder in the converged preset.
pub const CONVERGED_LOWER_ELEMENT_LENGTH: f64 = 0.32;
/// Band limit (Hz) of the converged preset's acceleration indices (docs/contact-patch.md): the
/// band its rail is verified in against the refined reference and resolves (the time step's
/// 1 % limit is 2.23 kHz); the rail peak low-passed there moves by under 0.5 % from 20 to 80
/// elements per bay and under Δt halved, point contact or patch, where the raw peak does not
/// converge under a point contact.
pub const CONVERGED_BAND_LIMIT: f64 = 2000.0;

/// The article's case on a converged discretisation: the same structure, vehicle,
/// excitation and run, with a Timoshenko rail (`RAIL_SHEAR_MODULUS`,
/// `RAIL_SHEAR_COEFFICIENT`) in finite elements, the rail meshed at
/// `CONVERGED_RAIL_ELEMENTS_PER_BAY` elements per fastener bay and the lower layers at
/// `CONVERGED_LOWER_ELEMENT_LENGTH`, nodes on every fastener and pier, Δt =
/// `CONVERGED_TIME_STEP`; the wheels on their Hertz contact patches and the acceleration
/// indices band-limited at `CONVERGED_BAND_LIMIT`.
pub fn paper_converged() -> Config {
    let mut cfg = paper();
    for v in cfg.vehicles.iter_mut() {
        v.wheels.contact_patch = true;
    }
    cfg.output.band_limit = Some(CONVERGED_BAND_LIMIT);
    cfg.discretisation.method = Method::Fem;
    cfg.discretisation.omega_r = None;
    cfg.solver.dt = CONVERGED_TIME_STEP;
    let layers = &mut cfg.structure.layers;
    let rail = &mut layers[0];
    rail.shear_modulus = Some(RAIL_SHEAR_MODULUS);
    rail.shear_coefficient = Some(RAIL_SHEAR_COEFFICIENT);
    rail.local_modes = 0;
    rail.element_length = Some(0.64 / CONVERGED_RAIL_ELEMENTS_PER_BAY as f64);
    for l in layers[1..].iter_mut() {
        l.element_length = Some(CONVERGED_LOWER_ELEMENT_LENGTH);
    }
    cfg
}

/// Cut-off (Hz) of the fast preset's complex-modal synthesis: its modes reach twice the band
/// limit (docs/synthesis.md, cut-off study).
pub const FAST_CUTOFF: f64 = 4000.0;
/// Time step (s) of the fast preset: the exact modal step has no period error, and the
/// equalised piecewise-linear force is 1 % off at 3.1 kHz (`resolution`); measured, every
/// index is within 0.5 % of Δt = 1e-5 s (docs/synthesis.md, time-step study).
pub const FAST_TIME_STEP: f64 = 5e-5;

/// The converged preset run by complex-modal synthesis (docs/synthesis.md): the same finite
/// elements reduced to their complex modes below `FAST_CUTOFF` plus the rail's static
/// residual, stepped exactly at `FAST_TIME_STEP`.
pub fn paper_fast() -> Config {
    let mut cfg = paper_converged();
    cfg.discretisation.synthesis_cutoff = Some(FAST_CUTOFF);
    cfg.solver.dt = FAST_TIME_STEP;
    cfg
}

/// Cut-off (Hz) of the deck grade's substructures: they resolve half of it, the rail on its
/// pads included, whose resonance the contact force's extremes need. Against the time-converged
/// finite elements (5 and 10 spans, one car and four) the contact minima are within 0.9 % at
/// 1 200 Hz, but up to 6 % off at 800 Hz and 9.7 % at 600 Hz, where the deck and the ride are
/// already within 0.3 % (docs/substructures.md).
pub const DECK_CUTOFF: f64 = 1200.0;
/// Time step (s) of the deck grade: what its kept modes need for the contact force's extremes
/// (at 2e-4 s they move by 1.2–3.6 %, at 1e-4 s by 0.2 %); 67 steps a period at its 150 Hz
/// index band.
pub const DECK_TIME_STEP: f64 = 1e-4;
/// The deck grade's acceleration indices are band-limited here (Hz): deck and ride.
pub const DECK_BAND_LIMIT: f64 = 150.0;

/// The deck grade: the converged preset's structure and car stepped on the substructured
/// engine, each substructure's fixed-interface modes below `DECK_CUTOFF`, at `DECK_TIME_STEP`,
/// its indices band-limited at `DECK_BAND_LIMIT`: the deck, ride comfort and the contact force
/// of long viaducts and long trains, not the rail's vibration (the rail grade, `paper_fast`).
pub fn paper_deck() -> Config {
    let mut cfg = paper_converged();
    cfg.discretisation.substructure_cutoff = Some(DECK_CUTOFF);
    cfg.solver.dt = DECK_TIME_STEP;
    cfg.output.band_limit = Some(DECK_BAND_LIMIT);
    cfg
}

/// Preset names known to `by_name`.
pub const PRESETS: [&str; 4] = ["paper", "paper_converged", "paper_fast", "paper_deck"];

/// A preset by name, as JSON (for the Python layer).
pub fn by_name(name: &str) -> Option<Config> {
    match name {
        "paper" => Some(paper()),
        "paper_converged" => Some(paper_converged()),
        "paper_fast" => Some(paper_fast()),
        "paper_deck" => Some(paper_deck()),
        _ => None,
    }
}
