//! FE–SEA hybrid correction of the rail (docs/model.md §6, article §2.2; derivations in
//! docs/fesea.md).
//!
//! The rail's sine modes beyond the global set (sines N_g+1 .. N_g+N_l of the top layer) are
//! *local* modes, condensed out of the time-domain model. Each local mode j is a
//! mass-normalised sine: modal mass m_j = ρA∫s_j² = 1, stiffness k_j = EI∫s_j″² plus the
//! springs attached to the rail with their other end blocked, damping c_j from the rail's
//! Rayleigh damping and those dashpots, ω_j = sqrt(k_j/m_j), loss factor η_j = c_j/(m_j·ω_j).
//! Local modes are orthogonal to the global sines, so they couple to the four cubic DOFs
//! g1..g4 of the rail only.
//!
//! Exact condensation at frequency ω gives D_gg′ = D_gg − Σ_j D_gj·D_jgᵀ/D_jj with
//! D_jj = k_j + iωc_j − ω²m_j, and F_g′ = F_g − Σ_j D_gj·F_j/D_jj, F_j(t) = Σ_w P_w·s_j(x_w).
//! The time-domain model uses one representative frequency ω_r and the resonant band
//! B = [ω_r·2^(−1/6), ω_r·2^(1/6)]:
//!
//! * `Mass` (the article's reading, D_gj ≈ −ω²M_gj): modes below B (ω ≫ ω_j) give
//!   ΔM = −Σ M_gj·M_jgᵀ/m_j and the load −Σ M_gj·F_j/m_j; modes in B, averaged over their
//!   resonances (Strasberg–Feit), give ΔC = (π/2)·ω_r²·ν⟨M_gj·M_jgᵀ/m_j⟩ and the load
//!   −(π/2)·ν·d/dt⟨M_gj·F_j/m_j⟩; modes above B are neglected.
//! * `Full` (default), on the cubic residuals g3, g4 only (the end functions g1, g2 carry the
//!   rail's rigid motion with the track and stay as in the modal model, docs/fesea.md):
//!   D_gj = K_gj + iωC_gj − ω²M_gj exactly (bending, rail springs and dashpots). Dividing
//!   by D_jj splits every mode's term into an exact frequency-independent part,
//!   ΔM = −M·Mᵀ/m, ΔK = −(K·Mᵀ + M·Kᵀ)/m + k·M·Mᵀ/m² (ΔC alike) and the load −M·F_j/m,
//!   which is exactly the change of the cubic functions to g̃ = g − Σ_j (M_gj/m_j)·s_j
//!   (mass-orthogonal to the local modes; g̃ is then also the shape for displacements),
//!   plus a residual resonator per mode with the stiffness coupling of g̃,
//!   c_j = K_gj − ω_j²·M_gj: −c·cᵀ/D_jj and −c·F_j/D_jj. Outside B the residual is taken at
//!   ω_r, load −c·F_j/(k_j − ω_r²m_j): below B as the positive stiffness
//!   ΔK −= c·cᵀ/(k_j − ω_r²m_j); above B as ΔK −= c·cᵀ/k_j (static condensation) plus the
//!   positive mass ΔM += c·cᵀ·m_j/(k_j·(k_j − ω_r²m_j)), exact at ω = 0 and at ω_r, so that
//!   K + ΔK and M + ΔM stay positive semi-definite; in B, the resonance average:
//!   ΔC += (π/2)·c·cᵀ/(m·ω_j·ω_r·|B|), load +(π/2)·c·Ḟ_j/(m·ω_j·ω_r·|B|).
//!   The article's mass coupling is the case K_gj = C_gj = 0. The cubic functions h2, h4 of
//!   the article's basis are made of high sines, so with mass coupling alone the below-band
//!   correction removes most of their mass and none of their stiffness (docs/fesea.md).
//!
//! ν⟨X⟩ is taken as (Σ_{j∈B} X_j)/|B| (modes counted in the band over its width), so ν and
//! ⟨·⟩ come from the same modes.

