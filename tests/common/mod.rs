//! Scene builders and measuring helpers shared by the dynamics test files.
#![allow(dead_code)] // each test file uses a different subset

pub mod fd;

use nalgebra::{Matrix3x2, Vector2, Vector3};
use origami_fmu::dofs::DofLayout;
use origami_fmu::ids::{FacetId, VertexId};
use origami_fmu::mesh::builders::grid;
use origami_fmu::model::{InputId, Model, StepReport};
use origami_fmu::scene::{CreaseStiffness, Fix, Integrator, Scene, Support};

/// The integrators every dynamics test runs with: add a row here to run the
/// whole suite with another integrator.
pub const INTEGRATORS: &[Integrator] = &[Integrator::GeneralizedAlpha];

/// Two square panels of side `w` side by side (x in [0, 2w]) on one crease
/// at x = w folding to `target`; the left panel's outer edge (vertices 0 and
/// 3) clamped, the crease ends are vertices 1 and 4, the free corners 2 and 5.
pub fn two_panels(w: f64, target: f64, integrator: Integrator) -> Scene {
    let mesh = grid(2.0 * w, w, 2, 1, &[(1, target)]);
    let mut scene = Scene::with_defaults("two_panels", mesh);
    scene.supports.push(Support {
        vertices: vec![VertexId(0), VertexId(3)],
        fix: Fix::Clamped,
    });
    scene.solver.integrator = integrator;
    scene
}

/// Crease stiffness per length k such that k w / D = `ratio` (D the plate
/// bending stiffness): `ratio` compares the hinge with the panel's own
/// bending stiffness over its width `w`.
pub fn crease_ratio(scene: &mut Scene, w: f64, ratio: f64) {
    let d = scene.material.bending_stiffness();
    scene.crease = CreaseStiffness::PerLength(ratio * d / w);
}

/// Angular frequency of a rigid panel of width `w` (perpendicular to the
/// crease) hinged on a crease of stiffness `k` per length: omega^2 = k l /
/// I with I = m w^2 / 3, m = rho h w l (docs/validation.md case C).
pub fn hinge_omega(scene: &Scene, w: f64) -> f64 {
    let m = &scene.material;
    let k = scene.crease.stiffness(m, 1.0);
    (3.0 * k / (m.density * m.thickness * w.powi(3))).sqrt()
}

/// The first `crease[..].angle` output (rad).
pub fn crease_angle(model: &Model) -> f64 {
    let i = model
        .outputs()
        .iter()
        .position(|v| v.name.starts_with("crease["))
        .expect("a crease output");
    model.output_values()[i]
}

/// Kinetic + strain + crease energy (J).
pub fn total_energy(model: &Model) -> f64 {
    model.energies().iter().sum()
}

/// Index of the input called `name`.
pub fn input(model: &Model, name: &str) -> InputId {
    model
        .input_id(name)
        .unwrap_or_else(|| panic!("no input {name}"))
}

/// The step controller's work summed over many advances.
#[derive(Clone, Debug, Default)]
pub struct Work {
    /// Sum of the reports so far (min_step: the smallest).
    pub total: StepReport,
    /// Number of advances.
    pub advances: usize,
}

impl Work {
    /// Add one advance's report.
    pub fn add(&mut self, r: &StepReport) {
        self.total.accumulate(r);
        self.advances += 1;
    }

    /// `advance(h)` on `model`, adding its report; panics on an error.
    pub fn advance(&mut self, model: &mut Model, h: f64) {
        let r = model
            .advance(h)
            .unwrap_or_else(|e| panic!("advance at t = {}: {e}", model.time()));
        self.add(&r);
    }

    /// One line for the log: steps, rejections, Newton iterations,
    /// factorizations, smallest step.
    pub fn line(&self) -> String {
        let t = &self.total;
        format!(
            "steps {}, rejected {}, newton {}, factorizations {}, min step {:.3e} s",
            t.steps, t.rejected, t.newton_iterations, t.factorizations, t.min_step
        )
    }
}

