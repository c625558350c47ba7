//! Sparse symmetric linear solves with faer: the pattern is analysed once
//! (fill-reducing ordering, elimination tree), each Newton matrix is only
//! refactored numerically into buffers allocated once. Cholesky first (the
//! dynamic iteration matrix is positive definite unless compressed
//! membranes buckle); LDLT on the same structure when Cholesky meets a
//! negative pivot; pivoting LU as the last resort (statics past a limit
//! point, or an LDLT whose solution fails its residual check).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::prelude::*;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering, factorize_symbolic_cholesky, supernodal,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use nalgebra::DMatrix;
// Phase times are CPU time, read where phase timing is on (phase_timer).
use crate::solver::phase_timer::PhaseTimer;

/// Why the sparse solver could not analyse, factor or solve.
#[derive(Clone, Debug, PartialEq)]
pub enum LinearError {
    /// The fill-reducing ordering failed.
    Ordering(super::ordering::OrderingError),
    /// faer's symbolic analysis failed (`what`: Cholesky or LU).
    Symbolic {
        /// Which factorization.
        what: &'static str,
        /// faer's error.
        detail: String,
    },
    /// The matrix has entries that are not finite.
    NonFiniteMatrix,
    /// No factorization (Cholesky, LDLT or LU) succeeded.
    Singular(String),
    /// A low-rank part of the wrong size.
    LowRankSize {
        /// Values of `U`.
        values: usize,
        /// Unknowns of the matrix.
        unknowns: usize,
        /// Rank of the part.
        rank: usize,
    },
    /// The low-rank part makes the matrix singular.
    LowRankSingular,
    /// A solve produced values that are not finite.
    NonFiniteSolution,
    /// A solve before any factorization.
    NotFactored,
}

impl std::fmt::Display for LinearError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinearError::Ordering(e) => write!(f, "{e}"),
            LinearError::Symbolic { what, detail } => {
                write!(f, "symbolic {what} failed: {detail}")
            }
            LinearError::NonFiniteMatrix => write!(f, "matrix has non-finite entries"),
            LinearError::Singular(detail) => write!(f, "matrix is singular: {detail}"),
            LinearError::LowRankSize {
                values,
                unknowns,
                rank,
            } => write!(
                f,
                "low-rank part: U has {values} values for {unknowns} unknowns and rank {rank}"
            ),
            LinearError::LowRankSingular => write!(f, "low-rank part makes the matrix singular"),
            LinearError::NonFiniteSolution => write!(f, "linear solve produced non-finite values"),
            LinearError::NotFactored => write!(f, "no factorization"),
        }
    }
}

impl std::error::Error for LinearError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LinearError::Ordering(e) => Some(e),
            _ => None,
        }
    }
}
use std::time::Duration;

/// A dense low-rank part of a matrix that its sparse pattern cannot hold:
/// the matrix is `A - U S^-1 U^T`, `A` sparse, `U` (n x rank, column-major)
/// and the small symmetric `S` (rank x rank) dense. Mass damping's
/// rigid-body projection is one (its `U` couples every DOF).
#[derive(Clone, Debug, PartialEq)]
pub struct LowRank {
    /// `U`, column-major, `n * rank` values.
    pub u: Vec<f64>,
    /// `S`, invertible.
    pub s: DMatrix<f64>,
}

impl LowRank {
    /// Number of columns of `U`.
    pub fn rank(&self) -> usize {
        self.s.nrows()
    }

    /// Both parts side by side: `[U1 U2]` with the block-diagonal inner
    /// matrix (the sum of the two low-rank parts).
    pub fn join(self, other: LowRank) -> LowRank {
        let (r1, r2) = (self.rank(), other.rank());
        let mut s = DMatrix::zeros(r1 + r2, r1 + r2);
        s.view_mut((0, 0), (r1, r1)).copy_from(&self.s);
        s.view_mut((r1, r1), (r2, r2)).copy_from(&other.s);
        let mut u = self.u;
        u.extend(other.u);
        LowRank { u, s }
    }
}