use crate::config::{Config, CouplingKind, FeSeaCoupling, GROUND};
use crate::error::{Result, VtbError};
use crate::model::basis::ModalBasis;
use crate::model::layers::Layer;
use serde::Serialize;
use std::f64::consts::PI;

/// Half-width of the resonant band on a log scale: B = [ω_r·2^(−1/6), ω_r·2^(1/6)] (a third
/// of an octave).
pub const BAND_HALF_OCTAVES: f64 = 1.0 / 6.0;

/// Where a local mode lies relative to the resonant band.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ModeClass {
    Below,
    Resonant,
    Above,
}

impl ModeClass {
    /// Where a mode of natural frequency `omega` lies relative to `band` (rad/s).
    fn of(omega: f64, band: (f64, f64)) -> Self {
        if omega < band.0 {
            ModeClass::Below
        } else if omega <= band.1 {
            ModeClass::Resonant
        } else {
            ModeClass::Above
        }
    }
}

/// One local rail mode.
#[derive(Clone, Debug, Serialize)]
pub struct LocalMode {
    /// Sine index n of s_n = sqrt(2/(ρAL))·sin(nπx/L).
    pub index: usize,
    /// Natural frequency f_j (Hz) and ω_j (rad/s).
    pub frequency: f64,
    pub omega: f64,
    /// Modal mass (kg), stiffness (N/m) and viscous damping (N·s/m), per unit modal amplitude.
    pub mass: f64,
    pub stiffness: f64,
    pub damping: f64,
    /// Loss factor η_j = c_j/(m_j·ω_j).
    pub loss_factor: f64,
    pub class: ModeClass,
}

/// A local mode's coupling to the rail's cubic DOFs g1..g4: mass M_gj = ρA∫g·s_j, stiffness
/// K_gj (bending EI∫g″·s_j″ plus the rail's springs, other end blocked) and damping C_gj
/// (Rayleigh plus the rail's dashpots).
#[derive(Clone, Debug)]
pub struct ModeCoupling {
    pub mode: LocalMode,
    pub m: [f64; 4],
    pub k: [f64; 4],
    pub c: [f64; 4],
}

/// The correction of one configuration.
#[derive(Clone, Debug)]
pub struct FeSea {
    pub coupling: FeSeaCoupling,
    /// Representative excitation frequency ω_r (rad/s) and the resonant band (rad/s).
    pub omega_r: f64,
    pub band: (f64, f64),
    pub modes: Vec<LocalMode>,
    /// Structure DOFs of the rail's cubic functions g1..g4.
    pub dofs: [usize; 4],
    /// ΔM, ΔK and ΔC on those DOFs.
    pub delta_m: [[f64; 4]; 4],
    pub delta_k: [[f64; 4]; 4],
    pub delta_c: [[f64; 4]; 4],
    /// `Full`: the part of ΔM, ΔK, ΔC that is the change g → g̃ itself (mode by mode; the
    /// assembled structure applies that change exactly instead, see [`FeSea::shape_terms`]).
    pub exact: [[[f64; 4]; 4]; 3],
    /// `Full`: the static condensation −Σ_j c_j c_jᵀ/k_j of the modes above B (part of ΔK),
    /// mode by mode, and those modes' sine indices. The assembled structure condenses them
    /// together instead (their mutual coupling through discrete springs kept), which keeps K
    /// positive semi-definite.
    pub above_k: [[f64; 4]; 4],
    pub above: Vec<usize>,
    /// `Full`: (j, −M_gj/m_j): the cubic functions with their local content removed,
    /// g̃ = g − Σ_j (M_gj/m_j)·s_j, the rail's shape functions for displacements and loads.
    shape_terms: Vec<(usize, [f64; 4])>,
    /// (sine index j, a_j) and (j, b_j), sorted by j: a load history F_j(t) on local mode j
    /// adds a_j·F_j(t) + b_j·dF_j/dt to the forces on g1..g4 (beyond the shape change).
    terms_a: Vec<(usize, [f64; 4])>,
    terms_b: Vec<(usize, [f64; 4])>,
    length: f64,
    scale: f64,
}