/// Give a just initialized, undamped model the initial velocity field
/// `field`: for a point X of the flat sheet and the facets around it (a
/// sector of a vertex fan, or all facets at a vertex for its position) it
/// returns the velocity and its gradient dv/dX (3 x 2). The Model API has no
/// velocity input, so this goes through `save_state`/`restore_state`; the
/// initial acceleration stays consistent because without damping the forces
/// do not depend on the velocity. Outputs (energies) update at the next advance.
pub fn set_velocity(
    model: &mut Model,
    field: impl Fn(Vector2<f64>, &[FacetId]) -> (Vector3<f64>, Matrix3x2<f64>),
) {
    let scene = model.scene();
    let d = &scene.damping;
    assert!(
        !scene.auto_damping && d.alpha == 0.0 && d.beta == 0.0 && d.crease == 0.0,
        "set_velocity needs an undamped scene"
    );
    let mesh = &scene.mesh;
    let layout = DofLayout::new(mesh);
    assert_eq!(
        layout.n_dofs(),
        model.n_dofs(),
        "layout differs from the model's"
    );
    let q_ref = layout.reference_state(mesh);
    let mut v = vec![f64::NAN; layout.n_dofs()];
    let mut put = |slot: usize, x: Vector3<f64>| {
        let old = &mut v[3 * slot..3 * slot + 3];
        if old[0].is_finite() {
            let diff = (Vector3::new(old[0], old[1], old[2]) - x).norm();
            assert!(
                diff <= 1e-12 * x.norm().max(1e-300),
                "slot {slot}: sectors disagree"
            );
        }
        old.copy_from_slice(x.as_slice());
    };
    for vx in mesh.vertex_ids() {
        let x = mesh.coord(vx);
        let all: Vec<FacetId> = layout.sectors[vx.index()]
            .iter()
            .flat_map(|s| s.faces.clone())
            .collect();
        put(layout.position_slot[vx.index()], field(x, &all).0);
        for sec in &layout.sectors[vx.index()] {
            let (_, grad) = field(x, &sec.faces);
            for &(slot, _) in &sec.terms {
                let dir = Vector2::new(q_ref[3 * slot], q_ref[3 * slot + 1]);
                put(slot, grad * dir);
            }
        }
    }
    let mut state = model.save_state();
    assert!(v.iter().all(|x| x.is_finite()), "a slot got no velocity");
    state.dynamics.v = v;
    model.restore_state(&state).expect("same model");
}

/// The velocity field of a rigid rotation `omega` about the point `centre`
/// (for [`set_velocity`]).
pub fn rigid_rotation(
    omega: Vector3<f64>,
    centre: Vector3<f64>,
    x: Vector2<f64>,
) -> (Vector3<f64>, Matrix3x2<f64>) {
    let r = Vector3::new(x.x, x.y, 0.0) - centre;
    let grad = Matrix3x2::from_columns(&[omega.cross(&Vector3::x()), omega.cross(&Vector3::y())]);
    (omega.cross(&r), grad)
}

/// Start the free panel of [`two_panels`] (facets right of the crease at
/// x = `w`) turning about the crease at `rate` rad/s as a rigid body, the
/// clamped panel at rest (see [`set_velocity`]).
pub fn hinge_velocity(model: &mut Model, w: f64, rate: f64) {
    let mesh = &model.scene().mesh;
    let free: Vec<bool> = mesh
        .triangles()
        .iter()
        .map(|t| t.iter().map(|&v| mesh.coord(v).x).sum::<f64>() / 3.0 > w)
        .collect();
    let axis = Vector3::new(0.0, rate, 0.0);
    let centre = Vector3::new(w, 0.0, 0.0);
    set_velocity(model, |x, faces| {
        if faces.iter().any(|&f| free[f.index()]) {
            rigid_rotation(axis, centre, x)
        } else {
            (Vector3::zeros(), Matrix3x2::zeros())
        }
    });
}
pub mod fmi;

