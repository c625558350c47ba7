//! The checked-in example FMU descriptions must match the generator.
//!
//! For every example scene this test regenerates
//! - `tests/fmpy/scenes/<name>.json`: the scene file the fmpy suite builds
//!   FMUs from (exactly the bytes that go into the FMU's resources), and
//! - `modelDescription/<name>.xml`: the generated modelDescription.xml,
//!
//! and fails when they differ from the files in the repository. After an
//! intended change, regenerate them with
//! `UPDATE_MODEL_DESCRIPTIONS=1 cargo test --test model_description`
//! and review the diff.

use nalgebra::Vector2;
use origami_fmu::contact::ContactSettings;
use origami_fmu::fmi::{self, resources::scene_bytes};
use origami_fmu::ids::{EdgeId, FoldEdgeId, VertexId, vertex_ids};
use origami_fmu::mesh::{Edge, Mesh, builders};
use origami_fmu::scene::{
    Actuator, ActuatorMode, Attachment, CreaseStiffness, Fix, Scene, Support, VertexInput,
};
use std::f64::consts::PI;
use std::path::Path;

/// Tag every mesh edge with its own index as FOLD edge (the examples are
/// built without a FOLD file), so creases get `crease[e].angle` outputs.
fn tag_fold_edges(mut s: Scene) -> Scene {
    for e in s.mesh.edge_ids() {
        s.mesh.set_fold_edge(e, Some(FoldEdgeId::of_mesh_edge(e)));
    }
    s.fold_edge_count = s.mesh.edges().len();
    s
}

/// One crease along the diagonal of a 0.1 m paper square, all defaults.
/// A free-floating square with a diagonal crease and no damping at all (the
/// energy-conservation test of the fmpy suite runs on it).
fn square() -> Scene {
    let mut s = tag_fold_edges(Scene::with_defaults(
        "square",
        builders::square_with_diagonal(0.1, true, PI / 2.0),
    ));
    s.auto_damping = false;
    s
}

/// A 0.2 m x 0.05 m strip clamped at its left end with a crease across the
/// middle, gravity and a force input at the free corner: every kind of
/// variable.
fn strip() -> Scene {
    let mesh = builders::grid(0.2, 0.05, 4, 1, &[(2, PI / 2.0)]);
    let mut s = tag_fold_edges(Scene::with_defaults("strip", mesh));
    s.supports.push(Support {
        vertices: vec![VertexId(0), VertexId(5)],
        fix: Fix::Clamped,
    });
    s.gravity = Some([0.0, 0.0, -9.81]);
    s.vertex_forces.push(VertexInput {
        name: "tip".into(),
        vertex: VertexId(4),
    });
    s.damping.crease = 1e-4;
    s
}

/// docs/validation.md case C: two 1 mm thick triangular panels on one crease of
/// stiffness 1e-3 N/rad per metre, panel 0 held (vertex 1 clamped, the
/// crease ends pinned), a torque input per unit crease length, damped near
/// critically (period about 1 s). Static angle = torque / 1e-3.
fn case_c() -> Scene {
    let mut s = tag_fold_edges(Scene::with_defaults(
        "case_c",
        builders::square_with_diagonal(0.1, true, PI / 2.0),
    ));
    s.material.thickness = 1e-3;
    s.crease = CreaseStiffness::PerLength(1e-3);
    s.damping.crease = 3e-4;
    s.actuators = vec![Actuator {
        name: "torque".into(),
        edges: vec![EdgeId(0)],
        mode: ActuatorMode::Torque,
        start: 0.0,
    }];
    s.supports = vec![
        Support {
            vertices: vec![VertexId(1)],
            fix: Fix::Clamped,
        },
        Support {
            vertices: vec![VertexId(0), VertexId(2)],
            fix: Fix::Position,
        },
    ];
    s.solver.stop_time = 5.0;
    s
}

/// Case C with internal step cutting disabled (min_step = max_step = 1 ms):
/// a violent torque input makes a step fail (fmi2Discard) where a shorter
/// communication step succeeds. For the forced-failure test.
fn case_c_nocut() -> Scene {
    let mut s = case_c();
    s.name = "case_c_nocut".into();
    s.solver.max_step = 1e-3;
    s.solver.min_step = s.solver.max_step;
    s
}