/// s·x·yᵀ.
fn outer(x: &[f64; 4], y: &[f64; 4], s: f64) -> [[f64; 4]; 4] {
    std::array::from_fn(|p| std::array::from_fn(|q| s * x[p] * y[q]))
}

fn add(acc: &mut [[f64; 4]; 4], m: [[f64; 4]; 4]) {
    for p in 0..4 {
        for q in 0..4 {
            acc[p][q] += m[p][q];
        }
    }
}

/// The local modes of the top layer of a modal config and their couplings to g1..g4.
pub fn local_modes(cfg: &Config, rail: &Layer) -> Result<Vec<ModeCoupling>> {
    let lc = &cfg.structure.layers[0];
    let (n_g, n_l) = (lc.modes, lc.local_modes);
    let length = cfg.structure.length;
    let rho_a = rail.rho_a;
    let global = ModalBasis::new(length, rho_a, n_g);
    let all = ModalBasis::new(length, rho_a, n_g + n_l);
    let (gm, gk) = (
        ModalBasis::gram(&global, &all, false),
        ModalBasis::gram(&global, &all, true),
    );
    let ncol = all.n_dofs();
    let on_rail = |name: &String| name == &lc.name;
    let attached: Vec<_> = cfg
        .structure
        .couplings
        .iter()
        .filter(|c| on_rail(&c.upper) || (c.lower != GROUND && on_rail(&c.lower)))
        .collect();
    // Each local mode stands on the rail's own springs: without them nothing holds the rail
    // and the correction would stand in for a support that is not there.
    if !attached.iter().any(|c| c.stiffness > 0.0) {
        return Err(VtbError::config(
            "structure.couplings",
            format!("no spring attached to {:?}", lc.name),
            "the hybrid method's local modes are the top layer on its own springs (fasteners): \
             attach it with a coupling of positive stiffness, or use method \"modal\" or \"fem\"",
        ));
    }
    // The cubic functions g1..g4 at every discrete spring of the rail.
    let mut gvals = vec![0.0; global.n_dofs()];
    let g_at: Vec<Vec<[f64; 4]>> = attached
        .iter()
        .map(|cp| {
            cp.positions
                .iter()
                .map(|&x| {
                    global.eval_into(x, &mut gvals);
                    [gvals[0], gvals[1], gvals[2], gvals[3]]
                })
                .collect()
        })
        .collect();
    let mut out = Vec::with_capacity(n_l);
    for n in n_g + 1..=n_g + n_l {
        let col = |g: usize, gram: &[f64]| gram[g * ncol + 3 + n];
        let mass = 1.0;
        let bending = rail.ei * all.wavenumber(n).powi(4) / rho_a;
        let m: [f64; 4] = std::array::from_fn(|g| rho_a * col(g, &gm));
        let kb: [f64; 4] = std::array::from_fn(|g| rail.ei * col(g, &gk));
        let mut k = kb;
        let mut c: [f64; 4] = std::array::from_fn(|g| rail.alpha * m[g] + rail.beta * kb[g]);
        let (mut k_s, mut c_s) = (0.0, 0.0);
        for (cp, gs) in attached.iter().zip(&g_at) {
            match cp.kind {
                CouplingKind::Discrete => {
                    for (&x, gv) in cp.positions.iter().zip(gs) {
                        let s = all.scale * (n as f64 * PI * x / length).sin();
                        k_s += cp.stiffness * s * s;
                        c_s += cp.damping * s * s;
                        for g in 0..4 {
                            k[g] += cp.stiffness * gv[g] * s;
                            c[g] += cp.damping * gv[g] * s;
                        }
                    }
                }
                CouplingKind::Continuous => {
                    // k·∫s_j² = k/ρA for mass-normalised sines; k·∫g·s_j = k·M_gj/ρA.
                    k_s += cp.stiffness / rho_a;
                    c_s += cp.damping / rho_a;
                    for g in 0..4 {
                        k[g] += cp.stiffness * m[g] / rho_a;
                        c[g] += cp.damping * m[g] / rho_a;
                    }
                }
            }
        }
        let stiffness = bending + k_s;
        let damping = rail.alpha * mass + rail.beta * bending + c_s;
        let omega = (stiffness / mass).sqrt();
        if !(omega.is_finite() && omega > 0.0) {
            return Err(VtbError::Solver(format!(
                "local rail mode {n} has no positive finite frequency"
            )));
        }
        out.push(ModeCoupling {
            mode: LocalMode {
                index: n,
                frequency: omega / (2.0 * PI),
                omega,
                mass,
                stiffness,
                damping,
                loss_factor: damping / (mass * omega),
                class: ModeClass::Above,
            },
            m,
            k,
            c,
        });
    }
    Ok(out)
}

