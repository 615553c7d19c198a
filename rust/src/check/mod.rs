//! The judge of a configuration: every validation phase, the plausible ranges and the memory
//! budget, above the model and the outputs it consults. Each configuration part checks its own
//! fields (`validate(path)` in crate::config); the phases here relate one part to another:
//! names, positions on layers, the method, the run, the outputs, the dampers, the budget.

pub mod budget;
mod dampers;
mod output;
pub mod plausibility;
mod run;
mod structure;

use crate::config::fields::{
    MAX_ELEMENTS, MAX_MODES, MAX_STEPS, MAX_TIDS, finite, non_negative, positive, within,
};
use crate::config::{
    Config, CouplingConfig, CouplingKind, DamperGroup, GROUND, LayerConfig, Method, Profile,
    VehicleConfig,
};
use crate::error::{Result, VtbError};
use crate::model::Model;

pub fn validate(cfg: &Config, profile: &Profile) -> Result<()> {
    plausibility::check(cfg)?;
    let length = structure::layers_and_couplings(cfg)?;
    structure::discretisation(cfg)?;
    let (dt, travel) = run::timing(cfg)?;
    run::loads(cfg, travel, profile)?;
    output::points_and_indices(cfg, dt)?;
    run::profile(profile)?;
    run::treads(cfg, profile)?;
    dampers::groups(cfg, length)?;
    budget::check_model(cfg)?;
    // The least any run records (one job, the indices' histories): a run too long for the
    // budget is refused here, before an irregularity profile is drawn for it.
    budget::check_histories(cfg, crate::outputs::Record::Metrics, 1)
}

/// The model of a configuration validated against `profile`.
pub fn validated(cfg: Config, profile: Profile) -> Result<Model> {
    validate(&cfg, &profile)?;
    Model::build(cfg, profile)
}