/// Largest rank of a low-rank part solved in one blocked solve (the six
/// rigid-body modes); higher ranks are solved a column at a time.
const LOW_RANK_MAX: usize = 6;

/// The Woodbury form of a factored `A - U S^-1 U^T`:
/// `x = A^-1 b + Z (S - U^T Z)^-1 U^T A^-1 b` with `Z = A^-1 U`.
struct Woodbury {
    u: Vec<f64>,
    z: Vec<f64>,
    capacitance: nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
}

/// Which factorization the last [`SparseSolver::factor`] produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorKind {
    /// Cholesky `L L^T`.
    Llt,
    /// `L D L^T` without pivoting (indefinite but strongly factorable).
    Ldlt,
    /// Pivoting LU.
    Lu,
}

/// Counts and time spent, for benchmarks.
#[derive(Clone, Copy, Debug, Default)]
pub struct SolverStats {
    /// Numeric factorizations by kind: Cholesky, LDLT, LU.
    pub llt: usize,
    /// LDLT factorizations.
    pub ldlt: usize,
    /// LU factorizations.
    pub lu: usize,
    /// Triangular solves.
    pub solves: usize,
    /// Time in numeric factorization.
    pub factor_time: Duration,
    /// Time in solves.
    pub solve_time: Duration,
}

/// Systems from this many unknowns on are ordered on their block graph
/// (see [`SparseSolver::new_blocked`]).
pub const BLOCK_ORDERING_MIN: usize = 100_000;

/// Systems from this many unknowns on whose blocks' positions are known
/// are ordered by nested dissection, below it by AMD: where the two cross
/// over on Miura-ori sheets (`cargo bench --bench ordering`).
pub const NESTED_DISSECTION_MIN: usize = 2_000;

/// How a pattern's fill-reducing ordering is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ordering<'a> {
    /// faer's AMD on the scalar graph.
    Amd,
    /// AMD on the graph of `block x block` blocks, expanded to scalars.
    BlockAmd(usize),
    /// Nested dissection by planes on the graph of `block x block` blocks
    /// ([`super::ordering`]).
    BlockNestedDissection {
        /// Scalars per block.
        block: usize,
        /// Where each block is (a slot's vertex in the reference sheet).
        coords: &'a [[f64; 3]],
    },
}

/// The graph of a block-structured pattern's blocks (`block` consecutive
/// scalars per block, which share their pattern), as CSR adjacency
/// without self loops.
fn block_graph(pattern: &SymbolicSparseColMat<usize>, block: usize) -> (Vec<usize>, Vec<usize>) {
    let nb = pattern.nrows() / block;
    let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
    let mut xadj = Vec::with_capacity(nb + 1);
    xadj.push(0usize);
    let mut adj = Vec::new();
    for j in 0..nb {
        let c = j * block;
        let mut last = usize::MAX;
        for &r in &ri[cp[c]..cp[c + 1]] {
            let b = r / block;
            if b != last && b != j {
                adj.push(b);
            }
            last = b;
        }
        xadj.push(adj.len());
    }
    (xadj, adj)
}

/// A fill-reducing ordering of a block-structured pattern, computed on the
/// graph of its blocks and expanded to scalars (`block` consecutive
/// scalars per block, kept together and in order): `(fwd, inv)`.
fn block_ordering(
    pattern: &SymbolicSparseColMat<usize>,
    block: usize,
    nested: Option<&[[f64; 3]]>,
) -> Result<(Vec<usize>, Vec<usize>), LinearError> {
    let n = pattern.nrows();
    let nb = n / block;
    let (xadj, adj) = block_graph(pattern, block);
    let fwd: Vec<usize> = match nested {
        Some(coords) => super::ordering::nested_dissection(
            &super::ordering::Graph {
                xadj: &xadj,
                adj: &adj,
            },
            coords,
        )
        .map_err(LinearError::Ordering)?,
        None => {
            // AMD wants the diagonal too.
            let mut bcol = Vec::with_capacity(nb + 1);
            let mut brow = Vec::with_capacity(adj.len() + nb);
            bcol.push(0);
            for j in 0..nb {
                brow.push(j);
                brow.extend_from_slice(&adj[xadj[j]..xadj[j + 1]]);
                bcol.push(brow.len());
            }
            super::ordering::amd(nb, bcol, brow).map_err(LinearError::Ordering)?
        }
    };
    let sfwd: Vec<usize> = fwd
        .iter()
        .flat_map(|&b| (0..block).map(move |k| b * block + k))
        .collect();
    let mut sinv = vec![0usize; n];
    for (i, &p) in sfwd.iter().enumerate() {
        sinv[p] = i;
    }
    Ok((sfwd, sinv))
}

