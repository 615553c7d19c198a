//! The stepper against closed forms (a unit oscillator) and its dampers against the same
//! system with the dampers assembled.

use super::*;
use crate::config::{DamperKind, DamperParams};
use crate::linalg::sparse::Assembler;

fn scalar(v: f64) -> CsrMatrix {
    let mut a = Assembler::new(1);
    a.add(0, 0, v);
    a.finish()
}

/// A unit oscillator: m = 1, k = 4π², u0 = 1, v0 = 0. Newmark average acceleration gives
/// u_n = cos(ω̄·n·Δt) with ω̄ = (2/Δt)·atan(ωΔt/2), i.e. T̄/T = (ωΔt/2)/atan(ωΔt/2)
/// (1.00033, 1.00817, 1.03207, 1.12003 for Δt/T = 0.01, 0.05, 0.1, 0.2), with no
/// amplitude decay.
#[test]
fn newmark_sdof_period_elongation_matches_exact_formula() {
    let w = 2.0 * std::f64::consts::PI;
    for (ratio, elong) in [
        (0.01, 1.00033),
        (0.05, 1.00817),
        (0.1, 1.03207),
        (0.2, 1.12003),
    ] {
        let dt = ratio;
        let (m, k, c) = (scalar(1.0), scalar(w * w), CsrMatrix::zeros(1));
        let mut nm: Newmark = Newmark::new(&m, &c, &k, dt, &[], 1, Numbering::Search, &[]).unwrap();
        nm.observe(&Shape {
            start: 0,
            values: vec![1.0],
        });
        nm.set_state(0, &[1.0], &[0.0], &[-w * w], &k, &m);
        let wbar = 2.0 / dt * (w * dt / 2.0).atan();
        assert!((w / wbar - elong).abs() < 5e-6, "T̄/T = {}", w / wbar);
        let zero = [0.0];
        let mut peak: f64 = 0.0;
        for step in 1..=2000 {
            nm.begin_step(&zero, &zero);
            nm.end_step();
            let (u, _, a) = nm.observed(0, 0);
            let t = step as f64 * dt;
            assert!(
                (u - (wbar * t).cos()).abs() < 1e-9,
                "Δt/T={ratio} step {step}: {u}"
            );
            // Newmark's acceleration of a free SDOF is −ω²u exactly.
            assert!((a + w * w * u).abs() < 1e-7 * w * w);
            peak = peak.max(u.abs());
        }
        assert!(peak <= 1.0 + 1e-12);
    }
}

/// The dampers' Woodbury path against the same system with the damper assembled into
/// M, K, C (a second method), with a linear spring acting through a port, for forward and
/// column ports and each kind.
#[test]
fn dampers_by_woodbury_match_assembled_matrices() {
    let n = 5;
    let (mut am, mut ak) = (Assembler::new(n), Assembler::new(n));
    for i in 0..n {
        am.add(i, i, 1.0 + i as f64);
        ak.add(i, i, 200.0);
        if i + 1 < n {
            for (r, c, v) in [(i, i + 1, -80.0), (i + 1, i, -80.0), (i + 1, i + 1, 80.0)] {
                ak.add(r, c, v);
            }
            ak.add(i, i, 80.0);
        }
    }
    let (m0, k0) = (am.finish(), ak.finish());
    let c0 = CsrMatrix::combine(&[(0.3, &m0), (1e-3, &k0)]);
    for kind in [DamperKind::Tid, DamperKind::Tvmd] {
        let att = Attachment {
            upper: Shape {
                start: 1,
                values: vec![0.3, 0.7],
            },
            lower: Shape {
                start: 4,
                values: vec![1.0],
            },
            node: n,
            params: DamperParams {
                kind,
                stiffness: 50.0,
                damping: 0.5,
                inertance: 0.2,
            },
        };
        // Full matrices with the node as DOF n: the damper assembled as a finite element.
        let [mf, kf, cf] = crate::model::dampers::stamp(
            [&m0, &k0, &c0],
            n + 1,
            std::slice::from_ref(&att),
            &[att.params],
        );
        let port = Shape {
            start: 0,
            values: vec![1.0, 0.5],
        };
        let k_contact = 300.0;
        let run = |nm: &mut Newmark| -> Vec<f64> {
            nm.observe(&Shape {
                start: 3,
                values: vec![1.0],
            });
            let u0 = [0.01, -0.02, 0.0, 0.03, 0.0, 0.0];
            nm.set_state(0, &u0, &[0.0; 6], &[0.0; 6], &kf, &mf);
            let mut ports = PortBlock::new(nm.n);
            nm.vector_into(&port, &mut ports.vecs[0]);
            let f = vec![0.0; nm.n];
            let mut out = Vec::new();
            for _ in 0..300 {
                nm.begin_step(&f, &f);
                nm.prepare_ports(&mut ports);
                let free = nm.free_port_disp(&ports)[0][0];
                let g = nm.port_compliance(&ports, &ports)[0][0][0];
                let p = -k_contact * free / (1.0 + k_contact * g);
                nm.add_port_forces(&ports, &[[p, 0.0, 0.0, 0.0]]);
                nm.end_step();
                out.push(nm.observed(0, 0).0);
                out.push(p);
            }
            out
        };
        for port_len in [2, 100] {
            let mut a: Newmark = Newmark::new(
                &m0,
                &c0,
                &k0,
                1e-2,
                &[0, 1],
                port_len,
                Numbering::Search,
                std::slice::from_ref(&att),
            )
            .unwrap();
            let mut b: Newmark = Newmark::new(
                &mf,
                &cf,
                &kf,
                1e-2,
                &[0, 1],
                port_len,
                Numbering::Search,
                &[],
            )
            .unwrap();
            let (ra, rb) = (run(&mut a), run(&mut b));
            let scale = rb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (x, y) in ra.iter().zip(&rb) {
                assert!(
                    (x - y).abs() < 1e-10 * scale,
                    "{kind:?}, port_len {port_len}: {x} vs {y}"
                );
            }
        }
    }
}

