//! Plausible ranges of the physical fields (docs/limits.md): a value outside its range is
//! almost always a unit mistake (a speed in km/h, a stiffness in kN/m, a modulus in GPa), so
//! it is refused with the likely mistake named, unless the configuration lists the field in
//! `accept_implausible`. The table is the one definition; Python reads it
//! (`vtb.plausible_ranges()`).

use crate::config::{Config, CouplingKind};
use crate::error::{Result, VtbError};

/// One field's plausible range, in SI units.
pub struct Range {
    /// The field's path, `[*]` standing for every index of a list.
    pub field: &'static str,
    pub min: f64,
    pub max: f64,
    pub unit: &'static str,
    /// What the range covers.
    pub covers: &'static str,
    get: fn(&Config) -> Vec<f64>,
}

fn layers(c: &Config, f: fn(&crate::config::LayerConfig) -> f64) -> Vec<f64> {
    c.structure.layers.iter().map(f).collect()
}

fn layers_ratio(c: &Config) -> Vec<f64> {
    // Every layer keeps its index in the path: coefficients (α, β) give NaN, which is skipped.
    c.structure
        .layers
        .iter()
        .map(|l| match l.damping {
            crate::config::RayleighConfig::Ratio { ratio, .. } => ratio,
            crate::config::RayleighConfig::Coefficients { .. } => f64::NAN,
        })
        .collect()
}

fn couplings(
    c: &Config,
    kind: CouplingKind,
    f: fn(&crate::config::CouplingConfig) -> f64,
) -> Vec<f64> {
    // Every coupling keeps its index in the path: others give NaN, which is skipped.
    c.structure
        .couplings
        .iter()
        .map(|cp| if cp.kind == kind { f(cp) } else { f64::NAN })
        .collect()
}

/// Every vehicle's model field `name` (NaN, skipped, where its model has no such field).
fn vehicles(c: &Config, name: &str) -> Vec<f64> {
    c.vehicles
        .iter()
        .map(|v| v.model.field(name).unwrap_or(f64::NAN))
        .collect()
}

fn dampers(c: &Config, f: fn(&crate::config::DamperGroup) -> f64) -> Vec<f64> {
    c.dampers.iter().map(f).collect()
}