/// The representative excitation frequency ω_r (rad/s): `discretisation.omega_r`, else the
/// geometric centre 2π·v/√(λ_min·λ_max) of the band the irregularity excites at the run's
/// speed (`discretisation.excitation_wavelengths`), else the geometric centre of the local
/// modes' frequency range (docs/fesea.md).
pub fn representative_omega(cfg: &Config, locals: &[ModeCoupling]) -> f64 {
    let d = &cfg.discretisation;
    let excited = d.excitation_wavelengths.and_then(|[lo, hi]| {
        let w = 2.0 * std::f64::consts::PI * cfg.speed / (lo * hi).sqrt();
        (w.is_finite() && w > 0.0).then_some(w)
    });
    d.omega_r.or(excited).unwrap_or_else(|| {
        let (lo, hi) = locals.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), l| {
            (lo.min(l.mode.omega), hi.max(l.mode.omega))
        });
        (lo * hi).sqrt()
    })
}

/// The corrections summed over the local modes while [`FeSea::new`] visits them (the fields
/// of `FeSea` of the same names).
#[derive(Default)]
struct Sums {
    delta_m: [[f64; 4]; 4],
    delta_k: [[f64; 4]; 4],
    delta_c: [[f64; 4]; 4],
    exact: [[[f64; 4]; 4]; 3],
    above_k: [[f64; 4]; 4],
    above: Vec<usize>,
    shape_terms: Vec<(usize, [f64; 4])>,
    terms_a: Vec<(usize, [f64; 4])>,
    terms_b: Vec<(usize, [f64; 4])>,
}

impl Sums {
    /// `Mass` coupling of a classified local mode: adds its ΔM (below B) or ΔC (in B) and
    /// returns its load coefficients (a_j, b_j).
    fn mass_coupled(&mut self, l: &ModeCoupling, omega_r: f64, width: f64) -> ([f64; 4], [f64; 4]) {
        let mm = l.mode.mass;
        let mg = &l.m;
        match l.mode.class {
            ModeClass::Below => {
                add(&mut self.delta_m, outer(mg, mg, -1.0 / mm));
                (mg.map(|v| -v / mm), [0.0; 4])
            }
            ModeClass::Resonant => {
                let kappa = 0.5 * PI / width;
                add(
                    &mut self.delta_c,
                    outer(mg, mg, kappa * omega_r * omega_r / mm),
                );
                ([0.0; 4], mg.map(|v| -kappa * v / mm))
            }
            ModeClass::Above => ([0.0; 4], [0.0; 4]),
        }
    }

