//! The run: speed, solver and end time; the vehicles and forces on the structure (a wheel
//! crossing a rail end), the irregularity profile and the treads under them.

use super::*;
use crate::config::fields::on_interval;

/// Speed, solver and the run's end; returns the time step and the distance travelled.
pub(super) fn timing(cfg: &Config) -> Result<(f64, f64)> {
    let speed = non_negative("speed", cfg.speed)?;
    let sv = &cfg.solver;
    sv.validate()?;
    let dt = sv.dt;
    if sv.edge_ramp > 0.0 && cfg.discretisation.method == Method::Hybrid {
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
    let t_end = cfg.t_end();
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
    let travel = speed * cfg.n_steps() as f64 * dt;
    Ok((dt, travel))
}

/// Vehicles and moving forces: their own fields, the method, the profile under them.
pub(super) fn loads(cfg: &Config, travel: f64, profile: &Profile) -> Result<()> {
    for (i, v) in cfg.vehicles.iter().enumerate() {
        let p = format!("vehicles[{i}]");
        v.validate(&p)?;
        // The engines and the records hold one vehicle model per run.
        let (kind, first) = (v.model.kind(), cfg.vehicles[0].model.kind());
        if kind != first {
            return Err(VtbError::config(
                format!("{p}.model"),
                kind.name(),
                format!(
                    "every vehicle of a run is of one model; vehicles[0] is a {:?}",
                    first.name()
                ),
            ));
        }
        if v.wheels.contact_patch && cfg.discretisation.method != Method::Fem {
            return Err(VtbError::config(
                format!("{p}.contact_patch"),
                true,
                format!(
                    "a distributed contact needs a finite-element rail (discretisation.method \
                     = \"fem\"), not {:?}",
                    cfg.discretisation.method
                ),
            ));
        }
        let offs = v.wheel_offsets();
        // Wheels may start before x = 0 and end beyond L: off the structure they run on a
        // rigid track (docs/model.md §4).
        let (rear, front) = (offs[offs.len() - 1], offs[0] + travel);
        on_the_rail(cfg, &p, v.wheels.x_front, (rear, front), travel)?;
        let (a, b) = cfg.extent(0);
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
        if cfg.solver.edge_ramp == 0.0 && !cfg.solver.edge_step {
            // The engine's rule (`Structure::edge_share`): a wheel is on the rail for a ≤ x ≤ b,
            // give or take the rounding of the ends (a rear wheelset placed on x = 0, or
            // t_end = L/v reaching x = L in n·Δt), which crosses nothing.
            let on = |x: f64| on_interval(x, a, b).is_some();
            let crossing = offs.iter().find_map(|&w| {
                let end = w + travel;
                if !on(w) && on(end) || w < a && end > b && !on(w) && !on(end) {
                    Some(("start", a))
                } else if on(w) && !on(end) {
                    Some(("end", b))
                } else {
                    None
                }
            });
            if let Some((which, x)) = crossing {
                let tail = if which == "end" && cfg.solver.tail.is_some() {
                    " (solver.tail runs the vehicles off it)"
                } else {
                    ""
                };
                return Err(VtbError::config(
                    format!("{p}.x_front"),
                    v.wheels.x_front,
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
    for (i, f) in cfg.forces.iter().enumerate() {
        let p = format!("forces[{i}]");
        f.validate(&p)?;
        let li = match &f.layer {
            Some(layer) => cfg.layer_index(layer).ok_or_else(|| {
                VtbError::config(
                    format!("{p}.layer"),
                    format!("{layer:?}"),
                    "no layer of that name",
                )
            })?,
            None => 0,
        };
        // A force that never reaches its layer loads nothing: the run would answer for an
        // unloaded structure.
        let (a, b) = cfg.extent(li);
        if !reaches(f.x0, f.x0 + travel, a, b) {
            return Err(VtbError::config(
                format!("{p}.x0"),
                f.x0,
                format!(
                    "the force travels [{:.4}, {:.4}] m and never reaches its layer [{a}, {b}] m: it \
                     would load nothing",
                    f.x0,
                    f.x0 + travel
                ),
            ));
        }
    }
    if cfg.vehicles.is_empty() && cfg.forces.is_empty() {
        return Err(VtbError::config(
            "vehicles",
            "[]",
            "nothing loads the structure: give at least one vehicle or moving force",
        ));
    }
    Ok(())
}

/// A vehicle none of whose wheels ever rolls onto the rail loads nothing: the run would
/// answer for a vehicle on rigid track and an unloaded structure, unless that is what is
/// meant (its x_front listed in accept_implausible). `(rear, front)`: its wheels' span.
fn on_the_rail(
    cfg: &Config,
    p: &str,
    x_front: f64,
    (rear, front): (f64, f64),
    travel: f64,
) -> Result<()> {
    let (a, b) = cfg.extent(0);
    let meant = cfg.accept_implausible.contains(&format!("{p}.x_front"));
    if !meant && !reaches(rear, front, a, b) {
        return Err(VtbError::config(
            format!("{p}.x_front"),
            x_front,
            format!(
                "the wheels of this vehicle span [{rear:.4}, {front:.4}] m during the run ({travel:.4} m \
                 of travel up to t = {:.6} s) and never reach the rail [{a}, {b}] m: it would load \
                 nothing. Place the vehicle so that it runs onto the rail, or lengthen the run \
                 (solver.t_end, or solver.tail to run the whole train over); a run on the rigid \
                 track alone lists \"{p}.x_front\" in accept_implausible",
                cfg.t_end()
            ),
        ));
    }
    Ok(())
}

/// Whether a load whose positions span [`lo`, `hi`] over the run meets the interval [`a`, `b`]
/// it rolls on, with the ends' rounding the engine allows (`on_interval`).
fn reaches(lo: f64, hi: f64, a: f64, b: f64) -> bool {
    let on = |x: f64| on_interval(x, a, b).is_some();
    on(lo) || on(hi) || (lo < a && hi > b)
}

/// The sampled rail profile.
pub(super) fn profile(profile: &Profile) -> Result<()> {
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

/// Tread irregularities: none, or one row per wheel, each empty or on the rail's grid.
pub(super) fn treads(cfg: &Config, profile: &Profile) -> Result<()> {
    if profile.treads.is_empty() {
        return Ok(());
    }
    let wheels: usize = cfg.vehicles.iter().map(VehicleConfig::n_wheels).sum();
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
