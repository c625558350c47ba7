//! Sparse Cholesky of the implicit stepper's iteration matrix (Miura m x m
//! panels at the flat reference, a 2 ms step's mass and damping weights):
//! faer's automatic choice against forced simplicial and supernodal
//! factorizations, in one run. It is why `SparseSolver` forces supernodal.
//!
//! `cargo bench --bench factorization`

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::*;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Par, Side};
// Times are CPU time (this thread's clock; the benches run on one thread).
use origami_fmu::cpu_time::CpuInstant as Instant;

mod common;

fn main() {
    println!(
        "| panels | unknowns | nnz(A) | factorization | nnz(L) | CPU ms per numeric factorization |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for p in [4usize, 8, 10, 16] {
        let (asm, vals) = common::flat_iteration_matrix(&common::miura_scene(p));
        let n = asm.n_free;
        let pat =
            SymbolicSparseColMat::new_checked(n, n, asm.col_ptr.clone(), None, asm.row_idx.clone());
        for (name, thr) in [
            ("auto", SupernodalThreshold::AUTO),
            ("simplicial", SupernodalThreshold::FORCE_SIMPLICIAL),
            ("supernodal", SupernodalThreshold::FORCE_SUPERNODAL),
        ] {
            let sym = factorize_symbolic_cholesky(
                pat.as_ref(),
                Side::Lower,
                SymmetricOrdering::Amd,
                CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: thr,
                    ..Default::default()
                },
            )
            .unwrap();
            let mut mem = MemBuffer::new(StackReq::any_of(&[
                sym.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            ]));
            let mut l = vec![0.0; sym.len_val()];
            let a = SparseColMatRef::new(pat.as_ref(), &vals);
            let reps = 200;
            let t = Instant::now();
            for _ in 0..reps {
                sym.factorize_numeric_llt(
                    &mut l,
                    a,
                    Side::Lower,
                    LltRegularization::default(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .unwrap();
            }
            let dt = t.elapsed().as_secs_f64() / reps as f64;
            println!(
                "| {p}x{p} | {n} | {} | {name} | {} | {:.3} |",
                asm.nnz(),
                sym.len_val(),
                dt * 1e3
            );
        }
    }
}