/// A fixed sparsity pattern (full symmetric storage, sorted rows) with its
/// symbolic factorizations and the latest numeric factorization.
pub struct SparseSolver {
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    /// Values of the Cholesky or LDLT factor.
    l_values: Vec<f64>,
    /// Copy of the factored matrix (to check LDLT solutions).
    a_values: Vec<f64>,
    mem: MemBuffer,
    sym_lu: Option<SymbolicLu<usize>>,
    lu: Option<Lu<usize, f64>>,
    kind: Option<FactorKind>,
    work: Vec<f64>,
    residual: Vec<f64>,
    stats: SolverStats,
    /// The low-rank part of the matrix in force, if any.
    low_rank: Option<Woodbury>,
    /// The matrix's lower triangle in the fill-reducing order, gathered
    /// from its values for the supernodal factorization (so faer need not
    /// permute it at every factorization).
    permuted: Option<PermutedLower>,
}

/// The pattern of `P A P^T`'s lower triangle (rows unsorted within a
/// column), where each of its values comes from in `A`'s, and a buffer.
struct PermutedLower {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Index into `A`'s values of each entry.
    src: Vec<usize>,
    values: Vec<f64>,
}

impl PermutedLower {
    /// From the full pattern `a` and the inverse permutation (new index of
    /// each old one): every entry with `old_i >= old_j` goes to
    /// `(max(new_i, new_j), min(new_i, new_j))`, as faer's own
    /// `permute_self_adjoint_to_unsorted` places it.
    fn new(a: &SymbolicSparseColMat<usize>, perm_inv: &[usize]) -> PermutedLower {
        let n = a.ncols();
        let (cp, ri) = (a.col_ptr(), a.row_idx());
        let mut counts = vec![0usize; n + 1];
        for j in 0..n {
            for &i in &ri[cp[j]..cp[j + 1]] {
                if i >= j {
                    counts[perm_inv[i].min(perm_inv[j]) + 1] += 1;
                }
            }
        }
        for c in 0..n {
            counts[c + 1] += counts[c];
        }
        let col_ptr = counts.clone();
        let nnz = col_ptr[n];
        let mut next = counts;
        let (mut row_idx, mut src) = (vec![0; nnz], vec![0; nnz]);
        for j in 0..n {
            for (p, &i) in ri[cp[j]..cp[j + 1]].iter().enumerate() {
                if i >= j {
                    let (a, b) = (perm_inv[i], perm_inv[j]);
                    let c = a.min(b);
                    row_idx[next[c]] = a.max(b);
                    src[next[c]] = cp[j] + p;
                    next[c] += 1;
                }
            }
        }
        PermutedLower {
            col_ptr,
            row_idx,
            src,
            values: vec![0.0; nnz],
        }
    }
}

impl SparseSolver {
    /// Analyse the pattern given as CSC column pointers and sorted row
    /// indices (both triangles present).
    pub fn new(n: usize, col_ptr: Vec<usize>, row_idx: Vec<usize>) -> Result<Self, LinearError> {
        Self::new_blocked(n, col_ptr, row_idx, 1, None)
    }

