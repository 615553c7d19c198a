//! The basis against independent quadratures, closed forms and brute-force sums.

use super::integrals::{gauss_legendre, hermite_values};
use super::modal::tail_sum;
use super::*;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

#[test]
fn gauss_legendre_is_exact_for_polynomials() {
    let f = Func::Poly {
        origin: 0.0,
        c: [1.0, 2.0, 3.0, 4.0],
    };
    let g = Func::Poly {
        origin: 1.0,
        c: [0.5, -1.0, 0.0, 2.0],
    };
    // Reference by expanding into monomials and integrating exactly on [0, 2].
    let n = 2000;
    let h = 2.0 / n as f64;
    // Simpson with many points as an independent check.
    let mut s = 0.0;
    for i in 0..=n {
        let x = i as f64 * h;
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        s += w * f.eval(x) * g.eval(x);
    }
    s *= h / 3.0;
    assert!(close(integrate(&f, &g, 0.0, 2.0), s, 1e-10));
}

#[test]
fn sine_products_match_closed_forms() {
    let l = 160.0;
    let b = ModalBasis::new(l, 2.0 / l, 10); // scale = 1
    for m in 1..=10 {
        for n in 1..=10 {
            let v = integrate(&b.sine(m), &b.sine(n), 0.0, l);
            let want = if m == n { l / 2.0 } else { 0.0 };
            assert!((v - want).abs() < 1e-10, "m={m} n={n} v={v}");
        }
    }
}

#[test]
fn poly_sine_matches_quadrature() {
    let l = 3.0;
    let p = Func::Poly {
        origin: 0.5,
        c: [0.3, -1.0, 0.7, 0.2],
    };
    for &(k, ph) in &[(0.1, 0.3), (2.0, 0.0), (25.0, 1.1)] {
        let s = Func::Sine {
            origin: 0.2,
            amp: 1.7,
            k,
            phase: ph,
        };
        let n = 20000;
        let h = l / n as f64;
        let mut q = 0.0;
        for i in 0..=n {
            let x = i as f64 * h;
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            q += w * p.eval(x) * s.eval(x);
        }
        q *= h / 3.0;
        assert!(close(integrate(&p, &s, 0.0, l), q, 1e-9), "k={k}");
    }
}

/// Gauss–Legendre reference integrals of the modal basis: the analytic Gram blocks must
/// match them, and the basis must span the Hermite cubics (h2 is reproduced exactly).
#[test]
fn modal_gram_matches_quadrature_and_spans_the_cubics() {
    let (l, rho_a) = (40.0, 3.0);
    let a = ModalBasis::new(l, rho_a, 12);
    let b = ModalBasis::new(l, 5.0, 17);
    let (xs, ws) = gauss_legendre::<16>();
    let n_int = 400;
    let pts: Vec<(f64, f64)> = (0..n_int)
        .flat_map(|e| {
            let (x0, h) = (e as f64 * l / n_int as f64, l / n_int as f64);
            xs.iter()
                .zip(ws)
                .map(move |(&t, w)| (x0 + 0.5 * h * (t + 1.0), 0.5 * h * w))
                .collect::<Vec<_>>()
        })
        .collect();
    let d2 = |bs: &ModalBasis, x: f64| {
        let hh = 1e-3;
        let (mut p, mut m, mut c) = (
            vec![0.0; bs.n_dofs()],
            vec![0.0; bs.n_dofs()],
            vec![0.0; bs.n_dofs()],
        );
        bs.eval_into(x + hh, &mut p);
        bs.eval_into(x - hh, &mut m);
        bs.eval_into(x, &mut c);
        (0..bs.n_dofs())
            .map(|i| (p[i] - 2.0 * c[i] + m[i]) / (hh * hh))
            .collect::<Vec<_>>()
    };
    for curvature in [false, true] {
        let g = ModalBasis::gram(&a, &b, curvature);
        let (mut va, mut vb) = (vec![0.0; a.n_dofs()], vec![0.0; b.n_dofs()]);
        let mut q = vec![0.0; g.len()];
        for &(x, w) in &pts {
            if curvature {
                va = d2(&a, x);
                vb = d2(&b, x);
            } else {
                a.eval_into(x, &mut va);
                b.eval_into(x, &mut vb);
            }
            for i in 0..a.n_dofs() {
                for j in 0..b.n_dofs() {
                    q[i * b.n_dofs() + j] += w * va[i] * vb[j];
                }
            }
        }
        let scale = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, (x, y)) in g.iter().zip(&q).enumerate() {
            let tol = if curvature { 2e-5 } else { 1e-9 };
            assert!(
                (x - y).abs() < tol * scale,
                "curv={curvature} entry {i}: {x} vs {y}"
            );
        }
    }
    // Unit modal mass of g3, g4 and of the sines.
    let m = ModalBasis::gram(&a, &a, false);
    let n = a.n_dofs();
    for i in 2..n {
        assert!((rho_a * m[i * n + i] - 1.0).abs() < 1e-12, "dof {i}");
    }
    // h2 = μ·g3 + projection: reconstruct at a few points.
    let mut v = vec![0.0; n];
    for &x in &[0.3, 7.0, 20.0, 39.9] {
        a.eval_into(x, &mut v);
        let proj: f64 = (0..a.n_sines)
            .map(|k| a.proj[0][k] * v[4 + k] / a.scale)
            .sum();
        let h2 = hermite_values(x, l)[1];
        assert!((a.mu[0] * v[2] + proj - h2).abs() < 1e-11 * l);
    }
}

