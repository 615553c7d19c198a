//! A finite-element structure in substructured coordinates (fixed-interface component mode
//! synthesis, docs/substructures.md): u = T·q, q = each substructure's fixed-interface modal
//! amplitudes and the DOFs on the cuts between substructures, numbered along the track.
//!
//! The reduction is computed by the Python layer (`vtb.analysis.substructures`: the cuts, the
//! interiors' modes Φ and constraint modes Ψ, each distinct interior once) and handed in with
//! the reduced M, C, K of the layers (the dampers are stamped here, on T's shapes, so a batch
//! of damper designs shares one reduction). This module maps the layers' shape vectors to
//! reduced ones: row i of T is Φ_g(r)|Ψ_g(r) over its substructure's columns for an interior
//! DOF (row r of group g), the unit vector of its column for a DOF on a cut. A substructure's
//! columns (the DOFs on the cut before it, its modes, the DOFs on the cut after it) are
//! contiguous, so a load inside one element is a contiguous reduced shape.

use crate::error::{Result, VtbError};
use crate::linalg::sparse::{Assembler, CsrMatrix};
use crate::model::basis::Shape;

/// Where a layer DOF sits in T.
#[derive(Clone, Copy, Debug)]
enum Row {
    /// Row `row` of piece `piece`'s group.
    Interior { piece: u32, row: u32 },
    /// The DOF is reduced column `col` itself.
    Interface { col: u32 },
}

/// One substructure: its group, its modes' first column, its interface columns, and the
/// range of columns its rows touch.
#[derive(Clone, Debug)]
struct Piece {
    group: usize,
    modes: usize,
    bound: Vec<usize>,
    lo: usize,
    hi: usize,
}

/// A distinct interior's reduction: Φ (rows × `n_modes`) and Ψ (rows × `n_bound`), row-major.
#[derive(Clone, Debug)]
struct Group {
    n_modes: usize,
    n_bound: usize,
    phi: Vec<f64>,
    psi: Vec<f64>,
    /// The truncated modes' receptance moments R₀ (m/N), R₁ (m·s/N), R₂ (m·s²/N) between rows
    /// r and r + d at `[(k·rows + r)·(band + 1) + d]`.
    residual: Vec<f64>,
}

/// The substructured coordinates of a structure's layers and their reduced matrices.
#[derive(Clone, Debug)]
pub struct Substructured {
    rows: Vec<Row>,
    pieces: Vec<Piece>,
    groups: Vec<Group>,
    /// Reduced DOFs (the layers'; the dampers' nodes come after them).
    pub n: usize,
    /// TᵀMT, TᵀCT, TᵀKT of the layers (no dampers).
    pub m: CsrMatrix,
    pub c: CsrMatrix,
    pub k: CsrMatrix,
    /// The widest reduced shape of one substructure (its column range).
    pub widest: usize,
    /// The residual's band (rows).
    band: usize,
}

fn refuse(field: &str, value: impl std::fmt::Display, why: impl Into<String>) -> VtbError {
    VtbError::config(format!("substructures.{field}"), value, why.into())
}

/// The parts of a [`Substructured`] as the Python layer hands them in.
pub struct Parts {
    /// Per layer DOF: its piece (−1 on a cut) and its row in the piece's group (its reduced
    /// column on a cut).
    pub dof_piece: Vec<i64>,
    pub dof_index: Vec<i64>,
    /// Per piece: its group, its modes' first column, its interface columns
    /// (`bound[bound_ptr[p]..bound_ptr[p + 1]]`).
    pub piece_group: Vec<usize>,
    pub piece_modes: Vec<usize>,
    pub bound_ptr: Vec<usize>,
    pub bound: Vec<usize>,
    /// Per group: rows, modes, interface DOFs and Φ, Ψ one group after another (row-major).
    pub group_rows: Vec<usize>,
    pub group_modes: Vec<usize>,
    pub group_bound: Vec<usize>,
    pub phi: Vec<f64>,
    pub psi: Vec<f64>,
    /// Reduced DOFs, and M, C, K as COO triplets (both triangles; duplicates summed).
    pub n: usize,
    pub matrices: [(Vec<usize>, Vec<usize>, Vec<f64>); 3],
    /// Per group, 3 × rows × (`residual_band` + 1): the moments R₀, R₁, R₂ of its truncated
    /// modes' receptance between rows r and r + d (m/N, m·s/N, m·s²/N; R₀ the static
    /// flexibility they hold), one group after another.
    pub residual: Vec<f64>,
    pub residual_band: usize,
}

