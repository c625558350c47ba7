//! End-to-end model checks: a single crease driven through its rest angle
//! folds to the target and settles there (BENCHMARKS.md case C: driving the
//! rest angle quasi-statically must end at phi_0 with zero crease moment).

use origami_fmu::mesh::builders::grid;
use origami_fmu::model::Model;
use origami_fmu::scene::{Fix, Scene, Support};

fn two_panels(target: f64) -> Scene {
    // Two 20 mm x 20 mm panels; crease along x = 20 mm; left edge clamped.
    let mesh = grid(0.04, 0.02, 2, 1, &[(1, target)]);
    let mut scene = Scene::with_defaults("two_panels", mesh);
    scene.supports.push(Support { vertices: vec![0, 3], fix: Fix::Clamped });
    scene
}

fn angle(model: &Model) -> f64 {
    let names: Vec<&str> = model.outputs().iter().map(|v| v.name.as_str()).collect();
    let i = names.iter().position(|n| n.starts_with("crease[")).expect("crease output");
    model.output_values()[i]
}

#[test]
fn rest_angle_ramp_folds_to_target() {
    for target in [1.2f64, -2.0, 3.0] {
        let mut m = Model::new(two_panels(target)).unwrap();
        m.initialize().unwrap();
        let fold = m.inputs().iter().position(|v| v.name == "fold").unwrap();
        // ramp over 0.2 s, hold 0.8 s
        let steps = 100;
        for k in 1..=steps {
            let t = k as f64 * 0.01;
            m.set_input(fold, (t / 0.2).min(1.0)).unwrap();
            m.advance(0.01).unwrap();
            assert!(m.output_values().iter().all(|x| x.is_finite()));
        }
        let phi = angle(&m);
        assert!(
            (phi - target).abs() < 5e-3 * target.abs(),
            "target {target}: final angle {phi}"
        );
        let [_, _, crease_e] = m.energies();
        assert!(crease_e < 1e-9, "crease energy left {crease_e}");
    }
}