    /// [`SparseSolver::new`] for a pattern made of dense `block x block`
    /// blocks (scalars `block i .. block i + block - 1` share their
    /// pattern, as the 3 coordinates of a slot do), at `coords` if known.
    /// From [`NESTED_DISSECTION_MIN`] unknowns on with positions, nested
    /// dissection orders the block graph; from [`BLOCK_ORDERING_MIN`] on
    /// without, AMD orders the block graph (`block^2` times fewer entries,
    /// the same quality at a fraction of the time and memory) and expands
    /// it. Smaller systems keep AMD on the scalars.
    pub fn new_blocked(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        block: usize,
        coords: Option<&[[f64; 3]]>,
    ) -> Result<Self, LinearError> {
        let blocked = block > 1 && n.is_multiple_of(block);
        let ordering = match coords {
            Some(coords) if blocked && n >= NESTED_DISSECTION_MIN => {
                Ordering::BlockNestedDissection { block, coords }
            }
            _ if blocked && n >= BLOCK_ORDERING_MIN => Ordering::BlockAmd(block),
            _ => Ordering::Amd,
        };
        Self::with_ordering(n, col_ptr, row_idx, ordering)
    }

    /// [`SparseSolver::new`] with the fill-reducing ordering chosen.
    pub fn with_ordering(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
        ordering: Ordering,
    ) -> Result<Self, LinearError> {
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let perm = match ordering {
            Ordering::Amd => None,
            Ordering::BlockAmd(b) => Some(block_ordering(&pattern, b, None)?),
            Ordering::BlockNestedDissection { block, coords } => {
                Some(block_ordering(&pattern, block, Some(coords))?)
            }
        };
        let ordering = match &perm {
            Some((fwd, inv)) => {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(fwd, inv, n))
            }
            None => SymmetricOrdering::Amd,
        };
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            ordering,
            CholeskySymbolicParams {
                // Supernodal at every size: faer's automatic choice takes
                // the simplicial factorization for small systems, which is
                // slower on our small sheets (docs/performance.md).
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| LinearError::Symbolic {
            what: "Cholesky",
            detail: format!("{e:?}"),
        })?;
        let mem = MemBuffer::new(StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(LOW_RANK_MAX, Par::Seq),
        ]));
        let permuted = match (symbolic.raw(), symbolic.perm()) {
            (SymbolicCholeskyRaw::Supernodal(_), Some(p)) => {
                let (_, inv) = p.arrays();
                Some(PermutedLower::new(&pattern, inv))
            }
            _ => None,
        };
        Ok(SparseSolver {
            permuted,
            l_values: vec![0.0; symbolic.len_val()],
            a_values: Vec::new(),
            pattern,
            symbolic,
            mem,
            sym_lu: None,
            lu: None,
            kind: None,
            work: vec![0.0; n],
            residual: vec![0.0; n],
            stats: SolverStats::default(),
            low_rank: None,
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

    /// Kind of the factorization in force, if any.
    pub fn kind(&self) -> Option<FactorKind> {
        self.kind
    }

    /// Entries of the Cholesky factor and the factorization's
    /// multiply-adds (`sum_j c_j^2` over the factor's column counts).
    pub fn factor_size(&self) -> (usize, f64) {
        let flops = match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sn) => {
                let (b, e) = (sn.supernode_begin(), sn.supernode_end());
                let cp = sn.col_ptr_for_row_idx();
                (0..sn.n_supernodes())
                    .map(|s| {
                        let r = (cp[s + 1] - cp[s]) as f64;
                        (1..=e[s] - b[s])
                            .map(|i| (i as f64 + r).powi(2))
                            .sum::<f64>()
                    })
                    .sum()
            }
            SymbolicCholeskyRaw::Simplicial(sp) => {
                let cp = sp.col_ptr();
                (0..sp.ncols())
                    .map(|j| ((cp[j + 1] - cp[j]) as f64).powi(2))
                    .sum()
            }
        };
        (self.symbolic.len_val(), flops)
    }

    /// Counts and times so far.
    pub fn stats(&self) -> SolverStats {
        self.stats
    }

    /// Continue the counts of a solver this one replaces (same system, a
    /// grown pattern), so that totals stay totals.
    pub fn carry_stats(&mut self, from: SolverStats) {
        self.stats = from;
    }

    /// Factor the matrix with these values (in pattern order). Any
    /// low-rank part of the previous matrix is dropped.
    pub fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
        let start = PhaseTimer::start();
        self.low_rank = None;
        let r = self.factor_inner(values);
        self.stats.factor_time += start.elapsed();
        r
    }

    /// Make the factored matrix `A` into `A - U S^-1 U^T` for the solves
    /// that follow (until the next [`SparseSolver::factor`]): `rank` more
    /// solves now, and per solve two products with `U` and `A^-1 U` and a
    /// `rank x rank` solve. Errors if nothing is factored, `U` has the
    /// wrong size, or the sum is singular.
    pub fn set_low_rank(&mut self, lr: LowRank) -> Result<(), LinearError> {
        let start = PhaseTimer::start();
        let r = self.set_low_rank_inner(lr);
        self.stats.factor_time += start.elapsed();
        r
    }

    fn set_low_rank_inner(&mut self, lr: LowRank) -> Result<(), LinearError> {
        self.low_rank = None;
        let n = self.pattern.nrows();
        let rank = lr.rank();
        if lr.u.len() != n * rank || lr.s.ncols() != rank {
            return Err(LinearError::LowRankSize {
                values: lr.u.len(),
                unknowns: n,
                rank,
            });
        }
        if rank == 0 {
            return Ok(());
        }
        let mut z = lr.u.clone();
        if self.kind == Some(FactorKind::Llt) && rank <= LOW_RANK_MAX {
            // All columns in one blocked solve.
            let f = LltRef::new(&self.symbolic, &self.l_values);
            let x = MatMut::from_column_major_slice_mut(&mut z, n, rank);
            f.solve_in_place_with_conj(Conj::No, x, Par::Seq, MemStack::new(&mut self.mem));
            if z.iter().any(|v| !v.is_finite()) {
                return Err(LinearError::NonFiniteSolution);
            }
        } else {
            for col in z.chunks_mut(n) {
                self.solve_inner(col)?;
            }
        }
        // The capacitance matrix S - U^T A^-1 U (symmetrised: both factors
        // of U^T Z are the same up to round-off).
        let mut c = lr.s;
        for i in 0..rank {
            for j in 0..rank {
                let ui = &lr.u[i * n..(i + 1) * n];
                let zj = &z[j * n..(j + 1) * n];
                let uz: f64 = ui.iter().zip(zj).map(|(a, b)| a * b).sum();
                c[(i, j)] -= uz;
            }
        }
        let c = (&c + c.transpose()) * 0.5;
        let capacitance = c.lu();
        if !capacitance.is_invertible() {
            return Err(LinearError::LowRankSingular);
        }
        self.low_rank = Some(Woodbury {
            u: lr.u,
            z,
            capacitance,
        });
        Ok(())
    }

    fn factor_inner(&mut self, values: &[f64]) -> Result<(), LinearError> {
        self.kind = None;
        if values.iter().any(|v| !v.is_finite()) {
            return Err(LinearError::NonFiniteMatrix);
        }
        // Not positive definite by the one route: LDLT next.
        let mut llt_failed = false;
        if let (Some(pl), SymbolicCholeskyRaw::Supernodal(sn)) =
            (self.permuted.as_mut(), self.symbolic.raw())
        {
            for (v, &k) in pl.values.iter_mut().zip(&pl.src) {
                *v = values[k];
            }
            let n = self.pattern.nrows();
            let sym =
                SymbolicSparseColMatRef::new_unsorted_checked(n, n, &pl.col_ptr, None, &pl.row_idx);
            let lower = SparseColMatRef::new(sym, &pl.values);
            let stack = MemStack::new(&mut self.mem);
            let llt = supernodal::factorize_supernodal_numeric_llt(
                &mut self.l_values,
                lower,
                LltRegularization::default(),
                sn,
                Par::Seq,
                stack,
                Default::default(),
            );
            if llt.is_ok() {
                self.stats.llt += 1;
                self.kind = Some(FactorKind::Llt);
                return Ok(());
            }
            llt_failed = true;
        }
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        let llt_ok = !llt_failed && {
            let stack = MemStack::new(&mut self.mem);
            self.symbolic
                .factorize_numeric_llt(
                    &mut self.l_values,
                    a,
                    Side::Lower,
                    LltRegularization::default(),
                    Par::Seq,
                    stack,
                    Default::default(),
                )
                .is_ok()
        };
        if llt_ok {
            self.stats.llt += 1;
            self.kind = Some(FactorKind::Llt);
            return Ok(());
        }
        let stack = MemStack::new(&mut self.mem);
        let ldlt = self.symbolic.factorize_numeric_ldlt(
            &mut self.l_values,
            a,
            Side::Lower,
            LdltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        );
        if ldlt.is_ok() && self.l_values.iter().all(|x| x.is_finite()) {
            self.stats.ldlt += 1;
            self.a_values.clear();
            self.a_values.extend_from_slice(values);
            self.kind = Some(FactorKind::Ldlt);
            return Ok(());
        }
        self.factor_lu(values)
    }

    fn factor_lu(&mut self, values: &[f64]) -> Result<(), LinearError> {
        self.kind = None;
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        if self.sym_lu.is_none() {
            self.sym_lu = Some(SymbolicLu::try_new(self.pattern.as_ref()).map_err(|e| {
                LinearError::Symbolic {
                    what: "LU",
                    detail: format!("{e:?}"),
                }
            })?);
        }
        let sym = self.sym_lu.clone().expect("just set");
        match Lu::try_new_with_symbolic(sym, a) {
            Ok(f) => {
                self.stats.lu += 1;
                self.lu = Some(f);
                self.kind = Some(FactorKind::Lu);
                Ok(())
            }
            Err(e) => Err(LinearError::Singular(format!("{e:?}"))),
        }
    }

    /// Solve with the latest factorization, overwriting `rhs` with the
    /// solution. Errors if nothing is factored or the result is not finite.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), LinearError> {
        let start = PhaseTimer::start();
        let r = self
            .solve_inner(rhs)
            .and_then(|()| self.apply_low_rank(rhs));
        self.stats.solves += 1;
        self.stats.solve_time += start.elapsed();
        r
    }

    fn solve_inner(&mut self, rhs: &mut [f64]) -> Result<(), LinearError> {
        let n = rhs.len();
        match self.kind {
            None => return Err(LinearError::NotFactored),
            Some(FactorKind::Llt) => {
                let f = LltRef::new(&self.symbolic, &self.l_values);
                let x = MatMut::from_column_major_slice_mut(rhs, n, 1);
                f.solve_in_place_with_conj(Conj::No, x, Par::Seq, MemStack::new(&mut self.mem));
            }
            Some(FactorKind::Ldlt) => {
                self.work.clear();
                self.work.extend_from_slice(rhs);
                let f = LdltRef::new(&self.symbolic, &self.l_values);
                let x = MatMut::from_column_major_slice_mut(rhs, n, 1);
                f.solve_in_place_with_conj(Conj::No, x, Par::Seq, MemStack::new(&mut self.mem));
                // No pivoting: accept the solution only if its residual is small.
                if self.relative_residual(rhs) > 1e-8 {
                    let a = std::mem::take(&mut self.a_values);
                    let r = self.factor_lu(&a);
                    self.a_values = a;
                    r?;
                    rhs.copy_from_slice(&self.work);
                    return self.solve_inner(rhs);
                }
            }
            Some(FactorKind::Lu) => {
                let f = self.lu.as_ref().expect("LU in force");
                let x = MatMut::from_column_major_slice_mut(rhs, n, 1);
                f.solve_in_place(x);
            }
        }
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err(LinearError::NonFiniteSolution);
        }
        Ok(())
    }

    /// `x += Z C^-1 U^T x` (with `x = A^-1 b` on entry): the solution with
    /// the low-rank part in force, if any.
    fn apply_low_rank(&self, x: &mut [f64]) -> Result<(), LinearError> {
        let Some(w) = &self.low_rank else {
            return Ok(());
        };
        let n = x.len();
        let rank = w.capacitance.l().nrows();
        let ux = DMatrix::from_fn(rank, 1, |i, _| {
            w.u[i * n..(i + 1) * n]
                .iter()
                .zip(x.iter())
                .map(|(a, b)| a * b)
                .sum::<f64>()
        });
        let y = w
            .capacitance
            .solve(&ux)
            .ok_or(LinearError::LowRankSingular)?;
        for (j, zj) in w.z.chunks(n).enumerate() {
            let yj = y[j];
            for (xi, zi) in x.iter_mut().zip(zj) {
                *xi += yj * zi;
            }
        }
        if x.iter().any(|v| !v.is_finite()) {
            return Err(LinearError::NonFiniteSolution);
        }
        Ok(())
    }

    /// `|A x - b| / |b|` with `b` in `work` and `A` in `a_values`.
    fn relative_residual(&mut self, x: &[f64]) -> f64 {
        let cp = self.pattern.col_ptr();
        let ri = self.pattern.row_idx();
        let r = &mut self.residual;
        r.clear();
        r.extend(self.work.iter().map(|b| -b));
        for j in 0..x.len() {
            for k in cp[j]..cp[j + 1] {
                r[ri[k]] += self.a_values[k] * x[j];
            }
        }
        let nb = self.work.iter().map(|b| b * b).sum::<f64>().sqrt();
        let nr = r.iter().map(|b| b * b).sum::<f64>().sqrt();
        if nb > 0.0 { nr / nb } else { nr }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tridiagonal(n: usize) -> (Vec<usize>, Vec<usize>) {
        let mut col_ptr = vec![0];
        let mut rows = Vec::new();
        for j in 0..n {
            for i in j.saturating_sub(1)..(j + 2).min(n) {
                rows.push(i);
            }
            col_ptr.push(rows.len());
        }
        (col_ptr, rows)
    }

    fn check(s: &mut SparseSolver, col_ptr: &[usize], rows: &[usize], vals: &[f64]) {
        let n = col_ptr.len() - 1;
        s.factor(vals).unwrap();
        let x_true: Vec<f64> = (0..n).map(|i| i as f64 + 1.0).collect();
        let mut b = vec![0.0; n];
        for j in 0..n {
            for k in col_ptr[j]..col_ptr[j + 1] {
                b[rows[k]] += vals[k] * x_true[j];
            }
        }
        s.solve_in_place(&mut b).unwrap();
        for i in 0..n {
            assert!((b[i] - x_true[i]).abs() < 1e-10, "{:?}", s.kind());
        }
    }

    /// 1D Laplacian (SPD: Cholesky) and shifted to be indefinite (LDLT).
    #[test]
    fn solves_spd_and_indefinite() {
        let n: usize = 5;
        let (col_ptr, rows) = tridiagonal(n);
        let mut s = SparseSolver::new(n, col_ptr.clone(), rows.clone()).unwrap();
        for (shift, kind) in [(0.0, FactorKind::Llt), (-2.5, FactorKind::Ldlt)] {
            let mut vals = Vec::new();
            for j in 0..n {
                for i in j.saturating_sub(1)..(j + 2).min(n) {
                    vals.push(if i == j { 2.0 + shift } else { -1.0 });
                }
            }
            check(&mut s, &col_ptr, &rows, &vals);
            assert_eq!(s.kind(), Some(kind));
        }
    }

    /// A block grid Laplacian (3 scalars per grid point, coupled within a
    /// point) solved under every ordering, to the same solution. (Which
    /// ordering fills less is the bench's question: at this size AMD's
    /// factor is the smaller, 70k against 100k entries.)
    #[test]
    fn every_ordering_solves_a_block_grid() {
        let (m, b) = (24usize, 3usize);
        let nb = m * m;
        let n = nb * b;
        let mut coords = Vec::with_capacity(nb);
        let mut col_ptr = vec![0];
        let (mut rows, mut vals) = (Vec::new(), Vec::new());
        for p in 0..nb {
            let (i, j) = (p / m, p % m);
            coords.push([j as f64, i as f64, 0.0]);
            let mut nbrs = vec![p];
            if i > 0 {
                nbrs.push(p - m);
            }
            if j > 0 {
                nbrs.push(p - 1);
            }
            if j + 1 < m {
                nbrs.push(p + 1);
            }
            if i + 1 < m {
                nbrs.push(p + m);
            }
            nbrs.sort_unstable();
            for c in 0..b {
                for &q in &nbrs {
                    for r in 0..b {
                        rows.push(q * b + r);
                        vals.push(if q == p {
                            if r == c { 4.5 } else { 0.1 }
                        } else if r == c {
                            -1.0
                        } else {
                            0.0
                        });
                    }
                }
                col_ptr.push(rows.len());
            }
        }
        for ordering in [
            Ordering::Amd,
            Ordering::BlockAmd(b),
            Ordering::BlockNestedDissection {
                block: b,
                coords: &coords,
            },
        ] {
            let mut s =
                SparseSolver::with_ordering(n, col_ptr.clone(), rows.clone(), ordering).unwrap();
            check(&mut s, &col_ptr, &rows, &vals);
            assert_eq!(s.kind(), Some(FactorKind::Llt));
        }
    }

    /// A zero diagonal defeats factorization without pivoting: LU takes over.
    #[test]
    fn zero_pivot_falls_back_to_lu() {
        let n: usize = 4;
        let (col_ptr, rows) = tridiagonal(n);
        let mut s = SparseSolver::new(n, col_ptr.clone(), rows.clone()).unwrap();
        let mut vals = Vec::new();
        for j in 0..n {
            for i in j.saturating_sub(1)..(j + 2).min(n) {
                vals.push(if i == j { 0.0 } else { 1.0 });
            }
        }
        check(&mut s, &col_ptr, &rows, &vals);
        assert_eq!(s.kind(), Some(FactorKind::Lu));
        let stats = s.stats();
        assert_eq!((stats.llt, stats.lu), (0, 1));
    }

    /// `A - U S^-1 U^T` with a dense rank-2 part, against the dense
    /// matrix; a new factorization drops the part.
    #[test]
    fn low_rank_part_is_solved_exactly() {
        let n: usize = 6;
        let (col_ptr, rows) = tridiagonal(n);
        let mut s = SparseSolver::new(n, col_ptr.clone(), rows.clone()).unwrap();
        let mut vals = Vec::new();
        let mut dense = DMatrix::<f64>::zeros(n, n);
        for j in 0..n {
            for i in j.saturating_sub(1)..(j + 2).min(n) {
                let v = if i == j { 4.0 } else { -1.0 };
                vals.push(v);
                dense[(i, j)] = v;
            }
        }
        let u: Vec<f64> = (0..2 * n)
            .map(|k| ((k * 7 % 5) as f64 - 2.0) * 0.3)
            .collect();
        let small = DMatrix::from_row_slice(2, 2, &[3.0, 0.5, 0.5, 2.0]);
        let um = DMatrix::from_column_slice(n, 2, &u);
        let full = &dense - &um * small.clone().try_inverse().unwrap() * um.transpose();
        let x_true: Vec<f64> = (0..n).map(|i| (i as f64 - 2.5) * 0.7).collect();
        let xt = DMatrix::from_column_slice(n, 1, &x_true);
        let b = &full * &xt;
        s.factor(&vals).unwrap();
        s.set_low_rank(LowRank { u, s: small }).unwrap();
        let mut x = b.as_slice().to_vec();
        s.solve_in_place(&mut x).unwrap();
        for i in 0..n {
            assert!(
                (x[i] - x_true[i]).abs() < 1e-12,
                "{i}: {} {}",
                x[i],
                x_true[i]
            );
        }
        // Refactoring drops the low-rank part: A alone again.
        check(&mut s, &col_ptr, &rows, &vals);
        // A U of the wrong size is named.
        let err = s
            .set_low_rank(LowRank {
                u: vec![1.0; n],
                s: DMatrix::identity(2, 2),
            })
            .unwrap_err();
        assert_eq!(
            err,
            LinearError::LowRankSize {
                values: n,
                unknowns: n,
                rank: 2
            }
        );
        assert!(err.to_string().contains("low-rank"), "{err}");
    }
}