impl Substructured {
    /// Checks every index and value (finite, in range, consistent sizes).
    pub fn new(p: Parts) -> Result<Self> {
        let n = p.n;
        let n_groups = p.group_rows.len();
        if p.group_modes.len() != n_groups || p.group_bound.len() != n_groups {
            return Err(refuse(
                "groups",
                n_groups,
                "rows, modes and bound need one entry per group",
            ));
        }
        let groups = Self::groups(&p)?;
        let pieces = Self::pieces(&p, &groups)?;
        let rows = Self::rows(&p, &pieces)?;
        let [m, c, k] = Self::matrices(&p)?;
        let widest = pieces.iter().map(|p| p.hi + 1 - p.lo).max().unwrap_or(1);
        Ok(Self {
            rows,
            pieces,
            groups,
            n,
            m,
            c,
            k,
            widest,
            band: p.residual_band,
        })
    }

    fn groups(p: &Parts) -> Result<Vec<Group>> {
        let n_groups = p.group_rows.len();
        let (mut at_phi, mut at_psi, mut at_res) = (0, 0, 0);
        let bw = p.residual_band + 1;
        let mut groups = Vec::with_capacity(n_groups);
        for g in 0..n_groups {
            let (r, m, b) = (p.group_rows[g], p.group_modes[g], p.group_bound[g]);
            let (lp, ls) = (r * m, r * b);
            if at_phi + lp > p.phi.len() || at_psi + ls > p.psi.len() {
                return Err(refuse(
                    &format!("groups[{g}]"),
                    r,
                    "Φ or Ψ is shorter than its rows × columns",
                ));
            }
            let lr = 3 * r * bw;
            if at_res + lr > p.residual.len() {
                return Err(refuse(
                    &format!("groups[{g}].residual"),
                    p.residual.len(),
                    "is shorter than its 3 moments × rows × band",
                ));
            }
            let phi = p.phi[at_phi..at_phi + lp].to_vec();
            let psi = p.psi[at_psi..at_psi + ls].to_vec();
            let residual = p.residual[at_res..at_res + lr].to_vec();
            if let Some(i) = phi
                .iter()
                .chain(&psi)
                .chain(&residual)
                .position(|v| !v.is_finite())
            {
                return Err(refuse(
                    &format!("groups[{g}]"),
                    i,
                    "holds a non-finite value",
                ));
            }
            (at_phi, at_psi, at_res) = (at_phi + lp, at_psi + ls, at_res + lr);
            groups.push(Group {
                n_modes: m,
                n_bound: b,
                phi,
                psi,
                residual,
            });
        }
        if at_phi != p.phi.len() || at_psi != p.psi.len() || at_res != p.residual.len() {
            return Err(refuse("phi", p.phi.len(), "has entries beyond its groups'"));
        }
        Ok(groups)
    }

    fn pieces(p: &Parts, groups: &[Group]) -> Result<Vec<Piece>> {
        let (n, n_groups) = (p.n, groups.len());
        let n_pieces = p.piece_group.len();
        if p.piece_modes.len() != n_pieces || p.bound_ptr.len() != n_pieces + 1 {
            return Err(refuse(
                "pieces",
                n_pieces,
                "modes and bound_ptr need one entry per piece",
            ));
        }
        let mut pieces = Vec::with_capacity(n_pieces);
        for i in 0..n_pieces {
            let g = p.piece_group[i];
            let (a, b) = (p.bound_ptr[i], p.bound_ptr[i + 1]);
            if g >= n_groups || a > b || b > p.bound.len() {
                return Err(refuse(
                    &format!("pieces[{i}]"),
                    g,
                    "names no group or bound range",
                ));
            }
            let bound = p.bound[a..b].to_vec();
            let grp = &groups[g];
            if bound.len() != grp.n_bound {
                return Err(refuse(
                    &format!("pieces[{i}].bound"),
                    bound.len(),
                    format!("its group has {} interface columns", grp.n_bound),
                ));
            }
            let modes = p.piece_modes[i];
            let lo = bound.iter().copied().chain([modes]).min().unwrap_or(modes);
            let hi = bound
                .iter()
                .copied()
                .chain([modes + grp.n_modes.max(1) - 1])
                .max()
                .unwrap_or(modes);
            if hi >= n {
                return Err(refuse(
                    &format!("pieces[{i}]"),
                    hi,
                    format!("reaches past the {n} reduced DOFs"),
                ));
            }
            pieces.push(Piece {
                group: g,
                modes,
                bound,
                lo,
                hi,
            });
        }
        Ok(pieces)
    }

