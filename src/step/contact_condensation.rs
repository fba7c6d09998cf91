//! The step matrix condensed onto Γ_C's tangential unknowns through the layers of bulk unknowns
//! next to Γ_C, on the pattern of A's own Γ_C rows: the operator the predicted bounds' sweep
//! relaxes the contact nodes with (`solver.condensed_layers`, [`super::newton_krylov`]).
//!
//! **What it approximates.** With T the Γ_C tangential velocities (the system's last rows) and
//! B every other unknown, eliminating B from A x = b leaves the condensed operator
//! S = A_TT − A_TB A_BB⁻¹ A_BT on T: how Γ_C's tractions answer a change of its velocities once
//! the body has followed. A sweep over A's Γ_C rows with the rest of x frozen sees only A_TT:
//! the load a node sheds when it weakens reaches its neighbours through the shared Γ_C rows,
//! but not through the body, which the next linear solve moves. S is dense; what the sweep
//! needs is its near field, so
//!
//! ```text
//! S_L = A_TT − A_TR A_RR⁻¹ A_RT     on the pattern of A_TT,
//! ```
//!
//! R the bulk unknowns within `layers` hops of Γ_C in A's graph (the body beyond is held), and
//! A_RR⁻¹ itself replaced by [`LAYER_SWEEPS`] symmetric Gauss–Seidel sweeps from zero: a local
//! inverse, which is all the near field needs. Each entry is probed: Γ_C's unknowns are
//! coloured so that no row of the pattern reads two of one colour (a distance-2 colouring: 18
//! colours on the 3D example's structured Γ_C), the sweeps run on A_RT times each colour's
//! indicator vector (all colours at once), and each row's entry at a column of a colour is the
//! row's product with that colour's vector (probing: Chan and Mathew, Acta Numerica 1994). What
//! a probe folds into an entry from the colour's other columns is the coupling of unknowns at
//! least two nodes apart: small, and the sweeps' local inverse makes it smaller.
//!
//! Cost: one pass over the Γ_C rows and the layers' rows per sweep and colour, once per step
//! size: 55 110 layer unknowns (2.3 M entries) and 18 colours at 972k unknowns.
//!
//! **Measured** (the 3D example, release; Newton iterations, each a Krylov solve), first with
//! the exact inverse (a sparse LU of A_BB or A_RR, dense S): on the slab 104 × 6 × 6 cells
//! (k = 1/64, 16 steps; the step where a front crosses the slab took 98 iterates with the sweep
//! over A's rows), the exact S with 1, 2, 4 and 8 symmetric sweeps over Γ_C: 96, 65, 39 and 23
//! iterates in that step; A's rows with 8 sweeps: 93. At 47k unknowns and k = 1/8 (8 steps),
//! 8 sweeps: A's rows 228 Newton iterations, S with A_BB's diagonal alone 199, S_L by LU with
//! 1, 2, 4 and 8 layers 134, 105, 101 and 99, S exact 99; S_2 kept on the Γ_C nodes within one
//! mesh spacing 105: two layers on A's own Γ_C pattern carry what matters, the near field
//! through the body. Probed on that pattern with the LU: 19 iterates in the slab's step, 114
//! Newton iterations at 47k and k = 1/8; with the sweeps instead of the LU, 19 and 103 (the LU
//! took 1 GB more at 972k unknowns: its fill on the layers; the sweeps take the probes' 8 MB).
//!
//! Depends on: [`crate::la`] (the error type).

use crate::la::{CsrMatrix, FactorStage, LaError};

/// Symmetric Gauss–Seidel sweeps that stand for A_RR⁻¹ in the probes (module header): 1 gave 166
/// Newton iterations at 47k unknowns and k = 1/8 (8 steps, 8 sweeps over Γ_C), 3 gave 103, 10
/// gave 115 (the sparse LU's solution path, another of the steps' solutions from step 2 on).
const LAYER_SWEEPS: usize = 3;