/// The table (SI units).
pub const RANGES: &[Range] = &[
    Range {
        field: "speed",
        min: 0.0,
        max: 150.0,
        unit: "m/s",
        covers: "railway vehicles up to 540 km/h",
        get: |c| vec![c.speed],
    },
    Range {
        field: "structure.length",
        min: 1.0,
        max: 1e5,
        unit: "m",
        covers: "a span to a long viaduct",
        get: |c| vec![c.structure.length],
    },
    Range {
        field: "structure.layers[*].density",
        min: 500.0,
        max: 2e4,
        unit: "kg/m³",
        covers: "timber to steel and ballast-laden sections",
        get: |c| layers(c, |l| l.density),
    },
    Range {
        field: "structure.layers[*].youngs_modulus",
        min: 1e8,
        max: 1e12,
        unit: "Pa",
        covers: "asphalt and mortar to steel",
        get: |c| layers(c, |l| l.youngs_modulus),
    },
    Range {
        field: "structure.layers[*].area",
        min: 1e-4,
        max: 100.0,
        unit: "m²",
        covers: "a rail section to a box girder",
        get: |c| layers(c, |l| l.area),
    },
    Range {
        field: "structure.layers[*].inertia",
        min: 1e-7,
        max: 1e3,
        unit: "m⁴",
        covers: "a rail to a long-span girder",
        get: |c| layers(c, |l| l.inertia),
    },
    Range {
        field: "structure.couplings[*].stiffness (discrete)",
        min: 1e6,
        max: 1e16,
        unit: "N/m",
        covers: "soft rail pads (≈ 1e7) to rigid supports",
        get: |c| couplings(c, CouplingKind::Discrete, |cp| cp.stiffness),
    },
    Range {
        field: "structure.couplings[*].stiffness (continuous)",
        min: 1e5,
        max: 1e13,
        unit: "N/m²",
        covers: "soft subgrade to concrete bearing",
        get: |c| couplings(c, CouplingKind::Continuous, |cp| cp.stiffness),
    },
    Range {
        field: "structure.couplings[*].damping (discrete)",
        min: 10.0,
        max: 1e7,
        unit: "N·s/m",
        covers: "rail pads and bearings",
        get: |c| couplings(c, CouplingKind::Discrete, |cp| cp.damping),
    },
    Range {
        field: "structure.couplings[*].damping (continuous)",
        min: 10.0,
        max: 1e8,
        unit: "N·s/m²",
        covers: "mortar, subgrade and bearing layers",
        get: |c| couplings(c, CouplingKind::Continuous, |cp| cp.damping),
    },
    Range {
        field: "structure.layers[*].damping.ratio",
        min: 1e-4,
        max: 0.5,
        unit: "–",
        covers: "structural damping ratios",
        get: |c| layers_ratio(c),
    },
    Range {
        field: "vehicles[*].m_c",
        min: 1e3,
        max: 2e5,
        unit: "kg",
        covers: "a light car body to a loaded freight wagon",
        get: |c| vehicles(c, "m_c"),
    },
    Range {
        field: "vehicles[*].j_c",
        min: 1e4,
        max: 1e8,
        unit: "kg·m²",
        covers: "car-body pitch inertia",
        get: |c| vehicles(c, "j_c"),
    },
    Range {
        field: "vehicles[*].m_t",
        min: 200.0,
        max: 2e4,
        unit: "kg",
        covers: "bogie frames",
        get: |c| vehicles(c, "m_t"),
    },
    Range {
        field: "vehicles[*].m_w",
        min: 100.0,
        max: 1e4,
        unit: "kg",
        covers: "wheelsets",
        get: |c| vehicles(c, "m_w"),
    },
    Range {
        field: "vehicles[*].k_s",
        min: 1e4,
        max: 1e8,
        unit: "N/m",
        covers: "secondary suspensions",
        get: |c| vehicles(c, "k_s"),
    },
    Range {
        field: "vehicles[*].k_p",
        min: 1e5,
        max: 1e9,
        unit: "N/m",
        covers: "primary suspensions",
        get: |c| vehicles(c, "k_p"),
    },
    Range {
        field: "vehicles[*].j_t",
        min: 100.0,
        max: 5e4,
        unit: "kg·m²",
        covers: "bogie pitch inertia",
        get: |c| vehicles(c, "j_t"),
    },
    Range {
        field: "vehicles[*].c_s",
        min: 1e3,
        max: 1e6,
        unit: "N·s/m",
        covers: "secondary dampers",
        get: |c| vehicles(c, "c_s"),
    },
    Range {
        field: "vehicles[*].c_p",
        min: 1e3,
        max: 1e6,
        unit: "N·s/m",
        covers: "primary dampers",
        get: |c| vehicles(c, "c_p"),
    },
    Range {
        field: "vehicles[*].l_c",
        min: 1.0,
        max: 15.0,
        unit: "m",
        covers: "half the distance between bogie centres",
        get: |c| vehicles(c, "l_c"),
    },
    Range {
        field: "vehicles[*].l_t",
        min: 0.5,
        max: 2.5,
        unit: "m",
        covers: "half bogie wheelbases",
        get: |c| vehicles(c, "l_t"),
    },
    Range {
        field: "vehicles[*].wheel_radius",
        min: 0.15,
        max: 0.8,
        unit: "m",
        covers: "wheels",
        get: |c| c.vehicles.iter().map(|v| v.wheels.wheel_radius).collect(),
    },
    Range {
        field: "dampers[*].inertance",
        min: 1e-3,
        max: 1e5,
        unit: "kg",
        covers: "inerters and tuned masses",
        get: |c| dampers(c, |t| t.inertance),
    },
    Range {
        field: "dampers[*].stiffness",
        min: 1e3,
        max: 1e11,
        unit: "N/m",
        covers: "damper springs",
        get: |c| dampers(c, |t| t.stiffness),
    },
    Range {
        field: "dampers[*].damping",
        min: 1e-2,
        max: 1e7,
        unit: "N·s/m",
        covers: "damper dashpots",
        get: |c| dampers(c, |t| t.damping),
    },
    Range {
        field: "forces[*].magnitude",
        min: 1e3,
        max: 5e6,
        unit: "N",
        covers: "a wheel load to a heavy axle group",
        get: |c| c.forces.iter().map(|f| f.magnitude).collect(),
    },
    Range {
        field: "solver.dt",
        min: 1e-7,
        max: 1e-2,
        unit: "s",
        covers: "time steps of vertical dynamics",
        get: |c| vec![c.solver.dt],
    },
];

/// The field's path for index i (`[*]` → `[i]`, a qualifier in parentheses dropped).
fn path(cfg: &Config, field: &str, i: usize) -> String {
    let base = field.split(" (").next().unwrap_or(field);
    match base.strip_prefix("dampers[*]") {
        // a named group is addressed by its name
        Some(rest) => format!("{}{rest}", cfg.dampers[i].path(i)),
        None => base.replace("[*]", &format!("[{i}]")),
    }
}