/// One degree-4 Miura-ori vertex (sector angle 60 degrees, creases 50 mm)
/// with rigid-foldable targets: the straight crease line at +60 / -60
/// degrees, the zig-zag pair at -2 atan(tan(30 deg) / cos(60 deg)).
fn miura() -> Scene {
    let (l, a) = (0.05, PI / 3.0);
    let (s_, c_) = (a.sin(), a.cos());
    let p = |x: f64, y: f64| Vector2::new(l * x, l * y);
    let coords = vec![
        p(-s_, c_ - 1.0),
        p(0.0, -1.0),
        p(s_, c_ - 1.0),
        p(-s_, c_),
        p(0.0, 0.0),
        p(s_, c_),
        p(-s_, c_ + 1.0),
        p(0.0, 1.0),
        p(s_, c_ + 1.0),
    ];
    let tris = vec![
        [0, 1, 4],
        [0, 4, 3],
        [1, 2, 5],
        [1, 5, 4],
        [3, 4, 7],
        [3, 7, 6],
        [4, 5, 8],
        [4, 8, 7],
    ];
    let straight = PI / 3.0;
    let zigzag = -2.0 * ((straight / 2.0).tan() / c_).atan();
    let edges = vec![
        Edge::crease(VertexId(4), VertexId(7), straight),
        Edge::crease(VertexId(4), VertexId(1), -straight),
        Edge::crease(VertexId(4), VertexId(5), zigzag),
        Edge::crease(VertexId(4), VertexId(3), zigzag),
    ];
    let tris = tris.into_iter().map(vertex_ids).collect();
    let mesh = Mesh::new(coords, tris, edges).expect("valid Miura vertex");
    let mut s = tag_fold_edges(Scene::with_defaults("miura", mesh));
    s.auto_damping = false;
    s.damping.alpha = 20.0;
    s.damping.crease = 1e-4;
    s.solver.stop_time = 2.0;
    s
}

/// The contact test of the fmpy suite (tests/contact.rs's diagonal folded
/// flat): a 0.1 m square with a valley crease along the diagonal 0-2 to
/// 180 degrees, the corner off the diagonal at vertex 1 clamped, a 0.5 mm
/// sheet, self-contact without friction, automatic damping.
fn diagonal_contact() -> Scene {
    let mut s = tag_fold_edges(Scene::with_defaults(
        "diagonal_contact",
        builders::square_with_diagonal(0.1, true, PI),
    ));
    s.material.thickness = 5e-4;
    s.supports.push(Support {
        vertices: vec![VertexId(1)],
        fix: Fix::Clamped,
    });
    s.contact = Some(ContactSettings {
        friction: 0.0,
        ..s.default_contact()
    });
    s
}

/// The strip of `strip()` spanning between a wall and a robot's gripper:
/// clamped to a support at its left end, its right end (vertices 4 and 9)
/// attached to the frame `mount`, with gravity and the reaction outputs:
/// the attachment's inputs and wrench, the support's reaction.
fn bridge() -> Scene {
    let mesh = builders::grid(0.2, 0.05, 4, 1, &[(2, PI / 2.0)]);
    let mut s = tag_fold_edges(Scene::with_defaults("bridge", mesh));
    s.material.thickness = 5e-4;
    s.supports.push(Support {
        vertices: vec![VertexId(0), VertexId(5)],
        fix: Fix::Clamped,
    });
    s.attachments.push(Attachment {
        name: "mount".into(),
        vertices: vec![VertexId(4), VertexId(9)],
    });
    s.gravity = Some([0.0, 0.0, -9.81]);
    s.outputs.reactions = true;
    s
}

/// A 0.1 m square of 0.5 mm paper (800 kg/m^3) dropped under gravity on
/// the ground `ground`, a half-space 2.5 mm below it (friction 0.3): the
/// obstacle's wrench outputs and the obstacles' energies.
fn ground() -> Scene {
    let mesh = builders::grid(0.1, 0.1, 1, 1, &[]);
    let mut s = tag_fold_edges(Scene::with_defaults("ground", mesh));
    s.material.thickness = 5e-4;
    s.material.density = 800.0;
    s.gravity = Some([0.0, 0.0, -9.81]);
    s.obstacles.push(origami_fmu::contact::Obstacle {
        name: "ground".into(),
        shape: origami_fmu::contact::Shape::HalfSpace {
            point: [0.0, 0.0, -0.0025],
            normal: [0.0, 0.0, 1.0],
        },
        friction: 0.3,
        moving: false,
    });
    s
}

/// The same square resting on a moving ground (`"moving": true`, friction
/// 0.3), its plane 0.26 mm below the sheet's midsurface (in the barrier):
/// the obstacle's pose inputs `ground.x/y/z/rx/ry/rz`; no numerical
/// dissipation, no damping and a tight tolerance (its energy balance is
/// tested).
fn conveyor() -> Scene {
    let mut s = ground();
    s.name = "conveyor".into();
    s.obstacles[0].moving = true;
    // Energy-conserving and tight: its test checks the energy balance.
    s.solver.rho_inf = 1.0;
    s.solver.tolerance = 1e-6;
    s.auto_damping = false;
    s.obstacles[0].shape = origami_fmu::contact::Shape::HalfSpace {
        point: [0.0, 0.0, -0.00026],
        normal: [0.0, 0.0, 1.0],
    };
    s
}

