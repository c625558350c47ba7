//! Rigid obstacles (`ancf:obstacles`): a sheet dropped on the ground comes
//! to rest half its thickness above it with the ground carrying its weight;
//! on an incline steeper than the friction angle it slides with
//! g (sin a - mu cos a); the obstacle force equals minus its energy's
//! gradient and the iteration matrix the force's derivative; the shapes'
//! closed-form distances against finite differences; bad entries are
//! refused with the key and the fault named.

mod common;

use common::fd::{eval_at, force_and_tangent_match_finite_differences, matrix_fd_error};
use nalgebra::Vector3;
use origami_fmu::Model;
use origami_fmu::assembly::{Assembler, MatrixCoeffs};
use origami_fmu::contact::{ContactSettings, Obstacle, ObstacleTerm, Shape};
use origami_fmu::element::ElementOptions;
use origami_fmu::mesh::builders::grid;
use origami_fmu::scene::Scene;

use common::output_vector as vector;

/// The 0.1 m plastic square with a corner at the origin
/// ([`common::plastic_square`]).
fn square(g: [f64; 3], obstacles: &str, extra: &str) -> Scene {
    common::plastic_square(
        [0.0, 0.0],
        g,
        &format!(r#""ancf:obstacles": {obstacles}{extra}"#),
    )
}

fn vertex(m: &Model, i: usize) -> Vector3<f64> {
    vector(m, &format!("vertex[{i}]"))
}

/// A sheet dropped flat from 2 mm above the ground comes to rest on it:
/// no contact sample ever within half the thickness of the plane (at every
/// output, every 10 ms), and after 0.5 s every contact sample's (and
/// vertex's) height above the plane is half the thickness to within the
/// barrier width (a tenth of it, 50 um), the sheet at rest (speed below 1e-4 m/s), and the ground's
/// force output the sheet's weight, pointing down, within 1e-3 relative,
/// its moment about the plane's point the weight's about it (1e-3 of the
/// weight times the lever arm).
#[test]
fn a_sheet_dropped_on_the_ground_rests_half_its_thickness_above_it() {
    let ground = r#"[{"name": "ground", "shape": "half_space", "point": [0, 0, -0.0025], "normal": [0, 0, 1]}]"#;
    let mut m = Model::new(square([0.0, 0.0, -9.81], ground, "")).unwrap();
    m.initialize().unwrap();
    let (mass, _) = m.mass_properties();
    let weight = mass * 9.81;
    let h = 1e-3;
    let mut steps = 0;
    for k in 0..50 {
        steps += m.advance(0.01).unwrap().steps;
        let (gap, _, clearance) = m.obstacle_gap().unwrap();
        assert!((clearance - h / 2.0).abs() < 1e-15);
        assert!(
            gap > 0.0,
            "t = {}: a sample within h/2 (gap {gap:e})",
            0.01 * (k + 1) as f64
        );
    }
    // Every contact sample's height above the plane less h/2, and the
    // FOLD vertices' (corners).
    let (gap, largest, _) = m.obstacle_gap().unwrap();
    let top: f64 = (0..4)
        .map(|i| vertex(&m, i).z + 0.0025)
        .fold(f64::NEG_INFINITY, f64::max);
    let (_, c) = m.mass_properties();
    let f = vector(&m, "ground.force");
    let mom = vector(&m, "ground.moment");
    eprintln!(
        "steps {steps}; sample gaps beyond h/2 {gap:.3e}..{largest:.3e} m, highest vertex \
         {top:.6e} m; force {f:?} (weight {weight:.6e} N); moment {mom:?}"
    );
    assert!(gap > 0.0 && largest < 0.1 * h / 2.0, "{gap}, {largest}");
    assert!(top - h / 2.0 < 0.1 * h / 2.0, "{top}");
    // At rest: speed below 1e-4 m/s.
    assert!(
        kinetic(&m) < 0.5 * mass * 1e-8,
        "kinetic energy {}",
        kinetic(&m)
    );
    assert!(
        (f.z + weight).abs() < 1e-3 * weight && f.xy().norm() < 1e-3 * weight,
        "force {f:?}, weight {weight}"
    );
    // The weight acts at the centre of mass, over the plane's point (0, 0).
    let want = Vector3::new(c[0], c[1], 0.0).cross(&Vector3::new(0.0, 0.0, -weight));
    assert!(
        (mom - want).norm() < 1e-3 * weight * 0.05,
        "moment {mom:?}, want {want:?}"
    );
}

/// The sheet's kinetic energy output now (J).
fn kinetic(m: &Model) -> f64 {
    m.output(m.output_id("energy.kinetic").unwrap()).unwrap()
}

/// On the ground tilted at 30 degrees (gravity turned instead: the plane
/// z = const, g = 9.81 (sin a, 0, -cos a)), friction mu = 0.3 (friction
/// angle 16.7 degrees), a square resting on it slides down with
/// g (sin a - mu cos a) = 2.356 m/s^2: measured from the centre of mass at
/// 0.1, 0.2 and 0.3 s (second difference), within 2 %; it does not leave
/// the plane (every output's smallest gap within the barrier width).
#[test]
fn a_sheet_on_a_plane_steeper_than_friction_slides_with_g_sin_minus_mu_cos() {
    let a = 30f64.to_radians();
    let (g, mu) = (9.81, 0.3);
    let ground = r#"[{"name": "ground", "shape": "half_space", "point": [0, 0, -0.00052], "normal": [0, 0, 1], "friction": 0.3}]"#;
    let mut m = Model::new(square([g * a.sin(), 0.0, -g * a.cos()], ground, "")).unwrap();
    m.initialize().unwrap();
    let mut xs = Vec::new();
    let mut steps = 0;
    for k in 1..=30 {
        steps += m.advance(0.01).unwrap().steps;
        let (gap, _, _) = m.obstacle_gap().unwrap();
        assert!(
            gap > 0.0 && gap < 5e-5,
            "t = {}: gap {gap:e}",
            0.01 * k as f64
        );
        if k % 10 == 0 {
            xs.push(m.mass_properties().1[0]);
        }
    }
    let acc = (xs[2] - 2.0 * xs[1] + xs[0]) / (0.1 * 0.1);
    let want = g * (a.sin() - mu * a.cos());
    eprintln!(
        "steps {steps}; acceleration {acc:.7} m/s^2, g (sin a - mu cos a) = {want:.7} ({:.1e} relative)",
        (acc - want).abs() / want
    );
    assert!((acc - want).abs() < 0.02 * want, "{acc} vs {want}");
}

/// On a plane tilted at 10 degrees (below the friction angle of mu = 0.3)
/// the square stays where it landed: after 0.3 s it has moved less than
/// 0.1 mm along the slope over the last 0.2 s.
#[test]
fn a_sheet_on_a_plane_below_the_friction_angle_sticks() {
    let a = 10f64.to_radians();
    let g = 9.81;
    let ground = r#"[{"name": "ground", "shape": "half_space", "point": [0, 0, -0.00052], "normal": [0, 0, 1], "friction": 0.3}]"#;
    let mut m = Model::new(square([g * a.sin(), 0.0, -g * a.cos()], ground, "")).unwrap();
    m.initialize().unwrap();
    m.advance(0.1).unwrap();
    let x0 = m.mass_properties().1[0];
    for _ in 0..20 {
        m.advance(0.01).unwrap();
    }
    let dx = m.mass_properties().1[0] - x0;
    eprintln!("slid {dx:e} m in 0.2 s; kinetic energy {:e} J", kinetic(&m));
    assert!(dx.abs() < 1e-4, "slid {dx} m");
}

/// A 0.1 m square as 8 facets in z = 0, nudged off flat (the same small
/// deviation for every shape), an assembler without damping of its own
/// (the velocity derivatives are the obstacles' alone) with `shape`
/// below it in the barrier (barrier width half the clearance, so that a
/// few contact samples are in it), exact Hessians.
fn assembler_with(shape: Shape, friction: f64) -> (Assembler, Vec<f64>) {
    let mesh = grid(0.1, 0.1, 2, 2, &[]);
    let scene = Scene::with_defaults("fd", mesh.clone());
    let physics = origami_fmu::assembly::Physics {
        alpha: 0.0,
        beta: 0.0,
        ..origami_fmu::model::physics(&scene)
    };
    let mut asm = Assembler::new(&mesh, physics, ElementOptions::default(), &[]).unwrap();
    let settings = ContactSettings {
        thickness: 1e-3,
        width: 1.0,
        stiffness: Some(10.0),
        damping_ratio: 1.0,
        subdivisions: 3,
        ..Default::default()
    };
    let obstacle = Obstacle {
        name: "o".into(),
        shape,
        friction,
        moving: false,
    };
    let term = ObstacleTerm::new(
        &mesh,
        &asm.layout,
        &asm.elements,
        &[obstacle],
        &settings,
        0.2,
        1e3,
    )
    .unwrap()
    .with_exact_hessian();
    asm.add_barrier(Box::new(term));
    let mut q = asm.layout.reference_state(&mesh);
    let mut rng = origami_fmu::rng::XorShift(11);
    for x in q.iter_mut() {
        *x += rng.range(-1e-5, 1e-5);
    }
    (asm, q)
}

/// Shapes under the square whose closest samples are within the barrier:
/// a tilted plane, a ball, a box turned so that an edge is highest, and a
/// slanted capsule.
fn fd_shapes() -> Vec<Shape> {
    let n = Vector3::new(0.002, -0.001, 1.0).normalize();
    vec![
        Shape::HalfSpace {
            point: [0.05, 0.05, -0.0008],
            normal: [n.x, n.y, n.z],
        },
        Shape::Sphere {
            center: [0.05, 0.05, -0.5006],
            radius: 0.5,
        },
        Shape::Box {
            center: [0.05, 0.05, -0.0113],
            half_extents: [0.02, 0.03, 0.01],
            rotation: [0.02, 0.0, 0.3],
        },
        Shape::Capsule {
            ends: [[0.01, 0.05, -0.2007], [0.09, 0.05, -0.2008]],
            radius: 0.2,
        },
    ]
}

/// The obstacle force is the gradient of its energy and its matrix (exact
/// Hessians `kappa (b'' n n^T + b' H)`) the derivative of its force, for
/// each shape (central differences with step 1e-8; 1e-5 of the largest
/// force, or of the largest matrix entry).
#[test]
fn obstacle_force_and_tangent_match_finite_differences() {
    for shape in fd_shapes() {
        let (mut asm, q) = assembler_with(shape.clone(), 0.0);
        let zeros = vec![0.0; q.len()];
        asm.before_step(&q, &zeros);
        let ev = eval_at(&asm, &q, &zeros, None);
        eprintln!("{shape:?}: {} pairs in the barrier", ev.barrier_pairs);
        assert!(ev.barrier_pairs >= 1, "{shape:?}: no pair in the barrier");
        force_and_tangent_match_finite_differences(&asm, &q);
    }
}

/// The obstacle's damping matrix (normal dashpot and friction, with the
/// normal force and basis lagged from the step start) is the derivative of
/// its force in the velocities, with the square sliding (friction
/// slipping) and approaching, for each shape (central differences with
/// step 1e-7 m/s; 1e-5 of the largest entry);
/// and the powers are positive.
#[test]
fn obstacle_dashpot_and_friction_match_finite_differences() {
    for shape in fd_shapes() {
        let (mut asm, q) = assembler_with(shape.clone(), 0.5);
        let mut v = vec![0.0; q.len()];
        let mut rng = origami_fmu::rng::XorShift(5);
        for s in 0..q.len() / 3 {
            if asm.layout.slot_kind[s] == origami_fmu::dofs::SlotKind::Position {
                let w = [0.02, 0.01, -0.005].map(|x| x * (1.0 + rng.range(-0.2, 0.2)));
                v[3 * s..3 * s + 3].copy_from_slice(&w);
            }
        }
        asm.before_step(&q, &v);
        let mut c = vec![0.0; asm.nnz()];
        let co = MatrixCoeffs {
            k: 0.0,
            m: 0.0,
            c: 1.0,
        };
        let ev = eval_at(&asm, &q, &v, Some((&mut c, co)));
        assert!(
            ev.contact_damping_power > 0.0 && ev.friction_power > 0.0,
            "{shape:?}: {} {}",
            ev.contact_damping_power,
            ev.friction_power
        );
        // Velocities of 2 cm/s: steps of 1e-7 m/s (at 1e-9 rounding
        // reaches 1e-5 of the matrix with the box's two pairs).
        let err = matrix_fd_error(&asm, &q, &v, &c, true, 1e-7);
        assert!(err <= 1e-5, "{shape:?}: damping matrix vs force: {err:.3e}");
    }
}

/// The wrench outputs are the obstacle forces summed: the force on the
/// obstacle is minus the sum of the forces the term puts on the sheet's
/// position slots (the surface gradients carry no net force), checked on
/// the evaluation of each shape (1e-9 relative: the sum is the difference
/// of the sheet's forces with and without the obstacle).
#[test]
fn obstacle_wrench_is_the_sum_of_the_pair_forces() {
    for shape in fd_shapes() {
        let (mut asm, q) = assembler_with(shape.clone(), 0.5);
        let v = vec![0.01; q.len()];
        asm.before_step(&q, &v);
        let with = eval_at(&asm, &q, &v, None);
        let w = with.obstacle_wrenches[0];
        // The sheet's own forces alone: the same assembler without contact.
        let mesh = grid(0.1, 0.1, 2, 2, &[]);
        let scene = Scene::with_defaults("fd", mesh.clone());
        let physics = origami_fmu::assembly::Physics {
            alpha: 0.0,
            beta: 0.0,
            ..origami_fmu::model::physics(&scene)
        };
        let bare = Assembler::new(&mesh, physics, ElementOptions::default(), &[]).unwrap();
        let without = eval_at(&bare, &q, &v, None);
        let mut sum = Vector3::zeros();
        for s in 0..q.len() / 3 {
            if asm.layout.slot_kind[s] == origami_fmu::dofs::SlotKind::Position {
                for a in 0..3 {
                    sum[a] += with.force[3 * s + a] - without.force[3 * s + a];
                }
            }
        }
        let f = Vector3::new(w[0], w[1], w[2]);
        assert!(f.norm() > 0.0);
        assert!(
            (f - sum).norm() <= 1e-9 * f.norm(),
            "{shape:?}: wrench {f:?}, sum of the slot forces {sum:?}"
        );
    }
}

/// Bad `ancf:obstacles` entries are refused with the key and what is
/// wrong.
#[test]
fn bad_obstacles_are_refused_with_the_key_and_the_fault() {
    let base = r#"{
      "frame_unit": "m",
      "vertices_coords": [[0,0],[0.1,0],[0.1,0.1],[0,0.1]],
      "edges_vertices": [[0,1],[1,2],[2,3],[3,0]],
      "edges_assignment": ["B","B","B","B"],
      "faces_vertices": [[0,1,2,3]],
      "ancf:obstacles": OBSTACLES
    }"#;
    let cases = [
        (r#"{"name": "g"}"#, "ancf:obstacles", "expected an array"),
        (r#"[{"name": "g"}]"#, "ancf:obstacles[0].shape", "missing"),
        (
            r#"[{"name": "g", "shape": "plane"}]"#,
            "ancf:obstacles[0].shape",
            "half_space",
        ),
        (
            r#"[{"name": "g", "shape": "sphere", "center": [0, 0, 0]}]"#,
            "ancf:obstacles[0].radius",
            "missing",
        ),
        (
            r#"[{"name": "g", "shape": "sphere", "center": [0, 0, 0], "radius": -1}]"#,
            "ancf:obstacles[0].radius",
            "positive",
        ),
        (
            r#"[{"name": "g", "shape": "half_space", "point": [0, 0, 0], "normal": [0, 0, 0]}]"#,
            "ancf:obstacles[0].normal",
            "nonzero",
        ),
        (
            r#"[{"name": "g", "shape": "half_space", "point": [0, 0], "normal": [0, 0, 1]}]"#,
            "ancf:obstacles[0].point",
            "3 components",
        ),
        (
            r#"[{"name": "g", "shape": "box", "center": [0, 0, 0], "half_extents": [1, 0, 1]}]"#,
            "ancf:obstacles[0].half_extents[1]",
            "positive",
        ),
        (
            r#"[{"name": "g", "shape": "capsule", "ends": [[0, 0, 0]], "radius": 1}]"#,
            "ancf:obstacles[0].ends",
            "2 end points",
        ),
        (
            r#"[{"name": "g", "shape": "sphere", "center": [0, 0, 0], "radius": 1, "radius_": 2}]"#,
            "ancf:obstacles[0]",
            "unknown field 'radius_'",
        ),
        (
            r#"[{"name": "g", "shape": "sphere", "center": [0, 0, 0], "radius": 1, "friction": -1}]"#,
            "ancf:obstacles[0].friction",
            "",
        ),
        (
            r#"[{"name": "g", "shape": "sphere", "center": [0, 0, 0], "radius": 1, "moving": "yes"}]"#,
            "ancf:obstacles[0].moving",
            "expected true or false",
        ),
        (
            r#"[{"name": "vertex", "shape": "sphere", "center": [0, 0, 0], "radius": 1}]"#,
            "ancf:obstacles[0].name",
            "clashes",
        ),
        (
            r#"[{"name": "g", "shape": "sphere", "center": [0, 0, 0], "radius": 1},
                {"name": "g", "shape": "sphere", "center": [0, 0, 1], "radius": 1}]"#,
            "ancf:obstacles[1].name",
            "already used",
        ),
        (
            r#"[{"name": "g", "shape": "sphere", "center": [0, 0, 1e31], "radius": 1}]"#,
            "ancf:obstacles[0].center[2]",
            "too large",
        ),
    ];
    for (obstacles, key, words) in cases {
        let text = base.replace("OBSTACLES", obstacles);
        let e = origami_fmu::scene::from_str(&text)
            .err()
            .unwrap_or_else(|| panic!("accepted: {obstacles}"))
            .to_string();
        assert!(
            e.contains(key) && e.contains(words),
            "{obstacles}: {e} (want {key}: ...{words}...)"
        );
    }
}

/// One shape of each kind, placed and turned off the axes.
fn shapes() -> Vec<Shape> {
    vec![
        Shape::HalfSpace {
            point: [0.1, -0.2, 0.05],
            normal: [0.3, -0.2, 1.0],
        },
        Shape::Sphere {
            center: [0.1, 0.2, -0.3],
            radius: 0.25,
        },
        Shape::Box {
            center: [0.1, 0.2, -0.3],
            half_extents: [0.2, 0.1, 0.3],
            rotation: [0.4, -0.3, 0.7],
        },
        Shape::Capsule {
            ends: [[0.0, 0.0, 0.0], [0.3, 0.1, -0.2]],
            radius: 0.05,
        },
    ]
}

/// Each shape's distance gradient and Hessian against central
/// differences of the distance and of the gradient (step 1e-6 m;
/// within 1e-6 relative to the larger of 1 and the entry's size), at
/// random points outside the shape (the box: also near its faces,
/// edges and corners; the capsule: beside its segment and beyond its
/// ends), and the distance itself against sampled surface points
/// (the gradient is unit and the closest point `x - d n` is on the
/// surface: its distance is zero).
#[test]
fn closest_gradients_and_hessians_match_finite_differences() {
    let mut rng = origami_fmu::rng::XorShift(7);
    let eps = 1e-6;
    let mut checked = 0;
    for shape in shapes() {
        for _ in 0..200 {
            let x = Vector3::from_fn(|_, _| rng.range(-0.8, 0.8));
            let c = shape.closest(&x);
            if c.distance < 1e-3 {
                continue;
            }
            checked += 1;
            assert!((c.normal.norm() - 1.0).abs() < 1e-12);
            let on = shape.closest(&(x - c.distance * c.normal));
            assert!(on.distance.abs() < 1e-12, "{shape:?}: {}", on.distance);
            for k in 0..3 {
                let e = Vector3::ith(k, eps);
                let (p, m) = (shape.closest(&(x + e)), shape.closest(&(x - e)));
                let g = (p.distance - m.distance) / (2.0 * eps);
                assert!(
                    (g - c.normal[k]).abs() < 1e-6,
                    "{shape:?} at {x:?}: gradient {k}: {} vs fd {g}",
                    c.normal[k]
                );
                let h = (p.normal - m.normal) / (2.0 * eps);
                for i in 0..3 {
                    let want = h[i];
                    let got = c.hessian[(i, k)];
                    assert!(
                        (got - want).abs() < 1e-6 * want.abs().max(1.0),
                        "{shape:?} at {x:?}: hessian ({i},{k}): {got} vs fd {want}"
                    );
                }
            }
            assert!(c.hessian.symmetric_eigen().eigenvalues.min() > -1e-9);
            assert!((c.hessian * c.normal).norm() < 1e-9);
        }
    }
    assert!(checked > 400, "{checked} points checked");
}

/// Known distances: a sphere's, a box's face, edge and corner, a
/// capsule's side and end, a plane's (to 1e-14).
#[test]
fn known_distances() {
    let s = &shapes();
    let d = |k: usize, x: [f64; 3]| s[k].closest(&Vector3::from(x)).distance;
    let b = Shape::Box {
        center: [0.0; 3],
        half_extents: [1.0, 2.0, 3.0],
        rotation: [0.0; 3],
    };
    let db = |x: [f64; 3]| b.closest(&Vector3::from(x)).distance;
    let cases = [
        (d(1, [0.1, 0.2, 0.2]), 0.25),
        (db([1.5, 0.0, 0.0]), 0.5),
        (db([2.0, 3.0, 0.0]), 2f64.sqrt()),
        (db([2.0, 3.0, 4.0]), 3f64.sqrt()),
        (db([0.5, 0.0, 0.0]), -0.5),
        (d(3, [-0.1, 0.0, 0.0]), 0.05),
        (d(0, [0.1, -0.2, 1.05]), 1.0 / (0.09f64 + 0.04 + 1.0).sqrt()),
    ];
    for (k, (got, want)) in cases.into_iter().enumerate() {
        assert!((got - want).abs() < 1e-14, "case {k}: {got} vs {want}");
    }
    // Beside the capsule's segment: its midpoint moved off the axis.
    let mid = Vector3::new(0.15, 0.05, -0.1);
    let off = Vector3::new(0.1, 0.3, 0.0).cross(&Vector3::new(0.3, 0.1, -0.2));
    let x = mid + 0.2 * off.normalize();
    assert!((s[3].closest(&x).distance - 0.15).abs() < 1e-14);
}

#[test]
fn bad_shapes_are_refused() {
    let bad = [
        Shape::Sphere {
            center: [0.0; 3],
            radius: 0.0,
        },
        Shape::HalfSpace {
            point: [0.0; 3],
            normal: [0.0; 3],
        },
        Shape::Box {
            center: [f64::NAN, 0.0, 0.0],
            half_extents: [1.0; 3],
            rotation: [0.0; 3],
        },
        Shape::Capsule {
            ends: [[0.0; 3]; 2],
            radius: -1.0,
        },
    ];
    for s in bad {
        assert!(s.check().is_err(), "{s:?}");
    }
}

/// A sheet that starts within half its thickness of an obstacle is refused
/// at initialization, the obstacle named; the model stays in setup.
#[test]
fn a_sheet_starting_inside_an_obstacle_is_refused_at_initialization() {
    let ground = r#"[{"name": "floor", "shape": "half_space", "point": [0, 0, -0.0004], "normal": [0, 0, 1]}]"#;
    let mut m = Model::new(square([0.0, 0.0, -9.81], ground, "")).unwrap();
    let e = m.initialize().unwrap_err().to_string();
    assert!(
        e.contains("obstacle floor") && e.contains("half the contact thickness"),
        "{e}"
    );
    assert_eq!(m.phase(), origami_fmu::model::Phase::Setup);
}

/// Obstacles and self-contact together: the sheet dropped on the ground
/// with `ancf:contact` on rests on it as without (the ground's force is
/// the weight within 1e-3), the outputs of both are there, and
/// `energy.contact` is the obstacles' barrier energy (positive).
#[test]
fn obstacles_work_with_self_contact_on() {
    let ground = r#"[{"name": "ground", "shape": "half_space", "point": [0, 0, -0.0025], "normal": [0, 0, 1]}]"#;
    let mut m = Model::new(square(
        [0.0, 0.0, -9.81],
        ground,
        r#", "ancf:contact": {"enabled": true}"#,
    ))
    .unwrap();
    m.initialize().unwrap();
    for _ in 0..50 {
        m.advance(0.01).unwrap();
        assert!(m.obstacle_gap().unwrap().0 > 0.0);
    }
    let weight = m.mass_properties().0 * 9.81;
    let f = vector(&m, "ground.force");
    assert!((f.z + weight).abs() < 1e-3 * weight, "{f:?} vs {weight}");
    let e = m.output(m.output_id("energy.contact").unwrap()).unwrap();
    assert!(e > 0.0, "energy.contact {e}");
    assert!(m.output_id("contact.min_gap").is_some());
}

/// The energy balance closes with obstacles: a square dropped on the
/// ground (generalized-alpha without numerical dissipation, rho_inf = 1,
/// no mass damping, tolerance 1e-6 as in tests/contact.rs: the trapezoidal
/// rule's energy error at an impact grows with the step) keeps kinetic + strain + crease + contact energy +
/// dissipated work (the ground's dashpots and friction) - input work
/// (gravity's) within 1 % of the fall's energy m g (2 mm) over its landing
/// and 0.3 s of rest; most of that energy goes to the dashpots.
#[test]
fn the_energy_balance_closes_with_obstacles() {
    let ground = r#"[{"name": "ground", "shape": "half_space", "point": [0, 0, -0.0025], "normal": [0, 0, 1]}]"#;
    let extra = r#", "ancf:solver": {"rho_inf": 1.0, "tolerance": 1e-6}, "ancf:damping": {"alpha": 0, "beta": 0}"#;
    let mut m = Model::new(square([0.0, 0.0, -9.81], ground, extra)).unwrap();
    m.initialize().unwrap();
    let out = |m: &Model, name: &str| m.output(m.output_id(name).unwrap()).unwrap();
    let total = |m: &Model| common::energy_and_dissipated(m) - out(m, "energy.input_work");
    let fall = m.mass_properties().0 * 9.81 * 0.002;
    let e0 = total(&m);
    let mut worst: f64 = 0.0;
    for _ in 0..40 {
        m.advance(0.01).unwrap();
        worst = worst.max((total(&m) - e0).abs());
    }
    let dissipated = out(&m, "energy.dissipated");
    eprintln!(
        "largest drift {:.2e} of m g (2 mm); dissipated {:.3} of it",
        worst / fall,
        dissipated / fall
    );
    assert!(worst < 0.01 * fall, "drift {worst:e} J of {fall:e} J");
    assert!(
        dissipated > 0.5 * fall,
        "dissipated {dissipated:e} J of {fall:e} J"
    );
}

/// The square dropped from 2 mm onto each curved shape under its middle
/// (a ball of radius 0.5 m, a box turned about the vertical whose top is
/// a 0.2 x 0.16 m table, a horizontal rod of radius 0.3 m across it) comes
/// to rest on it: no output with a sample within half the thickness of
/// it, and after 0.5 s the shape's force is the weight pressing down
/// (1e-3 relative) and its moment about the shape's origin that of the
/// weight at the centre of mass (1e-3 of the weight times 0.05 m).
#[test]
fn a_sheet_dropped_on_a_ball_a_table_and_a_rod_rests_on_each() {
    let top = -0.0025;
    let shapes = [
        format!(
            r#"{{"name": "ball", "shape": "sphere", "center": [0.05, 0.05, {}], "radius": 0.5}}"#,
            top - 0.5
        ),
        format!(
            r#"{{"name": "table", "shape": "box", "center": [0.05, 0.05, {}], "half_extents": [0.1, 0.08, 0.05], "rotation": [0, 0, 0.4]}}"#,
            top - 0.05
        ),
        format!(
            r#"{{"name": "rod", "shape": "capsule", "ends": [[0.05, -0.2, {z}], [0.05, 0.3, {z}]], "radius": 0.3}}"#,
            z = top - 0.3
        ),
    ];
    for (shape, name) in shapes.iter().zip(["ball", "table", "rod"]) {
        let mut m = Model::new(square([0.0, 0.0, -9.81], &format!("[{shape}]"), "")).unwrap();
        m.initialize().unwrap();
        let mut steps = 0;
        for _ in 0..50 {
            steps += m.advance(0.01).unwrap().steps;
            let (gap, _, _) = m.obstacle_gap().unwrap();
            assert!(gap > 0.0, "{name}: gap {gap:e} at t = {}", m.time());
        }
        let (mass, c) = m.mass_properties();
        let weight = mass * 9.81;
        let f = vector(&m, &format!("{name}.force"));
        let mom = vector(&m, &format!("{name}.moment"));
        let origin = match name {
            "ball" => Vector3::new(0.05, 0.05, top - 0.5),
            "table" => Vector3::new(0.05, 0.05, top - 0.05),
            _ => Vector3::new(0.05, 0.05, top - 0.3),
        };
        let want = (Vector3::from(c) - origin).cross(&Vector3::new(0.0, 0.0, -weight));
        eprintln!(
            "{name}: {steps} steps; force {f:?} (weight {weight:.6e}); moment {mom:?} (want {want:?})"
        );
        assert!(
            (f - Vector3::new(0.0, 0.0, -weight)).norm() < 1e-3 * weight,
            "{name}: force {f:?}, weight {weight}"
        );
        assert!(
            (mom - want).norm() < 1e-3 * weight * 0.05,
            "{name}: moment {mom:?}, want {want:?}"
        );
    }
}

/// A state saved while the square lands on the ground (pairs in the
/// barrier, their stiffnesses in the state's term memory) continues bit
/// for bit in the same model and in a fresh one; the obstacle term's memory
/// is in the state (pair stiffnesses in threes).
#[test]
fn a_state_on_the_ground_restores_bit_for_bit() {
    let ground = r#"[{"name": "ground", "shape": "half_space", "point": [0, 0, -0.0025], "normal": [0, 0, 1]}]"#;
    let scene = square([0.0, 0.0, -9.81], ground, "");
    let mut a = Model::new(scene.clone()).unwrap();
    a.initialize().unwrap();
    for _ in 0..3 {
        a.advance(0.01).unwrap();
    }
    let saved = a.save_state();
    let memory = saved.term_memory.last().cloned().unwrap_or_default();
    assert!(
        !memory.is_empty() && memory.len() % 3 == 0,
        "obstacle memory {memory:?}"
    );
    common::assert_restores_bit_for_bit(scene, &mut a, &saved, (10, |_: &mut Model| {}));
}

/// Friction stops a Newton correction where it would carry a sample
/// sliding on an obstacle through sticking to sliding the other way, at
/// the fraction where it comes to rest: the square sliding at +2 cm/s on
/// the plane, a correction to -2 cm/s is stopped half-way (within 1e-9), a
/// correction to +1 cm/s is taken whole.
#[test]
fn friction_stops_a_correction_that_would_reverse_a_slide_on_an_obstacle() {
    let plane = Shape::HalfSpace {
        point: [0.0, 0.0, -0.0007],
        normal: [0.0, 0.0, 1.0],
    };
    let (mut asm, q) = assembler_with(plane, 0.5);
    let positions: Vec<usize> = (0..q.len() / 3)
        .filter(|&s| asm.layout.slot_kind[s] == origami_fmu::dofs::SlotKind::Position)
        .collect();
    let along_x = |x: f64| {
        let mut v = vec![0.0; q.len()];
        for &s in &positions {
            v[3 * s] = x;
        }
        v
    };
    let v = along_x(0.02);
    asm.before_step(&q, &v);
    assert!(asm.limits_steps(), "the square is on the plane");
    let back = asm.max_correction_fraction(&q, &v, &along_x(-0.04), 1.0);
    assert!((back - 0.5).abs() < 1e-9, "stopped at {back}");
    let slower = asm.max_correction_fraction(&q, &v, &along_x(-0.01), 1.0);
    assert_eq!(slower, 1.0);
}

/// The collision check: a Newton step that would carry the square 2 mm
/// down into each shape is cut to a fraction at which every contact sample
/// still keeps more than half the thickness from it (the forces evaluate:
/// a sample within it is an error), and a step of 1 um up is taken whole.
#[test]
fn a_step_into_an_obstacle_is_cut_before_the_sheet_reaches_it() {
    for shape in fd_shapes() {
        let (mut asm, q) = assembler_with(shape.clone(), 0.5);
        let zeros = vec![0.0; q.len()];
        asm.before_step(&q, &zeros);
        let mut down = vec![0.0; q.len()];
        let mut up = vec![0.0; q.len()];
        for s in 0..q.len() / 3 {
            if asm.layout.slot_kind[s] == origami_fmu::dofs::SlotKind::Position {
                down[3 * s + 2] = -0.002;
                up[3 * s + 2] = 1e-6;
            }
        }
        let t = asm.max_step_fraction(&q, &down);
        assert!(t > 0.0 && t < 0.5, "{shape:?}: fraction {t}");
        let moved: Vec<f64> = q.iter().zip(&down).map(|(x, d)| x + t * d).collect();
        let ev = eval_at(&asm, &moved, &zeros, None);
        assert!(ev.barrier_pairs > 0, "{shape:?}");
        assert_eq!(asm.max_step_fraction(&q, &up), 1.0, "{shape:?}");
    }
}

/// A gripper pressing a sheet onto a ball: two 50 mm panels (1 mm
/// plastic) clamped along one edge to the attachment `mount`, a ball of
/// radius 20 mm under the free panel, 2 mm below the sheet. The master
/// lowers the mount by 6 mm over 0.3 s (position with its slope), then
/// holds it: the free panel lands on the ball and bends over it; no output
/// has the sheet within half its thickness of the ball, and at rest the
/// forces the sheet exerts on the mount and on the ball add up to its
/// weight (1e-3 relative), the ball carrying part of it.
#[test]
fn a_mount_presses_the_sheet_onto_a_ball() {
    let mut m = Model::new(common::two_plastic_panels(
        r#""ancf:loads": {"gravity": [0, 0, -9.81]},
      "ancf:attachments": [{"name": "mount", "vertices": [0, 5]}],
      "ancf:obstacles": [{"name": "ball", "shape": "sphere", "center": [0.075, 0.025, -0.0225], "radius": 0.02}]"#,
    ))
    .unwrap();
    m.initialize().unwrap();
    let z = m.input_id("mount.z").unwrap();
    let (speed, h) = (-0.02, 0.01);
    for k in 0..60 {
        let t = k as f64 * h;
        if t < 0.3 {
            m.set_input(z, speed * t).unwrap();
            m.set_input_derivative(z, 1, speed).unwrap();
        } else {
            m.set_input(z, speed * 0.3).unwrap();
        }
        m.advance(h).unwrap();
        let (gap, _, _) = m.obstacle_gap().unwrap();
        assert!(gap > 0.0, "gap {gap:e} at t = {}", m.time());
    }
    let weight = m.mass_properties().0 * 9.81;
    let mount = vector(&m, "mount.force");
    let ball = vector(&m, "ball.force");
    let total = mount + ball;
    eprintln!("mount {mount:?}, ball {ball:?}, weight {weight:e}");
    assert!(
        ball.z < -0.1 * weight,
        "the ball carries part of it: {ball:?}"
    );
    assert!(
        (total - Vector3::new(0.0, 0.0, -weight)).norm() < 1e-3 * weight,
        "mount {mount:?} + ball {ball:?} vs weight {weight}"
    );
}