#[test]
fn recurrence_matches_direct_sines() {
    let b = ModalBasis::new(160.0, 60.0, 220);
    let mut out = vec![0.0; b.n_dofs()];
    for &x in &[0.0, 0.37, 80.0, 123.456, 160.0] {
        b.eval_into(x, &mut out);
        for n in 1..=220 {
            let want = b.sine(n).eval(x);
            assert!((out[3 + n] - want).abs() < 1e-12 * b.scale, "x={x} n={n}");
        }
    }
}

#[test]
fn tail_sums_match_direct_summation() {
    for s in [2, 4, 6] {
        for n in [1usize, 7, 120, 1000] {
            let direct: f64 = ((n + 1)..4_000_000)
                .rev()
                .map(|k| (1.0 + 0.5 * if k % 2 == 0 { 1.0 } else { -1.0 }) / (k as f64).powi(s))
                .sum();
            let rest = if s == 2 { 1.0 / 4.0e6 } else { 0.0 };
            let t = tail_sum(1.0, 0.5, s, n);
            assert!(
                (t - direct - rest).abs() < 1e-7 * t,
                "s={s} n={n}: {t} vs {direct}"
            );
        }
    }
}

#[test]
fn hermite_end_conditions() {
    let l = 2.5;
    let h = hermite(1.0, l);
    let want = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    for (j, f) in h.iter().enumerate() {
        let d = f.d1();
        let got = [f.eval(1.0), d.eval(1.0), f.eval(1.0 + l), d.eval(1.0 + l)];
        for i in 0..4 {
            assert!((got[i] - want[j][i]).abs() < 1e-12, "h{} cond {i}", j + 1);
        }
    }
}

/// A rail mesh like the converged preset's: Timoshenko elements of 32 mm with a node on
/// every fastener, one shorter element to exercise uneven nodes.
fn rail_mesh() -> FemBasis {
    let mut nodes = FemBasis::uniform(0.0, 1.28, 40).nodes;
    nodes.insert(21, 0.6545);
    FemBasis {
        phi: vec![0.0; nodes.len() - 1],
        nodes,
    }
    .with_shear(6.625e6, 2.5e8)
}

/// Brute force: the midpoint rule over the patch on 200 000 points of the point shape
/// (a second quadrature that never splits at the nodes).
fn brute_patch(mesh: &FemBasis, x: f64, a: f64, mut f: impl FnMut(f64, f64)) {
    let n = 200_000;
    let h = 2.0 * a / n as f64;
    let w: Vec<f64> = (0..n)
        .map(|i| {
            let s = (-a + (i as f64 + 0.5) * h) / a;
            let xs = x + s * a;
            if mesh.covers(xs) { 1.0 - s * s } else { 0.0 }
        })
        .collect();
    let total: f64 = w.iter().sum();
    for (i, wi) in w.iter().enumerate() {
        f(x - a + (i as f64 + 0.5) * h, wi / total);
    }
}