    fn rows(p: &Parts, pieces: &[Piece]) -> Result<Vec<Row>> {
        let (n, n_pieces) = (p.n, pieces.len());
        if p.dof_piece.len() != p.dof_index.len() {
            return Err(refuse(
                "dof_index",
                p.dof_index.len(),
                "needs one entry per layer DOF",
            ));
        }
        let mut rows = Vec::with_capacity(p.dof_piece.len());
        for (i, (&pc, &ix)) in p.dof_piece.iter().zip(&p.dof_index).enumerate() {
            let row = match usize::try_from(pc) {
                Ok(pc)
                    if pc < n_pieces
                        && ix >= 0
                        && (ix as usize) < p.group_rows[pieces[pc].group] =>
                {
                    Row::Interior {
                        piece: pc as u32,
                        row: ix as u32,
                    }
                }
                Err(_) if pc == -1 && ix >= 0 && (ix as usize) < n => {
                    Row::Interface { col: ix as u32 }
                }
                _ => {
                    return Err(refuse(
                        &format!("dof[{i}]"),
                        format!("({pc}, {ix})"),
                        "names no piece row or reduced column",
                    ));
                }
            };
            rows.push(row);
        }
        Ok(rows)
    }

    fn matrices(p: &Parts) -> Result<[CsrMatrix; 3]> {
        let n = p.n;
        let mut out = [(); 3].map(|_| CsrMatrix::zeros(0));
        for (k, ((r, c, v), name)) in p.matrices.iter().zip(["m", "c", "k"]).enumerate() {
            if r.len() != v.len() || c.len() != v.len() {
                return Err(refuse(
                    name,
                    v.len(),
                    "rows, columns and values differ in length",
                ));
            }
            let mut asm = Assembler::new(n);
            for ((&i, &j), &x) in r.iter().zip(c).zip(v) {
                if i >= n || j >= n || !x.is_finite() {
                    return Err(refuse(
                        name,
                        format!("({i}, {j}) = {x}"),
                        format!("must be finite, within {n} DOFs"),
                    ));
                }
                asm.add(i, j, x);
            }
            out[k] = asm.finish();
        }
        Ok(out)
    }

    /// Layer DOFs this maps (the rows of T).
    pub fn layer_dofs(&self) -> usize {
        self.rows.len()
    }

    /// sᵀ·R_k·s for a layer shape s, k = 0, 1, 2: the moments of the truncated interior modes'
    /// receptance under the load s (zero on the cuts, between pieces and beyond the stored
    /// band); sᵀR₀s is the static flexibility they hold.
    pub fn residual_moments(&self, start: usize, values: &[f64]) -> [f64; 3] {
        let bw = self.band + 1;
        let mut sum = [0.0; 3];
        for (a, &va) in values.iter().enumerate() {
            let Row::Interior { piece: pa, row: ra } = self.rows[start + a] else {
                continue;
            };
            for (b, &vb) in values.iter().enumerate() {
                let Row::Interior { piece: pb, row: rb } = self.rows[start + b] else {
                    continue;
                };
                let (lo, hi) = (ra.min(rb) as usize, ra.max(rb) as usize);
                if pa == pb && hi - lo <= self.band {
                    let g = &self.groups[self.pieces[pa as usize].group];
                    let block = g.residual.len() / 3;
                    for (k, s) in sum.iter_mut().enumerate() {
                        *s += va * vb * g.residual[k * block + lo * bw + hi - lo];
                    }
                }
            }
        }
        sum
    }

