//! The static solver's load stepping: increments that fail are cut and the
//! path still reaches the answer, stops are landed on exactly, a hopeless
//! solve ends in a clear error, and bad inputs are errors, not panics.

use origami_fmu::assembly::{Assembler, Physics};
use origami_fmu::benchmarks::RollUp;
use origami_fmu::element::ElementOptions;
use origami_fmu::ids::VertexId;
use origami_fmu::mesh::builders::grid;
use origami_fmu::scene::Material;
use origami_fmu::solver::statics::{self, Load, StaticSettings};

/// A constant external force vector (all DOFs).
struct Constant(Vec<f64>);
impl Load for Constant {
    fn apply(&self, _: &Assembler, _: &[f64], lambda: f64, f: &mut [f64], _: Option<&mut [f64]>) {
        for (fi, x) in f.iter_mut().zip(&self.0) {
            *fi += lambda * x;
        }
    }
}

/// Rolling 16 cells into a full circle in one increment with at most 8
/// Newton iterations fails; the cut increments get there, to the same tip
/// as the default 16 increments, and land on the requested stops.
#[test]
fn failed_increments_are_cut_and_the_path_completes() {
    let reference = RollUp::new(16).solve(&[0.3, 0.7, 1.0]).unwrap();
    let mut hard = RollUp::new(16);
    hard.settings.load_steps = 1;
    hard.settings.max_iterations = 8;
    let run = hard.solve(&[0.3, 0.7, 1.0]).unwrap();
    let rep = &run.report;
    eprintln!(
        "{} increments, {} cuts, {} iterations ({} wasted)",
        rep.lambdas.len(),
        rep.cuts,
        rep.total_iterations(),
        rep.wasted_iterations
    );
    assert!(rep.cuts > 0 && rep.wasted_iterations > 0);
    assert_eq!(rep.lambdas.len(), rep.iterations.len());
    assert_eq!(rep.lambdas.len(), rep.residuals.len());
    assert!(rep.lambdas.windows(2).all(|w| w[1] > w[0]));
    for stop in [0.3, 0.7, 1.0] {
        assert!(rep.lambdas.contains(&stop), "stop {stop} not landed on");
    }
    assert!(rep.iterations.iter().all(|&i| i <= 8));
    for (a, b) in run.points.iter().zip(&reference.points) {
        assert!(
            (a.u - b.u).abs() < 1e-6 && (a.w - b.w).abs() < 1e-6,
            "{a:?} vs {b:?}"
        );
    }
}

fn plate() -> (Assembler, Vec<f64>, Vec<f64>) {
    let mesh = grid(1.0, 1.0, 2, 2, &[(1, 0.0)]);
    let physics = Physics {
        material: Material {
            youngs_modulus: 1e6,
            poisson_ratio: 0.3,
            thickness: 0.01,
            density: 1.0,
        },
        crease_k_per_length: 0.1,
        crease_c_per_length: 0.0,
        alpha: 0.0,
        beta: 0.0,
    };
    let layout = origami_fmu::dofs::DofLayout::new(&mesh);
    let fixed: Vec<usize> = (0..mesh.n_vertices())
        .filter(|&v| mesh.coords()[v].x == 0.0)
        .flat_map(|v| layout.vertex_slots(VertexId(v)))
        .collect();
    let asm = Assembler::new(&mesh, physics, ElementOptions::default(), &fixed).unwrap();
    let q = asm.layout.reference_state(&mesh);
    let mut f = vec![0.0; q.len()];
    for v in 0..mesh.n_vertices() {
        if mesh.coords()[v].x == 1.0 {
            f[3 * asm.layout.position_slot[v] + 2] = 1e-3;
        }
    }
    (asm, q, f)
}

/// One Newton iteration per increment can never converge: the solve cuts
/// down to `min_increment` and reports where and why it stopped.
#[test]
fn hopeless_solve_fails_with_a_clear_error() {
    let (asm, mut q, f) = plate();
    let theta0 = vec![std::f64::consts::PI; asm.creases.len()];
    let settings = StaticSettings {
        load_steps: 1,
        max_iterations: 1,
        tolerance: 1e-12,
        min_increment: 0.1,
    };
    let q0 = q.clone();
    let err = statics::solve(&asm, &mut q, &theta0, &Constant(f), settings)
        .unwrap_err()
        .to_string();
    eprintln!("{err}");
    assert!(err.contains("load factor 0.000000"), "{err}");
    assert!(err.contains("after 1 iterations"), "{err}");
    assert!(err.contains("below 1.0e-1"), "{err}");
    assert_eq!(q, q0, "a failed solve leaves q at the last converged state");
}

/// Wrong sizes, non-finite values and meaningless settings are errors.
#[test]
fn bad_inputs_are_errors() {
    let (asm, q, f) = plate();
    let theta0 = vec![std::f64::consts::PI; asm.creases.len()];
    let load = Constant(f);
    let ok = StaticSettings::default();
    let run = |q: &[f64], theta0: &[f64], settings: StaticSettings, stops: &[f64]| {
        let mut q = q.to_vec();
        statics::solve_path(&asm, &mut q, theta0, &load, settings, stops, |_, _, _| {})
    };
    assert!(run(&q, &theta0, ok, &[0.5]).is_ok());
    assert!(run(&q[1..], &theta0, ok, &[]).is_err());
    assert!(run(&q, &theta0[1..], ok, &[]).is_err());
    let mut nan = q.clone();
    nan[3] = f64::NAN;
    assert!(run(&nan, &theta0, ok, &[]).is_err());
    for bad in [
        StaticSettings {
            load_steps: 0,
            ..ok
        },
        StaticSettings {
            max_iterations: 0,
            ..ok
        },
        StaticSettings {
            tolerance: f64::NAN,
            ..ok
        },
        StaticSettings {
            tolerance: 0.0,
            ..ok
        },
        StaticSettings {
            min_increment: 0.0,
            ..ok
        },
        StaticSettings {
            min_increment: 2.0,
            ..ok
        },
    ] {
        assert!(run(&q, &theta0, bad, &[]).is_err(), "{bad:?}");
    }
    for stops in [&[0.5, 0.5][..], &[0.7, 0.3], &[0.0], &[1.5], &[f64::NAN]] {
        assert!(run(&q, &theta0, ok, stops).is_err(), "{stops:?}");
    }
    let bad_case = |nx, ny, ratios: &[f64]| {
        let mut case = RollUp::new(nx);
        case.ny = ny;
        case.solve(ratios).is_err()
    };
    assert!(bad_case(0, 1, &[0.5]));
    assert!(bad_case(4, 0, &[0.5]));
    assert!(bad_case(4, 1, &[]));
    assert!(bad_case(4, 1, &[0.5, 0.25]));
    assert!(bad_case(4, 1, &[-0.5]));
}
