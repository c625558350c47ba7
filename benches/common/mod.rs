//! Helpers the benches share.

/// CPU time of this process so far, s (the benches compare CPU, not wall,
/// time on the shared machine).
#[allow(dead_code)]
pub fn cpu_seconds() -> f64 {
    origami_fmu::cpu_time::process_seconds()
}

/// The quadrature rule a bench's `--quadrature 7|12` names.
#[allow(dead_code)]
pub fn quadrature_rule(arg: &str) -> origami_fmu::element::Rule {
    match arg {
        "7" => origami_fmu::element::Rule::Dunavant7,
        "12" => origami_fmu::element::Rule::Dunavant12,
        _ => panic!("--quadrature 7|12, not {arg}"),
    }
}

/// The m x m panel Miura-ori scene of the benches (20 mm, 60 degree sectors).
#[allow(dead_code)]
pub fn miura_scene(panels: usize) -> origami_fmu::scene::Scene {
    let miura = origami_fmu::scene::patterns::Miura {
        nx: panels / 2,
        ny: panels / 2,
        ..Default::default()
    };
    origami_fmu::scene::from_fold(&miura.generate().expect("Miura generates"), None)
        .expect("Miura loads")
        .0
}

/// The scene's assembler and its iteration matrix at the flat reference
/// (creases driven toward 3 rad, a 2 ms step's weights at rho_inf 0.6):
/// what the factorization benches factor.
#[allow(dead_code)]
pub fn flat_iteration_matrix(
    scene: &origami_fmu::scene::Scene,
) -> (origami_fmu::assembly::Assembler, Vec<f64>) {
    use origami_fmu::assembly::{Assembler, Evaluation, MatrixCoeffs, State};
    let physics = origami_fmu::model::physics(scene);
    let asm = Assembler::new(
        &scene.mesh,
        physics,
        origami_fmu::element::ElementOptions::default(),
        &[],
    )
    .expect("assembler");
    let q = asm.layout.reference_state(&scene.mesh);
    let v = vec![0.0; q.len()];
    let nc = asm.creases.len();
    let t0 = vec![3.0; nc];
    let mom = vec![0.0; nc];
    let tp = vec![std::f64::consts::PI; nc];
    let st = State {
        q: &q,
        v: &v,
        theta0: &t0,
        moment: &mom,
        theta_prev: &tp,
    };
    let mut vals = vec![0.0; asm.nnz()];
    let mut ev = Evaluation::default();
    let h = 2e-3;
    asm.evaluate(
        &st,
        &mut ev,
        Some((
            &mut vals,
            MatrixCoeffs {
                k: 1.0,
                c: 0.6 / (0.3 * h),
                m: 1.0 / (0.3 * h * h),
            },
        )),
    )
    .expect("evaluation");
    (asm, vals)
}

/// The free square of `tests/fmpy/scenes/square.json` with the ramp input
/// timing, changed by `edit`, as an initialized model, and the index of
/// its fold input.
#[allow(dead_code)]
pub fn square_model(
    edit: impl FnOnce(origami_fmu::scene::Scene) -> origami_fmu::scene::Scene,
) -> (origami_fmu::model::Model, origami_fmu::model::InputId) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fmpy/scenes/square.json");
    let mut scene = origami_fmu::fmi::resources::load_scene_file(&path).expect("square scene");
    scene.solver.input_timing = origami_fmu::scene::InputTiming::FirstOrderHold;
    let mut m = origami_fmu::model::Model::new(edit(scene)).expect("model");
    m.initialize().expect("initialize");
    let fold = m.input_id("fold").expect("fold input");
    (m, fold)
}