/// `x` (field `field`) lies on layer `i`, and not on one of its joints.
fn on_layer(cfg: &Config, field: &str, x: f64, i: usize) -> Result<f64> {
    let (a, b) = cfg.extent(i);
    let layer = &cfg.structure.layers[i];
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

/// The layers `path.upper` and `path.lower` name (`None`: the ground), refused when one does
/// not exist or both are the same (`same`: the reason given).
fn layer_pair(
    cfg: &Config,
    path: &str,
    upper: &str,
    lower: &str,
    same: &str,
) -> Result<(usize, Option<usize>)> {
    let u = cfg.layer_index(upper).ok_or_else(|| {
        VtbError::config(
            format!("{path}.upper"),
            format!("{upper:?}"),
            "no layer of that name",
        )
    })?;
    if lower == GROUND {
        return Ok((u, None));
    }
    let l = cfg.layer_index(lower).ok_or_else(|| {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn refused_field(cfg: &Config) -> Option<String> {
        match validate(cfg, &Profile::flat()) {
            Ok(()) => None,
            Err(VtbError::Config { field, .. }) => Some(field),
            Err(e) => panic!("not a ConfigError: {e}"),
        }
    }

    #[test]
    fn a_wheel_crossing_a_rail_end_needs_the_hand_over_set() {
        // The article car started 5 m before the rail: its wheels cross x = 0 at 80 m/s.
        let mut cfg = crate::library::presets::paper();
        cfg.vehicles[0].wheels.x_front = -5.0;
        assert_eq!(refused_field(&cfg).as_deref(), Some("vehicles[0].x_front"));
        cfg.solver.edge_step = true; // the step, on request (the hybrid takes no ramp)
        assert_eq!(refused_field(&cfg), None);
        cfg.solver.edge_ramp = 5.0; // a step and a hand-over at once: refused
        assert_eq!(refused_field(&cfg).as_deref(), Some("solver.edge_step"));
    }

    /// A vehicle none of whose wheels ever rolls onto the rail would load nothing: refused on
    /// its `x_front` whether it stands beyond the structure, or behind it on a run too short
    /// to arrive, and whatever the hand-over at the rail's ends.
    #[test]
    fn a_vehicle_that_never_reaches_the_rail_is_refused() {
        let message = |cfg: &Config| match validate(cfg, &Profile::flat()) {
            Err(VtbError::Config { field, reason, .. }) => (field, reason),
            other => panic!("not refused: {other:?}"),
        };
        let mut cfg = crate::library::presets::paper();
        let length = cfg.structure.length;
        for edge_step in [false, true] {
            cfg.solver.edge_step = edge_step;
            // far beyond the structure (the run's end time then is that of a run of no length)
            cfg.vehicles[0].wheels.x_front = 1e6;
            cfg.solver.t_end = Some(0.1);
            let (field, reason) = message(&cfg);
            assert_eq!(field, "vehicles[0].x_front");
            assert!(
                reason.contains(&format!("never reach the rail [0, {length}] m")),
                "{reason}"
            );
            // behind it: 80 m/s for 0.1 s is 8 m of travel, the front wheel ends at −492 m
            cfg.vehicles[0].wheels.x_front = -500.0;
            let (field, reason) = message(&cfg);
            assert_eq!(field, "vehicles[0].x_front");
            let rear = cfg.vehicles[0].wheel_offsets()[3];
            assert!(
                reason.contains(&format!("span [{rear:.4}, -492.0000] m")),
                "{reason}"
            );
        }
        // long enough to arrive: the step onto the rail, as asked for, runs
        cfg.solver.t_end = Some(500.0 / cfg.speed);
        assert_eq!(refused_field(&cfg), None);
        // a wheel reaching the rail's start within its rounding has arrived (the engine's rule)
        cfg.solver.t_end = Some(0.1);
        cfg.vehicles[0].wheels.x_front = -8.0 * (1.0 + 1e-12);
        assert_eq!(refused_field(&cfg), None);
        // one car of a train that stays behind is refused by its own index
        let mut second = cfg.vehicles[0].clone();
        second.wheels.x_front = -500.0;
        cfg.vehicles.push(second);
        assert_eq!(refused_field(&cfg).as_deref(), Some("vehicles[1].x_front"));
        // unless a run on the rigid track alone is meant
        cfg.accept_implausible = vec!["vehicles[1].x_front".into()];
        assert_eq!(refused_field(&cfg), None);
        cfg.accept_implausible = vec!["vehicles[2].x_front".into()]; // no such vehicle
        assert_eq!(
            refused_field(&cfg).as_deref(),
            Some("accept_implausible[0]")
        );
        cfg.accept_implausible.clear();
        // a quarter car standing still off the rail (speed 0) as well
        let mut qc = crate::library::presets::paper();
        qc.vehicles[0].model =
            crate::config::VehicleModel::QuarterCar(crate::config::QuarterCarConfig {
                m_c: 14e3,
                m_w: 1.7e3,
                k_p: 1.2e6,
                c_p: 3e4,
            });
        qc.speed = 0.0;
        qc.solver.t_end = Some(0.01);
        qc.vehicles[0].wheels.x_front = length + 1.0;
        assert_eq!(refused_field(&qc).as_deref(), Some("vehicles[0].x_front"));
        qc.vehicles[0].wheels.x_front = length;
        assert_eq!(refused_field(&qc), None);
    }

    /// A car whose rear wheelset stands on the pinned support at x = 0 has not crossed the
    /// rail's start, though its wheel position rounds to −6.7e-16 m (l_c = 9, l_t = 1.2), and
    /// the engine puts that wheel's whole load on the rail from t = 0: the run starts in the
    /// same static state as a car 1 µm further on.
    #[test]
    fn a_wheel_on_the_rails_start_at_t0_has_not_crossed_it() {
        let mut cfg = crate::library::presets::paper();
        cfg.solver.t_end = Some(0.002);
        let v = &mut cfg.vehicles[0];
        let crate::config::VehicleModel::Car(car) = &mut v.model else {
            unreachable!("the article's car")
        };
        (car.l_c, car.l_t) = (9.0, 1.2);
        v.wheels.x_front = 2.0 * (car.l_c + car.l_t);
        assert!(
            v.wheel_offsets()[3] < 0.0,
            "the rounding this test is about"
        );
        assert_eq!(refused_field(&cfg), None);
        let at_zero = crate::engine::simulate(&cfg, &Profile::flat(), None).unwrap();
        cfg.vehicles[0].wheels.x_front += 1e-6;
        let inside = crate::engine::simulate(&cfg, &Profile::flat(), None).unwrap();
        let (w0, w1) = (at_zero.wheel_force(3)[0], inside.wheel_force(3)[0]);
        assert!((w0 - w1).abs() < 1e-6 * w1, "{w0} vs {w1}");
        // a wheel truly before the start is still refused
        cfg.vehicles[0].wheels.x_front -= 1e-3;
        assert_eq!(refused_field(&cfg).as_deref(), Some("vehicles[0].x_front"));
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
        cfg.vehicles[0].wheels.contact_patch = true;
        assert_eq!(
            refused_field(&cfg).as_deref(),
            Some("vehicles[0].contact_patch")
        );
        assert_eq!(
            refused_field(&crate::library::presets::paper_converged()),
            None
        );
        cfg.discretisation.method = Method::Fem;
        cfg.vehicles[0].wheels.rail_crown_radius = 0.0;
        assert_eq!(
            refused_field(&cfg).as_deref(),
            Some("vehicles[0].rail_crown_radius")
        );
    }
}
