//! Elimination orders for time stepping: AMD, the heavy (and the contact) unknowns moved
//! last, and slot-major versions of these; the cheapest by an estimate of one step's work.

use super::Ldlt;
use crate::error::Result;
use crate::linalg::sparse::CsrMatrix;

/// The order key of an unknown: (heavy, late, its component's size, its rank in the component,
/// the component).
type GroupKey = (bool, bool, usize, usize, usize);

impl Ldlt {
    /// Factorises with the cheapest of a few orderings for time stepping: AMD; AMD with the
    /// high-degree unknowns moved to the end; the same with `late` (the unknowns contact
    /// forces act on) also moved late; and slot-major versions of these (see `slot_major`).
    /// The cost estimate (`stepping_cost`) is deterministic, so the choice is reproducible.
    pub fn for_stepping(a: &CsrMatrix, late: &[usize]) -> Result<Self> {
        let n = a.n;
        let amd = Self::new(a)?;
        let degree: Vec<usize> = (0..n).map(|i| a.row_ptr[i + 1] - a.row_ptr[i]).collect();
        let mut sorted = degree.clone();
        sorted.sort_unstable();
        let median = sorted[n / 2];
        let mut is_late = vec![false; n];
        for &i in late {
            is_late[i] = true;
        }
        let moved = |keep_last: &dyn Fn(usize) -> bool| -> Vec<usize> {
            let mut o: Vec<usize> = amd
                .perm
                .iter()
                .copied()
                .filter(|&i| !keep_last(i))
                .collect();
            o.extend(amd.perm.iter().copied().filter(|&i| keep_last(i)));
            o
        };
        let mut best = amd.clone();
        let mut best_cost = best.stepping_cost(late);
        // "Heavy" at two levels: only the very dense rows, or every row well above the median
        // (e.g. girder sines coupled to each other by the piers).
        for factor in [8, 2] {
            let heavy: Vec<bool> = degree
                .iter()
                .map(|&d| d > (factor * median).max(32))
                .collect();
            for cand in [moved(&|i| heavy[i]), moved(&|i| heavy[i] || is_late[i])] {
                for order in [cand.clone(), slot_major(a, &cand, &heavy, &is_late)] {
                    if let Ok(f) = Self::with_ordering(a, Some(&order)) {
                        let c = f.stepping_cost(late);
                        if c < best_cost {
                            best = f;
                            best_cost = c;
                        }
                    }
                }
            }
        }
        Ok(best)
    }

    /// Estimated work of one step: a forward and a backward substitution of one vector plus
    /// the forward substitution of four port vectors from the first `late` unknown on:
    /// interior entries cost 2, interior columns 4, border runs 8 plus their entries.
    fn stepping_cost(&self, late: &[usize]) -> usize {
        let start = late.iter().map(|&i| self.inv[i]).min().unwrap_or(self.n);
        let seg_cost = |from: usize| -> usize {
            2 * (self.l.len() - self.col_ptr[from.min(self.p)] as usize)
                + 4 * (self.p - from.min(self.p))
        };
        let border: usize =
            self.brun.iter().map(|&(_, l, _)| l + 8).sum::<usize>() + (self.n - self.p).pow(2) / 2;
        let ports: usize = self
            .brun
            .iter()
            .filter(|r| r.0 + r.1 > start)
            .map(|&(s, l, _)| 8 + (s + l - s.max(start)))
            .sum();
        2 * (seg_cost(0) + border) + 4 * (seg_cost(start) + ports)
    }
}

/// Reorders `order` so that, after the heavy unknowns are removed, the disjoint components
/// of the rest (per-mode chains of a modal basis) are laid out slot by slot: the first
/// unknown of every component, then the second, …, with the `late` ones after all others.
/// Each component keeps its internal order, so the fill of the factor is unchanged while the
/// heavy rows of L become a few long runs.
fn slot_major(a: &CsrMatrix, order: &[usize], heavy: &[bool], late: &[bool]) -> Vec<usize> {
    let n = a.n;
    let mut comp = vec![usize::MAX; n];
    let mut ncomp = 0;
    for s in 0..n {
        if heavy[s] || comp[s] != usize::MAX {
            continue;
        }
        let mut stack = vec![s];
        comp[s] = ncomp;
        while let Some(i) = stack.pop() {
            for p in a.row_ptr[i]..a.row_ptr[i + 1] {
                let j = a.col_idx[p];
                if !heavy[j] && comp[j] == usize::MAX {
                    comp[j] = ncomp;
                    stack.push(j);
                }
            }
        }
        ncomp += 1;
    }
    let mut size = vec![0usize; ncomp];
    for i in 0..n {
        if !heavy[i] {
            size[comp[i]] += 1;
        }
    }
    let mut rank_in = vec![0usize; ncomp];
    // Components of equal size share their offset pattern, so they are grouped.
    let mut keyed: Vec<(GroupKey, usize)> = order
        .iter()
        .map(|&i| {
            if heavy[i] {
                ((true, false, 0, 0, 0), i)
            } else {
                let c = comp[i];
                let r = rank_in[c];
                rank_in[c] += 1;
                ((false, late[i], size[c], r, c), i)
            }
        })
        .collect();
    // Stable: heavy unknowns keep their relative order at the end.
    keyed.sort_by_key(|e| e.0);
    keyed.into_iter().map(|e| e.1).collect()
}