/// Two 50 x 50 mm panels of 1 mm plastic (2 GPa, 1200 kg/m^3) with a valley
/// crease between them (vertices 0-5 counter-clockwise from the origin,
/// the crease from 1 to 4), with the scene keys `keys` (JSON members,
/// comma-separated) added.
pub fn two_plastic_panels(keys: &str) -> Scene {
    let text = format!(
        r#"{{
          "frame_unit": "m",
          "vertices_coords": [[0,0],[0.05,0],[0.1,0],[0.1,0.05],[0.05,0.05],[0,0.05]],
          "edges_vertices": [[0,1],[1,2],[2,3],[3,4],[4,5],[5,0],[1,4]],
          "edges_assignment": ["B","B","B","B","B","B","V"],
          "edges_foldAngle": [null,null,null,null,null,null,90],
          "faces_vertices": [[0,1,4,5],[1,2,3,4]],
          "ancf:material": {{"thickness": 1e-3, "youngs_modulus": 2e9, "density": 1200}},
          {keys}
        }}"#
    );
    origami_fmu::scene::from_str(&text).unwrap().0
}

/// The outputs `prefix.x/y/z` now (a wrench's force or moment, a vertex).
pub fn output_vector(m: &Model, prefix: &str) -> Vector3<f64> {
    let at = |c: &str| {
        let name = format!("{prefix}.{c}");
        let id = m
            .output_id(&name)
            .unwrap_or_else(|| panic!("no output {name}"));
        m.output(id).unwrap()
    };
    Vector3::new(at("x"), at("y"), at("z"))
}

/// Assert that the state `saved` of `model` (a model of `scene`, still at
/// that state) continues bit for bit over `steps` advances of 10 ms, each
/// after `drive` sets the inputs: from it, again after restoring it in the
/// same model, and in a fresh model of `scene` (every output compared).
#[allow(dead_code)]
pub fn assert_restores_bit_for_bit(
    scene: Scene,
    model: &mut Model,
    saved: &origami_fmu::model::ModelState,
    (steps, drive): (usize, impl Fn(&mut Model)),
) {
    let run = |m: &mut Model| {
        let mut out = Vec::new();
        for _ in 0..steps {
            drive(m);
            m.advance(0.01).unwrap();
            out.extend(m.output_values());
        }
        out
    };
    let first = run(model);
    model.restore_state(saved).unwrap();
    let again = run(model);
    let mut fresh_model = Model::new(scene).unwrap();
    fresh_model.restore_state(saved).unwrap();
    let fresh = run(&mut fresh_model);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&first), bits(&again), "same model");
    assert_eq!(bits(&first), bits(&fresh), "fresh model");
}

/// A 0.1 x 0.1 m square of 1 mm plastic (2 GPa, 1200 kg/m^3) in the plane
/// z = 0 with its lowest corner at `corner`, under gravity `g`, with the
/// further FOLD keys `keys` (`"key": value, ...`).
#[allow(dead_code)]
pub fn plastic_square(corner: [f64; 2], g: [f64; 3], keys: &str) -> Scene {
    let [x, y] = corner;
    let (x1, y1) = (x + 0.1, y + 0.1);
    let text = format!(
        r#"{{
          "frame_unit": "m",
          "vertices_coords": [[{x},{y}],[{x1},{y}],[{x1},{y1}],[{x},{y1}]],
          "edges_vertices": [[0,1],[1,2],[2,3],[3,0]],
          "edges_assignment": ["B","B","B","B"],
          "faces_vertices": [[0,1,2,3]],
          "ancf:material": {{"thickness": 1e-3, "youngs_modulus": 2e9, "density": 1200}},
          "ancf:loads": {{"gravity": [{}, {}, {}]}},
          {keys}
        }}"#,
        g[0], g[1], g[2]
    );
    origami_fmu::scene::from_str(&text).unwrap().0
}

/// Kinetic, strain, crease and contact energy plus the work dissipated so
/// far, from the outputs (J): less `energy.input_work`, it is constant.
#[allow(dead_code)]
pub fn energy_and_dissipated(m: &Model) -> f64 {
    [
        "energy.kinetic",
        "energy.strain",
        "energy.crease",
        "energy.contact",
        "energy.dissipated",
    ]
    .iter()
    .map(|n| m.output(m.output_id(n).unwrap()).unwrap())
    .sum()
}
