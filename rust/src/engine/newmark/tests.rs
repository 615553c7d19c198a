//! The Newmark engine's lockstep lanes and treads.

use super::*;
use crate::config::DamperKind;
use crate::config::{Config, DamperGroup};
use crate::engine::simulate;
use crate::library::presets;

fn short_with_dampers() -> Config {
    let mut cfg = presets::paper();
    cfg.solver.t_end = Some(0.05);
    cfg.dampers = vec![DamperGroup {
        name: Some("tids".into()),
        kind: DamperKind::Tid,
        inertance: 3.0,
        stiffness: 1e8,
        damping: 1e3,
        count: Some(3),
        x0: Some(30.0),
        spacing: Some(0.64),
        positions: None,
        upper: "rail".into(),
        lower: "slab".into(),
    }];
    cfg
}

/// Four lanes on one model, one of them on an irregularity that is non-finite from 9 m on: that lane fails with a `Solver` error, the other three give exactly the bits
/// of their single runs (different damper parameters and irregularities).
#[test]
fn a_failing_lane_leaves_its_group_unharmed() {
    let cfg = short_with_dampers();
    let smooth = Profile::flat();
    let wavy = Profile {
        x0: -1.0,
        dx: 0.01,
        values: (0..20_000).map(|i| 1e-4 * (i as f64 * 0.3).sin()).collect(),
        treads: Vec::new(),
    };
    let mut broken = wavy.clone();
    broken
        .values
        .iter_mut()
        .skip(1000)
        .for_each(|v| *v = f64::NAN);
    let model = crate::check::validated(cfg.clone(), smooth.clone()).unwrap();
    let param = |k: f64, b: f64| {
        vec![
            DamperParams {
                kind: DamperKind::Tid,
                stiffness: k,
                damping: 1e3,
                inertance: b,
            };
            3
        ]
    };
    let lanes = [
        LaneSpec {
            profile: &smooth,
            dampers: param(1e8, 3.0),
        },
        LaneSpec {
            profile: &wavy,
            dampers: param(7e8, 9.0),
        },
        LaneSpec {
            profile: &broken,
            dampers: param(2e7, 1.0),
        },
        LaneSpec {
            profile: &wavy,
            dampers: param(1e4, 5.0),
        },
    ];
    let out = Simulation::<4>::lanes(&model, &lanes, Record::Full)
        .unwrap()
        .run_lanes(None)
        .unwrap();
    assert!(
        matches!(out[2], Err(VtbError::Solver(_))),
        "{:?}",
        out[2].as_ref().err()
    );
    for j in [0, 1, 3] {
        let alone = Simulation::<1>::lanes(&model, &lanes[j..j + 1], Record::Full)
            .unwrap()
            .run_lanes(None)
            .unwrap()
            .pop()
            .unwrap()
            .unwrap();
        let got = out[j].as_ref().unwrap();
        for (a, b) in alone.acc.iter().zip(&got.acc) {
            assert_eq!(a.to_bits(), b.to_bits(), "lane {j}");
        }
        assert_eq!(alone.contact_force, got.contact_force);
        assert_eq!(alone.metrics(), got.metrics());
    }
}

/// A tread irregularity is the rail's seen by one wheel: the same samples as treads of
/// every wheel over a smooth rail give the rail run's bits; on one wheel only, that wheel's
/// contact force departs most from the smooth run's.
#[test]
fn treads_on_every_wheel_equal_the_rail_profile() {
    let cfg = short_with_dampers();
    let wheels = cfg.vehicles.len() * 4;
    let wavy: Vec<f64> = (0..20_000).map(|i| 1e-4 * (i as f64 * 0.3).sin()).collect();
    let grid = |values: Vec<f64>, treads: Vec<Vec<f64>>| Profile {
        x0: -1.0,
        dx: 0.01,
        values,
        treads,
    };
    let on_rail = grid(wavy.clone(), Vec::new());
    let on_wheels = grid(vec![0.0; wavy.len()], vec![wavy.clone(); wheels]);
    let mut one = vec![Vec::new(); wheels];
    one[0] = wavy.clone();
    let on_wheel_0 = grid(vec![0.0; wavy.len()], one);
    let a = simulate(&cfg, &on_rail, None).unwrap();
    let b = simulate(&cfg, &on_wheels, None).unwrap();
    assert_eq!(a.contact_force, b.contact_force);
    assert_eq!(a.metrics(), b.metrics());
    let c = simulate(&cfg, &on_wheel_0, None).unwrap();
    let a = simulate(&cfg, &grid(vec![0.0; wavy.len()], Vec::new()), None).unwrap();
    let change = |w: usize| {
        (0..=c.n_steps)
            .map(|k| (c.contact_force[k * wheels + w] - a.contact_force[k * wheels + w]).abs())
            .fold(0.0, f64::max)
    };
    // Wheel 0 rides its tread; the others feel it only through the car and the rail.
    for w in 1..wheels {
        assert!(
            change(w) < 0.5 * change(0),
            "wheel {w}: {} vs {}",
            change(w),
            change(0)
        );
    }
}

#[test]
fn treads_need_one_row_per_wheel_on_the_rail_grid() {
    let cfg = short_with_dampers();
    let p = Profile {
        x0: -1.0,
        dx: 0.01,
        values: vec![0.0; 20_000],
        treads: vec![vec![0.0; 10]],
    };
    let e = crate::check::validate(&cfg, &p).unwrap_err().to_string();
    assert!(e.contains("irregularity.treads"), "{e}");
    let wheels = cfg.vehicles.len() * 4;
    let mut rows = vec![Vec::new(); wheels];
    rows[1] = vec![0.0; 10];
    let e = crate::check::validate(
        &cfg,
        &Profile {
            treads: rows,
            ..p.clone()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("irregularity.treads[1]"), "{e}");
    let mut rows = vec![Vec::new(); wheels];
    rows[0] = vec![0.0; 20_000];
    rows[0][7] = f64::INFINITY;
    let e = crate::check::validate(&cfg, &Profile { treads: rows, ..p })
        .unwrap_err()
        .to_string();
    assert!(e.contains("irregularity.treads[0][7]"), "{e}");
}

/// Moving forces on the rail and on the girder of the hybrid model, whose layers have different
/// numbers of modes: each load's shape is its own layer's (a shared buffer once kept the
/// rail's length for the girder and indexed past the structure's DOFs).
#[test]
fn moving_forces_on_layers_of_different_mode_counts() {
    let mut cfg = presets::paper();
    cfg.solver.t_end = Some(0.01);
    cfg.forces = vec![
        crate::config::MovingForceConfig {
            magnitude: 5e4,
            x0: 3.0,
            layer: None,
        },
        crate::config::MovingForceConfig {
            magnitude: 1e5,
            x0: 10.0,
            layer: Some("bridge".into()),
        },
    ];
    let r = simulate(&cfg, &Profile::flat(), None).unwrap();
    assert!(r.metrics().values().all(|v| v.is_finite()));
}