fn examples() -> Vec<Scene> {
    vec![
        square(),
        strip(),
        case_c(),
        case_c_nocut(),
        miura(),
        diagonal_contact(),
        bridge(),
        ground(),
        conveyor(),
    ]
}

fn check(path: &Path, want: &[u8], update: bool, drift: &mut Vec<String>) {
    let have = std::fs::read(path).unwrap_or_default();
    if have != want {
        if update {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, want).unwrap();
        } else {
            drift.push(path.display().to_string());
        }
    }
}

#[test]
fn checked_in_model_descriptions_match_the_generator() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let update = std::env::var_os("UPDATE_MODEL_DESCRIPTIONS").is_some();
    let mut drift = Vec::new();
    for scene in examples() {
        let c = fmi::fmu_contents(&scene).expect("example scenes are valid");
        let name = &scene.name;
        check(
            &root.join(format!("tests/fmpy/scenes/{name}.json")),
            &scene_bytes(&scene),
            update,
            &mut drift,
        );
        check(
            &root.join(format!("modelDescription/{name}.xml")),
            c.model_description.as_bytes(),
            update,
            &mut drift,
        );
    }
    // The shipped example scenes (scenes/*.fold) too.
    let mut shipped: Vec<_> = std::fs::read_dir(root.join("scenes"))
        .expect("scenes/ exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "fold"))
        .collect();
    shipped.sort();
    assert!(shipped.len() >= 5, "expected the shipped example scenes");
    for path in shipped {
        let (scene, _) = origami_fmu::scene::load(&path).expect("shipped scenes load");
        let c = fmi::fmu_contents(&scene).expect("shipped scenes are valid");
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        check(
            &root.join(format!("modelDescription/{stem}.xml")),
            c.model_description.as_bytes(),
            update,
            &mut drift,
        );
    }
    assert!(
        drift.is_empty(),
        "generated files differ from the checked-in ones: {drift:?}\n\
         regenerate with `UPDATE_MODEL_DESCRIPTIONS=1 cargo test --test model_description` and review the diff"
    );
}

#[test]
fn model_description_has_the_required_structure() {
    let c = fmi::fmu_contents(&strip()).unwrap();
    let x = &c.model_description;
    for needle in [
        r#"fmiVersion="2.0""#,
        r#"variableNamingConvention="structured""#,
        r#"modelIdentifier="origami_fmu""#,
        r#"canHandleVariableCommunicationStepSize="true""#,
        r#"canGetAndSetFMUstate="true""#,
        r#"canSerializeFMUstate="true""#,
        r#"canNotUseMemoryManagementFunctions="true""#,
        r#"<Unit name="m"><BaseUnit m="1"/></Unit>"#,
        r#"<Unit name="J"><BaseUnit kg="1" m="2" s="-2"/></Unit>"#,
        r#"name="material.youngs_modulus" valueReference="0""#,
        r#"causality="parameter" variability="fixed" initial="exact"><Real unit="Pa" start="3e9"/>"#,
        r#"name="fold" valueReference="#,
        r#"name="tip.z""#,
        r#"name="vertex[4].x""#,
        r#"name="crease[0].angle""#,
        r#"name="energy.crease""#,
        r#"<DefaultExperiment startTime="0" stopTime="1" tolerance="1e-4" stepSize="0.01"/>"#,
        &format!(r#"guid="{}""#, c.guid),
    ] {
        assert!(x.contains(needle), "missing {needle}\n{x}");
    }
    // every output listed once in Outputs and in InitialUnknowns
    let n_out = x.matches(r#"causality="output""#).count();
    // Only the crease energy feeds through: it depends on the rest-angle
    // actuator `fold` (read under the rest angles in force), the rest on no input.
    assert_eq!(x.matches(r#"dependencies="""#).count(), n_out - 1);
    let vr: usize = x.split(r#"name="fold" valueReference=""#).nth(1).unwrap()[..]
        .split('"')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let crease_energy = x
        .lines()
        .position(|l| l.contains(r#"name="energy.crease""#))
        .unwrap();
    let index: usize = x
        .lines()
        .nth(crease_energy - 1)
        .unwrap()
        .trim()
        .trim_start_matches("<!-- index ")
        .trim_end_matches(" -->")
        .parse()
        .unwrap();
    assert!(
        x.contains(&format!(
            r#"<Unknown index="{index}" dependencies="{}"/>"#,
            vr + 1
        )),
        "{x}"
    );
    assert_eq!(x.matches("<Unknown ").count(), 2 * n_out);
}
