//! Fill-reducing orderings of the implicit stepper's iteration matrix
//! (Miura sheets and Origami Simulator's BoxPleatPyramid at the flat
//! reference, a 2 ms step's weights): AMD on the scalar graph, AMD on the
//! slot graph, nested dissection by planes on the slot graph; the factor's
//! entries, its multiply-adds and the time of one numeric factorization
//! (best of the repetitions), in one run.
//!
//! `cargo bench --bench ordering [-- --panels 10,16,24] [--no-pyramid]`

use origami_fmu::scene::Scene;
use origami_fmu::solver::{Ordering, SparseSolver};
// Times are CPU time (this thread's clock; the benches run on one thread).
use origami_fmu::cpu_time::CpuInstant as Instant;

mod common;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let panels: Vec<usize> = value("--panels")
        .unwrap_or_else(|| "10,16,24".into())
        .split(',')
        .map(|p| p.parse().expect("panels"))
        .collect();
    let pyramid = !args.iter().any(|a| a == "--no-pyramid");
    println!(
        "| scene | unknowns | ordering | ordering CPU ms | nnz(L) | G multiply-adds | CPU ms per factorization |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for p in panels {
        let scene = common::miura_scene(p);
        compare(&format!("Miura {p}x{p}"), &scene);
    }
    if pyramid {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/origami-simulator/BoxPleatPyramid.fold"
        );
        let (scene, _) = origami_fmu::scene::load(path).expect("BoxPleatPyramid loads");
        compare("BoxPleatPyramid", &scene);
    }
}

fn compare(name: &str, scene: &Scene) {
    let (asm, vals) = common::flat_iteration_matrix(scene);
    let n = asm.n_free;
    let coords = asm.free_block_coords(&scene.mesh);
    let orderings = [
        ("AMD", Ordering::Amd),
        ("slot AMD", Ordering::BlockAmd(3)),
        (
            "slot nested dissection",
            Ordering::BlockNestedDissection {
                block: 3,
                coords: &coords,
            },
        ),
    ];
    for (label, ord) in orderings {
        let t = Instant::now();
        let mut s =
            SparseSolver::with_ordering(n, asm.col_ptr.clone(), asm.row_idx.clone(), ord).unwrap();
        let t_order = t.elapsed().as_secs_f64();
        let (len, flops) = s.factor_size();
        s.factor(&vals).unwrap();
        // Best of the repetitions: the machine is shared.
        let reps = (2e9 / flops).clamp(3.0, 200.0) as usize;
        let mut dt = f64::INFINITY;
        for _ in 0..reps {
            let t = Instant::now();
            s.factor(&vals).unwrap();
            dt = dt.min(t.elapsed().as_secs_f64());
        }
        println!(
            "| {name} | {n} | {label} | {:.1} | {len} | {:.3} | {:.2} |",
            t_order * 1e3,
            flops * 1e-9,
            dt * 1e3
        );
    }
}