    /// `Full` coupling of a classified local mode: adds the exact part (the change g → g̃) and
    /// the residual resonator's ΔK and ΔM (outside B) or ΔC (in B), and returns its load
    /// coefficients (a_j, b_j).
    fn full_coupled(&mut self, l: &ModeCoupling, omega_r: f64, width: f64) -> ([f64; 4], [f64; 4]) {
        let md = &l.mode;
        let (mm, kk, cc, wj) = (md.mass, md.stiffness, md.damping, md.omega);
        // Only the cubic residuals g3, g4 are split. The end functions g1, g2
        // carry the rail's rigid motion with the track; their local content is
        // the sine tail of a linear function, and removing it (or condensing it
        // at ω_r on springs whose other end is blocked) ties that motion to the
        // ground (docs/fesea.md, "End functions").
        let split = |v: &[f64; 4]| [0.0, 0.0, v[2], v[3]];
        let (mg, kg, cg) = (&split(&l.m), &split(&l.k), &split(&l.c));
        // The exact part: g → g̃ = g − (M_gj/m_j)·s_j.
        add(&mut self.exact[0], outer(mg, mg, -1.0 / mm));
        let [_, ek, ec] = &mut self.exact;
        for (delta, xg, xj) in [(ek, kg, kk), (ec, cg, cc)] {
            add(delta, outer(xg, mg, -1.0 / mm));
            add(delta, outer(mg, xg, -1.0 / mm));
            add(delta, outer(mg, mg, xj / (mm * mm)));
        }
        self.shape_terms.push((md.index, mg.map(|v| -v / mm)));
        // The residual resonator, coupled through the stiffness of g̃.
        let c: [f64; 4] = std::array::from_fn(|g| kg[g] - wj * wj * mg[g]);
        if md.class == ModeClass::Resonant {
            let s = 0.5 * PI / (mm * wj * omega_r * width);
            add(&mut self.delta_c, outer(&c, &c, s));
            ([0.0; 4], c.map(|v| s * v))
        } else {
            // −c·cᵀ/(k_j − ω²m_j) at ω_r: below B a positive stiffness; above B
            // written as −c·cᵀ/k_j (static condensation) plus the positive mass
            // c·cᵀ·m_j/(k_j(k_j − ω_r²m_j)), exact at ω = 0 and at ω_r and keeping
            // K + ΔK and M + ΔM positive semi-definite.
            let d = kk - omega_r * omega_r * mm;
            if md.class == ModeClass::Below {
                add(&mut self.delta_k, outer(&c, &c, -1.0 / d));
            } else {
                add(&mut self.delta_k, outer(&c, &c, -1.0 / kk));
                add(&mut self.above_k, outer(&c, &c, -1.0 / kk));
                self.above.push(md.index);
                add(&mut self.delta_m, outer(&c, &c, mm / (kk * d)));
            }
            (c.map(|v| -v / d), [0.0; 4])
        }
    }
}

impl FeSea {
    /// The correction of the top layer `rail` for a validated hybrid config.
    pub fn new(cfg: &Config, rail: &Layer) -> Result<Self> {
        let mut locals = local_modes(cfg, rail)?;
        let coupling = cfg.discretisation.fesea_coupling;
        let omega_r = representative_omega(cfg, &locals);
        let band = (
            omega_r * 2f64.powf(-BAND_HALF_OCTAVES),
            omega_r * 2f64.powf(BAND_HALF_OCTAVES),
        );
        let width = band.1 - band.0;
        let mut sums = Sums::default();
        for l in &mut locals {
            l.mode.class = ModeClass::of(l.mode.omega, band);
            let (a, b) = match coupling {
                FeSeaCoupling::Mass => sums.mass_coupled(l, omega_r, width),
                FeSeaCoupling::Full => sums.full_coupled(l, omega_r, width),
            };
            if a.iter().any(|v| *v != 0.0) {
                sums.terms_a.push((l.mode.index, a));
            }
            if b.iter().any(|v| *v != 0.0) {
                sums.terms_b.push((l.mode.index, b));
            }
        }
        for (delta, e) in [&mut sums.delta_m, &mut sums.delta_k, &mut sums.delta_c]
            .into_iter()
            .zip(sums.exact)
        {
            add(delta, e);
        }
        let length = cfg.structure.length;
        Ok(Self {
            coupling,
            omega_r,
            band,
            modes: locals.into_iter().map(|l| l.mode).collect(),
            dofs: std::array::from_fn(|g| rail.offset + g),
            delta_m: sums.delta_m,
            delta_k: sums.delta_k,
            delta_c: sums.delta_c,
            exact: sums.exact,
            above_k: sums.above_k,
            above: sums.above,
            shape_terms: sums.shape_terms,
            terms_a: sums.terms_a,
            terms_b: sums.terms_b,
            length,
            scale: (2.0 / (rail.rho_a * length)).sqrt(),
        })
    }