/// A wheel-like port (a load and a contact spring on the rail's shape vector at a moving x)
/// on two 32 m spans of the converged preset's finite elements (rail ten times finer than the
/// lower layers): with the length order (with contact ports the stepper keeps it, and its
/// columns of A⁻¹ are windows of about ±20 m around the wheel, which starts mid-structure) it
/// gives the general search's results (full solves) to round-off, in the rail's and the
/// girder's displacements and the contact force.
#[test]
fn length_order_matches_the_general_search_on_two_spans() {
    let mut cfg = crate::library::presets::paper_converged();
    cfg.structure.length = 64.0;
    for cp in cfg.structure.couplings.iter_mut() {
        cp.positions.retain(|&x| x <= 64.0 + 1e-9);
    }
    let st = crate::model::structure::Structure::build(&cfg).unwrap();
    let (m, c, k) = st.stepping_matrices();
    let dt = cfg.solver.dt;
    let rail: Vec<usize> = (0..st.layers[0].n_dofs()).collect();
    let order = st.length_order().unwrap();
    let girder = st.layers.len() - 1;
    let run = |numbering: Numbering| -> Vec<f64> {
        let mut nm: Newmark = Newmark::new(m, c, k, dt, &rail, 4, numbering, &[]).unwrap();
        for (layer, x) in [(0, 31.0), (0, 31.3), (girder, 16.0), (girder, 31.0)] {
            nm.observe(&st.shape(layer, x));
        }
        let mut ports = PortBlock::new(nm.n);
        let f = vec![0.0; nm.n];
        let (k_contact, load) = (1.2e9, 7e4);
        let mut out = Vec::new();
        for step in 0..600 {
            let x = 30.0 + 80.0 * dt * step as f64;
            nm.begin_step(&f, &f);
            nm.vector_into(&st.shape(0, x), &mut ports.vecs[0]);
            nm.prepare_ports(&mut ports);
            let free = nm.free_port_disp(&ports)[0][0];
            let g = nm.port_compliance(&ports, &ports)[0][0][0];
            let p = (load - k_contact * free) / (1.0 + k_contact * g);
            nm.add_port_forces(&ports, &[[p, 0.0, 0.0, 0.0]]);
            nm.end_step();
            out.extend((0..4).map(|j| nm.observed(j, 0).0));
            out.push(p);
        }
        out
    };
    let (search, along) = (run(Numbering::Search), run(Numbering::Order(&order)));
    // Compared per quantity (displacements and forces differ in scale).
    for q in 0..5 {
        let of = |v: &[f64]| -> Vec<f64> { v.iter().skip(q).step_by(5).copied().collect() };
        let (a, b) = (of(&search), of(&along));
        let scale = a.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        assert!(scale > 0.0, "quantity {q} moved");
        for (step, (x, y)) in a.iter().zip(&b).enumerate() {
            assert!(
                (x - y).abs() <= 1e-9 * scale,
                "quantity {q}, step {step}: {x} vs {y}"
            );
        }
    }
}