    /// `out` = Tᵀ·s for a layer shape s (`values` from DOF `start`): a contiguous reduced shape.
    pub fn reduce_shape(&self, start: usize, values: &[f64], out: &mut Shape) {
        let (mut lo, mut hi) = (usize::MAX, 0);
        for (k, &v) in values.iter().enumerate() {
            if v == 0.0 {
                continue;
            }
            let (a, b) = match self.rows[start + k] {
                Row::Interior { piece, .. } => {
                    let p = &self.pieces[piece as usize];
                    (p.lo, p.hi)
                }
                Row::Interface { col } => (col as usize, col as usize),
            };
            (lo, hi) = (lo.min(a), hi.max(b));
        }
        out.values.clear();
        if lo > hi {
            out.start = 0;
            return;
        }
        out.start = lo;
        out.values.resize(hi + 1 - lo, 0.0);
        for (k, &v) in values.iter().enumerate() {
            if v == 0.0 {
                continue;
            }
            match self.rows[start + k] {
                Row::Interior { piece, row } => {
                    let p = &self.pieces[piece as usize];
                    let g = &self.groups[p.group];
                    let r = row as usize;
                    let phi = &g.phi[r * g.n_modes..(r + 1) * g.n_modes];
                    for (o, f) in out.values[p.modes - lo..p.modes - lo + g.n_modes]
                        .iter_mut()
                        .zip(phi)
                    {
                        *o += v * f;
                    }
                    for (&col, s) in p
                        .bound
                        .iter()
                        .zip(&g.psi[r * g.n_bound..(r + 1) * g.n_bound])
                    {
                        out.values[col - lo] += v * s;
                    }
                }
                Row::Interface { col } => out.values[col as usize - lo] += v,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two pieces of one group (2 interior rows, 1 mode, 1 interface DOF each) around one cut:
    /// reduced DOFs [mode₀, cut, mode₁]; layer DOFs [interior 0 r0, r1, cut, interior 1 r0, r1].
    fn two_pieces() -> Substructured {
        let eye = |n: usize| -> (Vec<usize>, Vec<usize>, Vec<f64>) {
            ((0..n).collect(), (0..n).collect(), vec![1.0; n])
        };
        Substructured::new(Parts {
            dof_piece: vec![0, 0, -1, 1, 1],
            dof_index: vec![0, 1, 1, 0, 1],
            piece_group: vec![0, 0],
            piece_modes: vec![0, 2],
            bound_ptr: vec![0, 1, 2],
            bound: vec![1, 1],
            group_rows: vec![2],
            group_modes: vec![1],
            group_bound: vec![1],
            phi: vec![0.5, 0.25],
            psi: vec![0.75, 0.125],
            n: 3,
            matrices: [eye(3), eye(3), eye(3)],
            // R₀ between rows 0 and 0, 0 and 1, 1 and 1: 3, 1, 2 (band 1); R₁ = −R₀/10;
            // R₂ = R₀/100.
            residual: vec![
                3.0, 1.0, 2.0, 0.0, -0.3, -0.1, -0.2, 0.0, 0.03, 0.01, 0.02, 0.0,
            ],
            residual_band: 1,
        })
        .unwrap()
    }

    #[test]
    fn a_layer_shape_maps_to_the_rows_of_t_over_its_pieces_columns() {
        let s = two_pieces();
        let mut out = Shape::default();
        // 2·(row 1 of piece 0) + 1·(the cut): [2·0.25, 2·0.125 + 1] on columns 0, 1.
        s.reduce_shape(1, &[2.0, 1.0], &mut out);
        assert_eq!(
            (out.start, out.values.as_slice()),
            (0, [0.5, 1.25].as_slice())
        );
        // row 0 of piece 1: its mode is column 2, its interface column 1.
        s.reduce_shape(3, &[1.0], &mut out);
        assert_eq!(
            (out.start, out.values.as_slice()),
            (1, [0.75, 0.5].as_slice())
        );
    }

    #[test]
    fn the_residual_is_the_quadratic_form_of_rows_of_one_piece() {
        let s = two_pieces();
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-12);
        // [1, 2] on piece 0's rows 0, 1: 3 + 2·2·1 + 4·2 = 15; the cut adds nothing.
        let r = s.residual_moments(0, &[1.0, 2.0, 5.0]);
        assert!(close(r, [15.0, -1.5, 0.15]), "{r:?}");
        // rows of two pieces do not couple: piece 0 row 1 and piece 1 row 0 → 2 + 3
        let r = s.residual_moments(1, &[1.0, 0.0, 1.0]);
        assert!(close(r, [5.0, -0.5, 0.05]), "{r:?}");
    }

    #[test]
    fn bad_parts_name_their_field() {
        let good = || Parts {
            dof_piece: vec![0, -1],
            dof_index: vec![0, 1],
            piece_group: vec![0],
            piece_modes: vec![0],
            bound_ptr: vec![0, 1],
            bound: vec![1],
            group_rows: vec![1],
            group_modes: vec![1],
            group_bound: vec![1],
            phi: vec![1.0],
            psi: vec![0.5],
            n: 2,
            matrices: [
                (vec![0], vec![0], vec![1.0]),
                (vec![], vec![], vec![]),
                (vec![1], vec![1], vec![1.0]),
            ],
            residual: vec![0.5, -0.05, 0.005],
            residual_band: 0,
        };
        assert!(Substructured::new(good()).is_ok());
        let mut p = good();
        p.phi[0] = f64::NAN;
        assert!(
            Substructured::new(p)
                .unwrap_err()
                .to_string()
                .contains("substructures.groups[0]")
        );
        let mut p = good();
        p.dof_index[1] = 7;
        assert!(
            Substructured::new(p)
                .unwrap_err()
                .to_string()
                .contains("substructures.dof[1]")
        );
        let mut p = good();
        p.matrices[2].0[0] = 5;
        assert!(
            Substructured::new(p)
                .unwrap_err()
                .to_string()
                .contains("substructures.k")
        );
        let mut p = good();
        p.bound = vec![4];
        assert!(
            Substructured::new(p)
                .unwrap_err()
                .to_string()
                .contains("substructures.pieces[0]")
        );
    }
}