    /// (j, t_j) with g̃ = g + Σ_j t_j·s_j (`Full` coupling; empty for the article's reading).
    pub fn shape_terms(&self) -> &[(usize, [f64; 4])] {
        &self.shape_terms
    }

    /// Adds g̃(x) − g(x) to the cubic entries (the first four values) of a rail shape vector:
    /// `Full` coupling only, the article's reading keeps g.
    pub fn correct_shape(&self, x: f64, values: &mut [f64]) {
        if self.shape_terms.is_empty() {
            return;
        }
        let [d] = self.sum_at(&self.shape_terms, [x]);
        for g in 0..4 {
            values[g] += d[g];
        }
    }

    /// (a(x), b(x)) = Σ_j (a_j, b_j)·s_j(x): a load w(t) at x(t) on the rail adds
    /// w·a(x) + d/dt(w·b(x)) to the forces on g1..g4, beyond its load vector w·N(x).
    pub fn load_terms(&self, x: f64) -> ([f64; 4], [f64; 4]) {
        self.load_terms_at([x])[0]
    }

    /// `load_terms` at K points in one pass (independent sine recurrences side by side).
    pub fn load_terms_at<const K: usize>(&self, xs: [f64; K]) -> [([f64; 4], [f64; 4]); K] {
        let (a, b) = (
            self.sum_at(&self.terms_a, xs),
            self.sum_at(&self.terms_b, xs),
        );
        std::array::from_fn(|k| (a[k], b[k]))
    }

    /// Σ_j v_j·s_j(x) at K points; sin(nθ) by sin((n+1)θ) = 2cosθ·sin(nθ) − sin((n−1)θ)
    /// (terms are sorted by j).
    fn sum_at<const K: usize>(&self, terms: &[(usize, [f64; 4])], xs: [f64; K]) -> [[f64; 4]; K] {
        let mut out = [[0.0; 4]; K];
        let Some(&(first, _)) = terms.first() else {
            return out;
        };
        let th = xs.map(|x| PI * x / self.length);
        let two_c = th.map(|t| 2.0 * t.cos());
        let mut prev = th.map(|t| ((first - 1) as f64 * t).sin());
        let mut cur = th.map(|t| (first as f64 * t).sin());
        let mut n = first;
        for (j, v) in terms {
            while n < *j {
                for k in 0..K {
                    (prev[k], cur[k]) = (cur[k], two_c[k] * cur[k] - prev[k]);
                }
                n += 1;
            }
            for k in 0..K {
                let s = self.scale * cur[k];
                for g in 0..4 {
                    out[k][g] += v[g] * s;
                }
            }
        }
        // Off the rail (a wheel before x = 0 or beyond L) nothing acts.
        for (o, x) in out.iter_mut().zip(xs) {
            if !(0.0..=self.length).contains(&x) {
                *o = [0.0; 4];
            }
        }
        out
    }

    /// s_j(x) of every local mode, in `modes` order (consecutive sine indices).
    /// Zero off the rail.
    pub fn local_sines_into(&self, x: f64, out: &mut [f64]) {
        let Some(first) = self.modes.first().map(|m| m.index) else {
            return;
        };
        if !(0.0..=self.length).contains(&x) {
            out.iter_mut().take(self.modes.len()).for_each(|o| *o = 0.0);
            return;
        }
        let th = PI * x / self.length;
        let two_c = 2.0 * th.cos();
        let (mut prev, mut cur) = (((first - 1) as f64 * th).sin(), (first as f64 * th).sin());
        for o in out.iter_mut().take(self.modes.len()) {
            *o = self.scale * cur;
            (prev, cur) = (cur, two_c * cur - prev);
        }
    }

    /// Number of local modes in the resonant band over its width (modes per rad/s).
    pub fn modal_density(&self) -> f64 {
        let n = self
            .modes
            .iter()
            .filter(|m| m.class == ModeClass::Resonant)
            .count();
        n as f64 / (self.band.1 - self.band.0)
    }
}

#[cfg(test)]
mod tests;
