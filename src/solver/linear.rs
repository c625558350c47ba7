//! Sparse symmetric linear solves with faer: the pattern is analysed once,
//! each Newton matrix is only refactored numerically. Cholesky first (the
//! dynamic iteration matrix is positive definite for small steps); LU when
//! Cholesky finds the matrix indefinite (statics past a limit point).

use faer::Side;
use faer::prelude::*;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

/// A fixed sparsity pattern (full symmetric storage, sorted rows) with its
/// symbolic factorizations and the latest numeric factorization.
pub struct SparseSolver {
    pattern: SymbolicSparseColMat<usize>,
    sym_llt: SymbolicLlt<usize>,
    sym_lu: Option<SymbolicLu<usize>>,
    factor: Option<Factor>,
}

enum Factor {
    Llt(Llt<usize, f64>),
    Lu(Lu<usize, f64>),
}

impl SparseSolver {
    /// Analyse the pattern given as CSC column pointers and sorted row
    /// indices (both triangles present).
    pub fn new(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Result<Self, String> {
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let sym_llt = SymbolicLlt::try_new(pattern.as_ref(), Side::Lower)
            .map_err(|e| format!("symbolic Cholesky failed: {e:?}"))?;
        Ok(SparseSolver {
            pattern,
            sym_llt,
            sym_lu: None,
            factor: None,
        })
    }

    /// The pattern (values are laid out in its order).
    pub fn pattern(&self) -> &SymbolicSparseColMat<usize> {
        &self.pattern
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.pattern.row_idx().len()
    }

    /// Factor the matrix with these values (in pattern order).
    pub fn factor(&mut self, values: &[f64]) -> Result<(), String> {
        if values.iter().any(|v| !v.is_finite()) {
            self.factor = None;
            return Err("matrix has non-finite entries".into());
        }
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        match Llt::try_new_with_symbolic(self.sym_llt.clone(), a, Side::Lower) {
            Ok(f) => {
                self.factor = Some(Factor::Llt(f));
                return Ok(());
            }
            Err(_) => {}
        }
        if self.sym_lu.is_none() {
            self.sym_lu = Some(
                SymbolicLu::try_new(self.pattern.as_ref())
                    .map_err(|e| format!("symbolic LU failed: {e:?}"))?,
            );
        }
        let sym = self.sym_lu.clone().expect("just set");
        match Lu::try_new_with_symbolic(sym, a) {
            Ok(f) => {
                self.factor = Some(Factor::Lu(f));
                Ok(())
            }
            Err(e) => {
                self.factor = None;
                Err(format!("matrix is singular: {e:?}"))
            }
        }
    }

    /// Solve with the latest factorization, overwriting `rhs` with the
    /// solution. Errors if nothing is factored or the result is not finite.
    pub fn solve_in_place(&self, rhs: &mut [f64]) -> Result<(), String> {
        let mut x = Col::<f64>::from_fn(rhs.len(), |i| rhs[i]);
        match &self.factor {
            Some(Factor::Llt(f)) => f.solve_in_place(x.as_mut()),
            Some(Factor::Lu(f)) => f.solve_in_place(x.as_mut()),
            None => return Err("no factorization".into()),
        }
        for (r, xi) in rhs.iter_mut().zip(x.iter()) {
            *r = *xi;
        }
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err("linear solve produced non-finite values".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1D Laplacian (SPD) and the same shifted to be indefinite (LU path).
    #[test]
    fn solves_spd_and_indefinite() {
        let n: usize = 5;
        let mut col_ptr = vec![0];
        let mut rows = Vec::new();
        for j in 0..n {
            for i in j.saturating_sub(1)..(j + 2).min(n) {
                rows.push(i);
            }
            col_ptr.push(rows.len());
        }
        let mut s = SparseSolver::new(n, col_ptr.clone(), rows.clone()).unwrap();
        for shift in [0.0, -2.5] {
            let mut vals = Vec::new();
            for j in 0..n {
                for i in j.saturating_sub(1)..(j + 2).min(n) {
                    vals.push(if i == j { 2.0 + shift } else { -1.0 });
                }
            }
            s.factor(&vals).unwrap();
            let x_true: Vec<f64> = (0..n).map(|i| i as f64 + 1.0).collect();
            let mut b = vec![0.0; n];
            for j in 0..n {
                for k in col_ptr[j]..col_ptr[j + 1] {
                    b[rows[k]] += vals[k] * x_true[j];
                }
            }
            s.solve_in_place(&mut b).unwrap();
            for i in 0..n {
                assert!((b[i] - x_true[i]).abs() < 1e-12);
            }
        }
    }
}