/// S_L (module header) of the system whose row r is `row(r)` (columns and values of A, the
/// system's order, `n` unknowns, Γ_C's tangential unknowns from `first` on), through the bulk
/// unknowns within `layers` hops of Γ_C (0: A_TT itself): rows and columns are Γ_C's tangential
/// unknowns, numbered from `first`.
pub(super) fn condense<'r>(
    row: impl Fn(usize) -> (&'r [u32], &'r [f64]),
    n: usize,
    first: usize,
    layers: usize,
) -> Result<CsrMatrix, LaError> {
    let nt = n - first;
    let layer = bulk_layers(&row, n, first, layers);
    let mut local = vec![usize::MAX; first];
    layer.iter().enumerate().for_each(|(l, &r)| local[r] = l);
    let pattern: Vec<Vec<usize>> = (first..n)
        .map(|r| {
            let mut cols: Vec<usize> = (row(r).0.iter())
                .map(|&c| c as usize)
                .filter(|&c| c >= first)
                .map(|c| c - first)
                .collect();
            cols.sort_unstable();
            cols
        })
        .collect();
    let colour = distance_two_colouring(&pattern, nt);
    let colours = colour.iter().copied().max().map_or(0, |c| c + 1);

    // A_RR by rows (the layer's numbering), and A_RT times each colour's indicator vector:
    // the probes, row-major (row l's colours side by side).
    let nr = layer.len();
    let (mut rr_ptr, mut rr_cols, mut rr_values) = (vec![0], Vec::<u32>::new(), Vec::new());
    let mut rhs = vec![0.0; nr * colours];
    for (l, &r) in layer.iter().enumerate() {
        let (row_cols, row_values) = row(r);
        for (&c, &v) in row_cols.iter().zip(row_values) {
            let c = c as usize;
            if c >= first {
                rhs[l * colours + colour[c - first]] += v;
            } else if local[c] != usize::MAX {
                rr_cols.push(local[c] as u32);
                rr_values.push(v);
            }
        }
        rr_ptr.push(rr_cols.len());
    }
    let a_rr = CsrMatrix::from_rows(nr, rr_ptr, rr_cols, rr_values);
    let probes = gauss_seidel(&a_rr, &rhs, colours)?;

    // Row i of S_L times colour c's indicator: A_TT's part at that colour minus A_TR y_c.
    let (mut ptr, mut cols, mut values) = (Vec::with_capacity(nt + 1), Vec::new(), Vec::new());
    ptr.push(0);
    let mut product = vec![0.0; colours];
    for (i, own) in pattern.iter().enumerate() {
        product.iter_mut().for_each(|p| *p = 0.0);
        let (row_cols, row_values) = row(first + i);
        for (&c, &v) in row_cols.iter().zip(row_values) {
            let c = c as usize;
            if c >= first {
                product[colour[c - first]] += v;
            } else if local[c] != usize::MAX {
                let y = &probes[local[c] * colours..(local[c] + 1) * colours];
                product.iter_mut().zip(y).for_each(|(p, y)| *p -= v * y);
            }
        }
        for &j in own {
            cols.push(j as u32);
            values.push(product[colour[j]]);
        }
        ptr.push(cols.len());
    }
    Ok(CsrMatrix::from_rows(nt, ptr, cols, values))
}

/// Symmetric Gauss–Seidel sweeps on A_RR y = rhs for the probes' columns at once
/// ([`LAYER_SWEEPS`] from y = 0), `width` columns side by side.
fn gauss_seidel(a_rr: &CsrMatrix, rhs: &[f64], width: usize) -> Result<Vec<f64>, LaError> {
    let n = a_rr.n();
    let mut y = vec![0.0; n * width];
    let mut sum = vec![0.0; width];
    let diagonal: Vec<f64> = (0..n).map(|l| a_rr.diagonal(l)).collect();
    for (l, d) in diagonal.iter().enumerate() {
        if !(d.is_finite() && *d != 0.0) {
            return Err(LaError::Factorization {
                stage: FactorStage::CondensedLayers,
                detail: format!("row {l} of the {n} bulk rows next to Γ_C has the diagonal {d}"),
            });
        }
    }
    for _ in 0..LAYER_SWEEPS {
        for l in (0..n).chain((0..n).rev()) {
            sum.copy_from_slice(&rhs[l * width..(l + 1) * width]);
            let (cols, values) = a_rr.row(l);
            for (&c, &value) in cols.iter().zip(values) {
                let c = c as usize;
                if c != l {
                    let yc = &y[c * width..(c + 1) * width];
                    sum.iter_mut().zip(yc).for_each(|(s, y)| *s -= value * y);
                }
            }
            let d = diagonal[l];
            y[l * width..(l + 1) * width]
                .iter_mut()
                .zip(&sum)
                .for_each(|(y, s)| *y = s / d);
        }
    }
    Ok(y)
}

/// The bulk unknowns (rows below `first`) within `layers` hops of Γ_C's in the rows' graph,
/// ascending.
fn bulk_layers<'r>(
    row: &impl Fn(usize) -> (&'r [u32], &'r [f64]),
    n: usize,
    first: usize,
    layers: usize,
) -> Vec<usize> {
    let mut inside = vec![false; first];
    let mut frontier: Vec<usize> = (first..n).collect();
    for _ in 0..layers {
        let mut next = Vec::new();
        for &r in &frontier {
            for &c in row(r).0 {
                let c = c as usize;
                if c < first && !inside[c] {
                    inside[c] = true;
                    next.push(c);
                }
            }
        }
        frontier = next;
    }
    (0..first).filter(|&r| inside[r]).collect()
}