/// The likely unit mistake for a value outside its range.
fn hint(r: &Range, v: f64) -> String {
    let tries: &[(f64, &str)] = match r.unit {
        "m/s" => &[(1.0 / 3.6, "km/h")],
        "N/m" | "N/m²" => &[(1e3, "kN/m"), (1e6, "MN/m")],
        "Pa" => &[(1e6, "MPa"), (1e9, "GPa")],
        "kg" => &[(1e3, "t")],
        "m" => &[(1e-3, "mm")],
        "m²" => &[(1e-4, "cm²"), (1e-6, "mm²")],
        "m⁴" => &[(1e-8, "cm⁴")],
        "–" => &[(1e-2, "%")],
        "N" => &[(1e3, "kN")],
        "N·s/m" => &[(1e3, "kN·s/m")],
        "N·s/m²" => &[(1e3, "kN·s/m²")],
        _ => &[],
    };
    let fits: Vec<String> = tries
        .iter()
        .filter(|(f, _)| (r.min..=r.max).contains(&(v * f)))
        .map(|(f, u)| format!("in {u}, that is {:.4} {}", v * f, r.unit))
        .collect();
    if fits.is_empty() {
        String::new()
    } else {
        format!(" — if it is {}", fits.join("; if "))
    }
}

/// Refuses the first finite positive value outside its plausible range, unless its path is
/// in `accept_implausible` (zero, negative and non-finite values are left to the field's own
/// checks).
pub fn check(cfg: &Config) -> Result<()> {
    // An entry that names no field of the table would silently accept nothing: a typo.
    // Besides the table, a vehicle's `x_front` may be listed: a vehicle meant to run on the
    // rigid track off the structure for the whole run (check::run).
    let known: Vec<String> = RANGES
        .iter()
        .flat_map(|r| (0..(r.get)(cfg).len()).map(move |i| path(cfg, r.field, i)))
        .chain((0..cfg.vehicles.len()).map(|i| format!("vehicles[{i}].x_front")))
        .collect();
    for (j, a) in cfg.accept_implausible.iter().enumerate() {
        if !known.contains(a) {
            return Err(VtbError::config(
                format!("accept_implausible[{j}]"),
                a,
                "names no field of the plausibility table in this configuration (docs/limits.md; \
                 e.g. \"speed\", \"vehicles[0].m_c\", \"structure.couplings[1].stiffness\"), \
                 nor a vehicle's x_front",
            ));
        }
    }
    for r in RANGES {
        for (i, v) in (r.get)(cfg).into_iter().enumerate() {
            if !v.is_finite()
                || v < 0.0
                || (v == 0.0 && r.min > 0.0)
                || (r.min..=r.max).contains(&v)
            {
                continue;
            }
            let p = path(cfg, r.field, i);
            if cfg.accept_implausible.contains(&p) {
                continue;
            }
            return Err(VtbError::config(
                p.clone(),
                v,
                format!(
                    "outside the plausible {} … {} {} ({}){}; if the value is meant, list \
                     \"{p}\" in accept_implausible",
                    r.min,
                    r.max,
                    r.unit,
                    r.covers,
                    hint(r, v)
                ),
            ));
        }
    }
    Ok(())
}

/// The table as (field, min, max, unit, covers) rows (for the Python layer and docs).
pub fn table() -> Vec<(&'static str, f64, f64, &'static str, &'static str)> {
    RANGES
        .iter()
        .map(|r| (r.field, r.min, r.max, r.unit, r.covers))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library::presets::{paper, paper_converged};

    #[test]
    fn the_presets_are_plausible() {
        check(&paper()).unwrap();
        check(&paper_converged()).unwrap();
    }

    #[test]
    fn a_speed_in_kmh_is_named_with_its_likely_unit() {
        let mut c = paper();
        c.speed = 300.0;
        let e = check(&c).unwrap_err().to_string();
        assert!(
            e.contains("`speed`") && e.contains("km/h, that is 83.3333 m/s"),
            "{e}"
        );
        c.accept_implausible = vec!["speed".into()];
        check(&c).unwrap();
    }

    #[test]
    fn a_force_in_kn_is_named_with_its_likely_unit() {
        let mut c = paper();
        c.vehicles.clear();
        c.forces = vec![crate::config::MovingForceConfig {
            magnitude: 170.0,
            x0: 0.0,
            layer: None,
        }];
        let e = check(&c).unwrap_err().to_string();
        assert!(
            e.contains("`forces[0].magnitude`") && e.contains("in kN, that is 170000.0000 N"),
            "{e}"
        );
        c.forces[0].magnitude = 170e3;
        check(&c).unwrap();
    }
}