#[test]
fn patch_shape_is_the_load_weighted_average_of_the_point_shape() {
    let mesh = rail_mesh();
    let basis = LayerBasis::Fem(mesh.clone());
    let a = 6.4e-3;
    // Inside one element, across a node, across the uneven node, at the end.
    for &x in &[0.101, 0.128, 0.6545 + 0.002, 0.64, 1.277] {
        let mut got = Shape::default();
        mesh.patch_into(x, a, &mut got);
        assert!(got.values.len() <= mesh.patch_len(a));
        let mut want = vec![0.0; mesh.n_dofs()];
        brute_patch(&mesh, x, a, |xs, w| {
            let s = basis.shape(xs.min(mesh.end()));
            for (k, v) in s.values.iter().enumerate() {
                want[s.start + k] += w * v;
            }
        });
        for (k, w) in want.iter().enumerate() {
            let g = k
                .checked_sub(got.start)
                .and_then(|j| got.values.get(j))
                .copied()
                .unwrap_or(0.0);
            assert!((g - w).abs() < 1e-6, "x={x} dof {k}: {g} vs {w}");
        }
    }
}

#[test]
fn a_patch_sees_a_linear_field_at_its_centre() {
    // Nodal values of w = 2 + 3x (ψ = 3): the interdependent element interpolates it
    // exactly, and a symmetric load averages it to its value at the centre.
    let mesh = rail_mesh();
    let u: Vec<f64> = mesh
        .nodes
        .iter()
        .flat_map(|&x| [2.0 + 3.0 * x, 3.0])
        .collect();
    for &x in &[0.3, 0.64, 0.655] {
        let mut s = Shape::default();
        mesh.patch_into(x, 6.4e-3, &mut s);
        let w: f64 = s.values.iter().zip(&u[s.start..]).map(|(a, b)| a * b).sum();
        assert!((w - (2.0 + 3.0 * x)).abs() < 1e-12, "{w}");
    }
}

#[test]
fn patch_flexibility_is_the_weighted_average_of_the_local_flexibility() {
    let mesh = rail_mesh();
    for &x in &[0.101, 0.128, 0.6545 + 0.002] {
        let got = mesh.patch_flexibility(6.625e6, x, 6.4e-3);
        let mut want = 0.0;
        brute_patch(&mesh, x, 6.4e-3, |xs, w| {
            want += w * mesh.local_flexibility(6.625e6, xs)
        });
        assert!((got - want).abs() < 1e-6 * want, "x={x}: {got} vs {want}");
    }
}

/// The slope shape is the derivative of the value shape: against a central difference inside
/// every kind of element (Euler–Bernoulli, Timoshenko), zero off the mesh; a modal layer has
/// none.
#[test]
fn slope_shape_is_the_derivative_of_the_value_shape() {
    for mesh in [rail_mesh(), FemBasis::uniform(0.0, 1.0, 10)] {
        slope_matches_a_central_difference(mesh);
    }
    let modal = LayerBasis::Modal(ModalBasis::new(10.0, 1.0, 4));
    let mut d = modal.shape(5.0);
    assert!(!modal.eval_slope(5.0, &mut d));
}

fn slope_matches_a_central_difference(mesh: FemBasis) {
    let basis = LayerBasis::Fem(mesh.clone());
    let (mut s, mut sp, mut sm, mut d) = (
        basis.shape(0.0),
        basis.shape(0.0),
        basis.shape(0.0),
        basis.shape(0.0),
    );
    let h = 1e-6;
    for k in 0..400 {
        let x = mesh.start() + (mesh.end() - mesh.start()) * (k as f64 + 0.37) / 400.0;
        let e = mesh.element_of(x);
        // keep the stencil inside the element: the slope jumps at nodes
        if x - h <= mesh.nodes[e] || x + h >= mesh.nodes[e + 1] {
            continue;
        }
        assert!(basis.eval_slope(x, &mut d));
        basis.eval(x, &mut s);
        basis.eval(x + h, &mut sp);
        basis.eval(x - h, &mut sm);
        assert_eq!((d.start, sp.start, sm.start), (s.start, s.start, s.start));
        for i in 0..4 {
            let fd = (sp.values[i] - sm.values[i]) / (2.0 * h);
            assert!(
                close(d.values[i], fd, 1e-6),
                "x = {x}, entry {i}: {} vs {fd}",
                d.values[i]
            );
        }
    }
    assert!(basis.eval_slope(mesh.end() + 1.0, &mut d));
    assert!(d.values.iter().all(|&v| v == 0.0));
}