/// Colours of the columns 0..n such that no row of `pattern` holds two columns of one colour:
/// greedy, in column order.
fn distance_two_colouring(pattern: &[Vec<usize>], n: usize) -> Vec<usize> {
    // The rows that hold each column.
    let mut holders: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, cols) in pattern.iter().enumerate() {
        cols.iter().for_each(|&j| holders[j].push(i));
    }
    let mut colour = vec![usize::MAX; n];
    let mut taken: Vec<usize> = Vec::new();
    for j in 0..n {
        taken.clear();
        for &i in &holders[j] {
            taken.extend(
                pattern[i]
                    .iter()
                    .map(|&other| colour[other])
                    .filter(|&c| c != usize::MAX),
            );
        }
        taken.sort_unstable();
        taken.dedup();
        colour[j] = taken
            .iter()
            .enumerate()
            .find(|&(k, &c)| k != c)
            .map_or(taken.len(), |(k, _)| k);
    }
    colour
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small system in CSR rows (dense rows, zeros dropped).
    fn rows(dense: &[Vec<f64>]) -> Vec<(Vec<u32>, Vec<f64>)> {
        (dense.iter())
            .map(|r| {
                let entries: Vec<(u32, f64)> = (r.iter().enumerate())
                    .filter(|(_, v)| **v != 0.0)
                    .map(|(c, &v)| (c as u32, v))
                    .collect();
                entries.into_iter().unzip()
            })
            .collect()
    }

    /// Four Γ_C unknowns in a chain (rows 3–6) and three bulk unknowns (rows 0–2), each bulk
    /// unknown coupled to two neighbouring Γ_C unknowns and to nothing else in the bulk: S is
    /// then tridiagonal, on A_TT's pattern, and the probes (and the sweeps, A_BB being diagonal) give it exactly: S_ij = A_ij −
    /// Σ_b A_ib A_bj / A_bb.
    #[test]
    fn probes_give_the_schur_complement_where_it_lies_on_the_pattern() {
        let n = 7;
        let mut a = vec![vec![0.0; n]; n];
        for b in 0..3 {
            a[b][b] = 4.0 + b as f64;
            a[b][3 + b] = -1.0;
            a[b][4 + b] = -0.5;
            a[3 + b][b] = -1.5;
            a[4 + b][b] = -0.25;
        }
        for t in 3..7 {
            a[t][t] = 10.0;
            if t > 3 {
                a[t][t - 1] = -2.0;
            }
            if t < 6 {
                a[t][t + 1] = -3.0;
            }
        }
        let stored = rows(&a);
        let s = condense(|r| (&stored[r].0[..], &stored[r].1[..]), n, 3, 1).unwrap();
        for i in 0..4 {
            let (cols, values) = s.row(i);
            assert_eq!(cols.len(), if i == 0 || i == 3 { 2 } else { 3 });
            for (&j, &value) in cols.iter().zip(values) {
                let (ti, tj) = (3 + i, 3 + j as usize);
                let exact = a[ti][tj] - (0..3).map(|b| a[ti][b] * a[b][tj] / a[b][b]).sum::<f64>();
                assert!((value - exact).abs() < 1e-12, "S[{i}][{j}] = {value}, exact {exact}");
            }
        }
    }

    /// No layers: A_TT itself.
    #[test]
    fn without_layers_it_is_a_tt() {
        let a = vec![vec![2.0, -1.0, 0.0], vec![-1.0, 3.0, -1.0], vec![0.0, -1.0, 4.0]];
        let stored = rows(&a);
        let s = condense(|r| (&stored[r].0[..], &stored[r].1[..]), 3, 1, 0).unwrap();
        assert_eq!(s.row(0), (&[0u32, 1][..], &[3.0, -1.0][..]));
        assert_eq!(s.row(1), (&[0u32, 1][..], &[-1.0, 4.0][..]));
    }

    /// A row never holds two columns of one colour.
    #[test]
    fn a_row_holds_each_colour_once() {
        let pattern: Vec<Vec<usize>> = (0..20usize)
            .map(|i| (i.saturating_sub(2)..(i + 3).min(20)).collect())
            .collect();
        let colour = distance_two_colouring(&pattern, 20);
        for cols in &pattern {
            let mut seen: Vec<usize> = cols.iter().map(|&j| colour[j]).collect();
            seen.sort_unstable();
            let before = seen.len();
            seen.dedup();
            assert_eq!(
                seen.len(),
                before,
                "{cols:?}: {:?}",
                cols.iter().map(|&j| colour[j]).collect::<Vec<_>>()
            );
        }
        assert!(
            *colour.iter().max().unwrap() < 5,
            "five colours at most on a band of half-width 2"
        );
    }
}
