//! The `ancf:` physics (material, damping, actuators, supports, loads,
//! solver, outputs) checked against the mesh and set on the scene.

use super::edges::FoldEdges;
use super::{invalid, vertex_exists};
use crate::ids::{EdgeId, FoldEdgeId, VertexId};
use crate::mesh::EdgeKind;
use crate::scene::error::SceneError;
use crate::scene::keys::{self, EdgeSelection};
use crate::scene::{ActuatorMode, Attachment, Damping, Scene, Support};
use std::collections::HashMap;

/// Material, damping, actuators, supports, loads, solver and outputs,
/// checked against the mesh. `contact`: self-contact on whatever the
/// file's `enabled` says (with its settings, else the defaults).
pub(super) fn apply_physics(
    scene: &mut Scene,
    mut p: keys::PhysicsKeys,
    edges: &FoldEdges,
    copies: &[usize],
    contact: bool,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let nv = scene.fold_vertex_count;
    scene.material = p.material;
    scene.crease = p.crease;
    let (alpha, beta) = p.damping.unwrap_or((0.0, 0.0));
    scene.damping = Damping {
        alpha,
        beta,
        crease: p.crease_damping.unwrap_or(0.0),
    };
    scene.auto_damping = p.damping.is_none();
    scene.actuator_time_constant = p.actuator_time_constant;
    scene.gravity = p.gravity;
    let on = contact || p.contact_enabled;
    scene.contact = on.then(|| p.contact.unwrap_or_default()).map(|mut c| {
        if c.thickness == 0.0 {
            c.thickness = p.material.thickness;
        }
        c
    });
    scene.solver = p.solver;
    scene.outputs = p.outputs;

    let stages = p.sequence.take();
    if stages.is_some() && p.actuators.is_none() {
        // The sequence's own actuator replaces the default `fold`.
        scene.actuators.clear();
    } else {
        apply_actuators(scene, p.actuators.take(), edges, warnings)?;
    }
    if let Some(stages) = stages {
        super::sequence::apply_sequence(scene, stages, edges, warnings)?;
    }
    let supported = apply_supports(scene, p.supports, nv, copies)?;
    for (vi, key) in &p.vertex_forces {
        let k = format!("{key}.vertex");
        vertex_exists(vi.vertex.index(), nv, || k.clone())?;
        if let Some(s) = supported.get(&vi.vertex.index()) {
            warnings.push(format!(
                "{k}: vertex {} is fixed by {s}; the force '{}' acts on a support",
                vi.vertex, vi.name
            ));
        }
    }
    let mut driven: HashMap<VertexId, String> = HashMap::new();
    for (vi, key) in &p.vertex_motions {
        let k = format!("{key}.vertex");
        vertex_exists(vi.vertex.index(), nv, || k.clone())?;
        if let Some(s) = supported.get(&vi.vertex.index()) {
            return Err(invalid(
                k,
                format!(
                    "vertex {} is also fixed by {s}; a vertex cannot be both supported and driven",
                    vi.vertex
                ),
            ));
        }
        if let Some(first) = driven.insert(vi.vertex, key.clone()) {
            return Err(invalid(
                k,
                format!("vertex {} is already driven by {first}", vi.vertex),
            ));
        }
    }
    let attached = check_attachments(&p.attachments, nv, &supported, &driven)?;
    for (vi, key) in &p.vertex_forces {
        if let Some(a) = attached.get(&vi.vertex.index()) {
            warnings.push(format!(
                "{key}.vertex: vertex {} is held by {a}; the force '{}' acts on the attachment",
                vi.vertex, vi.name
            ));
        }
    }
    scene.attachments = p
        .attachments
        .into_iter()
        .map(|a| Attachment {
            name: a.name,
            vertices: with_copies(&a.vertices, nv, copies),
        })
        .collect();
    // An obstacle's friction: its own, else the contact's (given, even
    // with self-contact off), else the contact default.
    let friction = p
        .contact_friction
        .unwrap_or(crate::contact::ContactSettings::default().friction);
    scene.obstacles = p
        .obstacles
        .into_iter()
        .map(|o| crate::contact::Obstacle {
            friction: o.friction.unwrap_or(friction),
            ..o.obstacle
        })
        .collect();
    scene.vertex_forces = p.vertex_forces.into_iter().map(|x| x.0).collect();
    scene.vertex_motions = p.vertex_motions.into_iter().map(|x| x.0).collect();
    Ok(())
}

/// The scene's actuators from the `ancf:actuators` specs (None: the
/// default `fold` over every crease), with warnings for actuators that
/// drive nothing.
fn apply_actuators(
    scene: &mut Scene,
    actuators: Option<Vec<keys::ActuatorSpec>>,
    edges: &FoldEdges,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let creases = edges.creases();
    let zero = |list: &[usize]| list.iter().all(|&e| edges.target[e] == 0.0);
    match actuators {
        None => {
            // with_defaults made `fold` over every mesh crease (= FOLD creases).
            if creases.is_empty() {
                warnings.push(
                    "the pattern has no creases; the default actuator 'fold' drives nothing"
                        .to_string(),
                );
            } else if zero(&creases) {
                warnings.push(format!(
                    "the default actuator 'fold' drives nothing: all {} creases have the target \
                     0 (U or F edges without edges_foldAngle); give the creases M/V assignments \
                     or edges_foldAngle, or drive them with a torque actuator (ancf:actuators)",
                    creases.len()
                ));
            }
        }
        Some(list) => {
            let mut rest_owner: HashMap<usize, (String, String)> = HashMap::new();
            scene.actuators.clear();
            for a in list {
                let sel_key = format!("{}.edges", a.key);
                let selected = select_edges(&a.edges, &sel_key, &creases, edges, warnings)?;
                if a.mode == ActuatorMode::RestAngle && !selected.is_empty() && zero(&selected) {
                    warnings.push(format!(
                        "{sel_key}: every crease the rest_angle actuator '{}' drives has the \
                         target 0, so it drives nothing; give them edges_foldAngle, or use \
                         \"mode\": \"torque\"",
                        a.name
                    ));
                }
                if a.mode == ActuatorMode::RestAngle {
                    for &e in &selected {
                        if let Some((name, key)) = rest_owner.get(&e) {
                            return Err(invalid(
                                sel_key,
                                format!(
                                    "FOLD edge {e} is already driven by the rest_angle actuator \
                                     '{name}' ({key}); a crease can follow only one rest angle"
                                ),
                            ));
                        }
                        rest_owner.insert(e, (a.name.clone(), a.key.clone()));
                    }
                }
                scene.actuators.push(crate::scene::Actuator {
                    name: a.name,
                    edges: selected
                        .into_iter()
                        .map(|e| EdgeId::of_fold_edge(FoldEdgeId(e)))
                        .collect(),
                    mode: a.mode,
                    start: a.start,
                });
            }
        }
    }
    Ok(())
}

/// The FOLD creases an actuator's edge selection picks (checked: they
/// exist, are creases and are listed once).
pub(super) fn select_edges(
    selection: &EdgeSelection,
    sel_key: &str,
    creases: &[usize],
    edges: &FoldEdges,
    warnings: &mut Vec<String>,
) -> Result<Vec<usize>, SceneError> {
    let ne = edges.v.len();
    Ok(match selection {
        EdgeSelection::All => {
            if creases.is_empty() {
                warnings.push(format!(
                    "{sel_key}: \"all\" selects nothing; the pattern has no creases"
                ));
            }
            creases.to_vec()
        }
        EdgeSelection::Assignment(x) => {
            let s: Vec<usize> = creases
                .iter()
                .copied()
                .filter(|&e| edges.assignment[e] == *x)
                .collect();
            if s.is_empty() {
                warnings.push(format!(
                    "{sel_key}: no crease has assignment {}; the actuator drives nothing",
                    x.letter()
                ));
            }
            s
        }
        EdgeSelection::List(l) => {
            let mut s = Vec::with_capacity(l.len());
            for (i, &e) in l.iter().enumerate() {
                let k = format!("{sel_key}[{i}]");
                if e >= ne {
                    return Err(invalid(
                        k,
                        format!("FOLD edge {e} does not exist (there are {ne} edges)"),
                    ));
                }
                if edges.kind[e] != EdgeKind::Crease {
                    return Err(invalid(
                        k,
                        format!(
                            "FOLD edge {e} is not a crease (assignment {}{})",
                            edges.assignment[e].letter(),
                            if edges.kind[e] == EdgeKind::Boundary {
                                ", on the boundary"
                            } else {
                                ""
                            }
                        ),
                    ));
                }
                if s.contains(&e) {
                    return Err(invalid(k, format!("FOLD edge {e} is listed twice")));
                }
                s.push(e);
            }
            s
        }
    })
}

/// The supports, each vertex supported once; returns who supports each
/// FOLD vertex.
fn apply_supports(
    scene: &mut Scene,
    supports: Vec<keys::SupportSpec>,
    nv: usize,
    copies: &[usize],
) -> Result<HashMap<usize, String>, SceneError> {
    let mut supported: HashMap<usize, String> = HashMap::new();
    for s in supports {
        for (i, &v) in s.vertices.iter().enumerate() {
            let k = format!("{}.vertices[{i}]", s.key);
            vertex_exists(v, nv, || k.clone())?;
            if let Some(first) = supported.get(&v) {
                return Err(invalid(
                    k,
                    format!("vertex {v} is already supported by {first}"),
                ));
            }
            supported.insert(v, s.key.clone());
        }
        // A support on a split vertex holds all its copies.
        scene.supports.push(Support {
            vertices: with_copies(&s.vertices, nv, copies),
            fix: s.fix,
        });
    }
    Ok(supported)
}

/// Each attached vertex exists and is held by nothing else; returns who
/// holds each FOLD vertex.
fn check_attachments(
    attachments: &[keys::AttachmentSpec],
    nv: usize,
    supported: &HashMap<usize, String>,
    driven: &HashMap<VertexId, String>,
) -> Result<HashMap<usize, String>, SceneError> {
    let mut attached: HashMap<usize, String> = HashMap::new();
    for a in attachments {
        for (i, &v) in a.vertices.iter().enumerate() {
            let k = format!("{}.vertices[{i}]", a.key);
            vertex_exists(v, nv, || k.clone())?;
            let taken = supported
                .get(&v)
                .map(|s| format!("supported by {s}"))
                .or_else(|| {
                    driven
                        .get(&VertexId::of_fold_vertex(v))
                        .map(|m| format!("driven by {m}"))
                })
                .or_else(|| attached.get(&v).map(|o| format!("attached by {o}")));
            if let Some(by) = taken {
                return Err(invalid(
                    k,
                    format!("vertex {v} is already {by}; a vertex can be held by one only"),
                ));
            }
            attached.insert(v, a.key.clone());
        }
    }
    Ok(attached)
}

/// The mesh vertices of the FOLD vertices `listed` and of all their split
/// copies (copy `j` is mesh vertex `nv + j`, a copy of FOLD vertex `copies[j]`).
fn with_copies(listed: &[usize], nv: usize, copies: &[usize]) -> Vec<VertexId> {
    let mut vertices: Vec<VertexId> = listed
        .iter()
        .map(|&v| VertexId::of_fold_vertex(v))
        .collect();
    if !copies.is_empty() {
        let held: std::collections::HashSet<usize> = listed.iter().copied().collect();
        vertices.extend(
            copies
                .iter()
                .enumerate()
                .filter(|(_, v)| held.contains(v))
                .map(|(j, _)| VertexId(nv + j)),
        );
    }
    vertices
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{base, err, load, with};
    use crate::ids::{EdgeId, VertexId};
    use crate::scene::Fix;
    use serde_json::json;

    #[test]
    fn physics_against_the_mesh() {
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "a", "edges": [7]}]),
        );
        let e = err(&v, "ancf:actuators[0].edges[0]");
        assert!(e.contains("does not exist"), "{e}");
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "a", "edges": [0]}]),
        );
        let e = err(&v, "ancf:actuators[0].edges[0]");
        assert!(e.contains("not a crease (assignment B"), "{e}");
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "a"}, {"name": "b", "edges": "V"}]),
        );
        let e = err(&v, "ancf:actuators[1].edges");
        assert!(
            e.contains("already driven by the rest_angle actuator 'a'"),
            "{e}"
        );
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "a"}, {"name": "t", "edges": [6], "mode": "torque"}]),
        );
        let (s, _) = load(&v).unwrap();
        assert_eq!(s.actuators.len(), 2);
        assert_eq!(s.actuators[1].edges, vec![EdgeId(6)]);
        let v = with(
            base(),
            "ancf:actuators",
            json!([{"name": "m", "edges": "M"}]),
        );
        let (s, w) = load(&v).unwrap();
        assert!(s.actuators[0].edges.is_empty());
        assert!(w[0].contains("no crease has assignment M"), "{w:?}");
        let v = with(base(), "ancf:actuators", json!([]));
        let (s, _) = load(&v).unwrap();
        assert!(s.actuators.is_empty());

        let v = with(base(), "ancf:supports", json!([{"vertices": [0, 6]}]));
        let e = err(&v, "ancf:supports[0].vertices[1]");
        assert!(e.contains("vertex 6 does not exist"), "{e}");
        let v = with(
            base(),
            "ancf:supports",
            json!([{"vertices": [0]}, {"vertices": [5, 0], "fix": "clamped"}]),
        );
        let e = err(&v, "ancf:supports[1].vertices[1]");
        assert!(e.contains("already supported by ancf:supports[0]"), "{e}");
        let v = with(
            base(),
            "ancf:supports",
            json!([{"vertices": [0, 5], "fix": "clamped"}]),
        );
        let v = with(v, "ancf:motions", json!([{"name": "grip", "vertex": 5}]));
        let e = err(&v, "ancf:motions[0].vertex");
        assert!(e.contains("both supported and driven"), "{e}");
        let v = with(
            v,
            "ancf:motions",
            json!([{"name": "grip", "vertex": 3}, {"name": "g2", "vertex": 3}]),
        );
        err(&v, "ancf:motions[1].vertex");
        let v = with(v, "ancf:motions", json!([{"name": "grip", "vertex": 3}]));
        let v = with(
            v,
            "ancf:loads",
            json!({"gravity": [0, 0, -9.81], "vertex_forces": [{"name": "push", "vertex": 0}]}),
        );
        let (s, w) = load(&v).unwrap();
        assert!(w[0].contains("acts on a support"), "{w:?}");
        assert_eq!(s.supports[0].fix, Fix::Clamped);
        assert_eq!(s.vertex_motions[0].vertex, VertexId(3));
        assert_eq!(s.vertex_forces[0].name, "push");
        assert_eq!(s.gravity, Some([0.0, 0.0, -9.81]));
        let m = crate::model::Model::new(s).unwrap();
        let names: Vec<&str> = m.inputs().iter().map(|x| x.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "fold", "push.x", "push.y", "push.z", "grip.x", "grip.y", "grip.z"
            ]
        );
        let v = with(
            base(),
            "ancf:loads",
            json!({"vertex_forces": [{"name": "p", "vertex": 60}]}),
        );
        err(&v, "ancf:loads.vertex_forces[0].vertex");
    }

    /// `ancf:attachments`: names join the input names, vertices must
    /// exist and be held by nothing else (support, motion, another
    /// attachment); a force on an attached vertex is a warning; the model
    /// gets the pose inputs (the origin starting at the centroid) and the
    /// wrench outputs.
    #[test]
    fn attachments_against_the_mesh() {
        let a = |list: serde_json::Value| with(base(), "ancf:attachments", list);
        let e = err(
            &a(json!([{"name": "m", "vertices": [0, 9]}])),
            "ancf:attachments[0].vertices[1]",
        );
        assert!(e.contains("vertex 9 does not exist"), "{e}");
        err(
            &a(json!([{"name": "m", "vertices": []}])),
            "ancf:attachments[0].vertices",
        );
        err(
            &a(json!([{"name": "vertex", "vertices": [0]}])),
            "ancf:attachments[0].name",
        );
        let e = err(
            &a(json!([{"name": "m", "vertices": [0, 5]}, {"name": "n", "vertices": [5]}])),
            "ancf:attachments[1].vertices[0]",
        );
        assert!(e.contains("already attached by ancf:attachments[0]"), "{e}");
        let v = with(
            a(json!([{"name": "m", "vertices": [0]}])),
            "ancf:supports",
            json!([{"vertices": [0]}]),
        );
        let e = err(&v, "ancf:attachments[0].vertices[0]");
        assert!(e.contains("supported by ancf:supports[0]"), "{e}");
        let v = with(
            a(json!([{"name": "m", "vertices": [2]}])),
            "ancf:motions",
            json!([{"name": "m2", "vertex": 2}]),
        );
        let e = err(&v, "ancf:attachments[0].vertices[0]");
        assert!(e.contains("driven by ancf:motions[0]"), "{e}");
        let v = with(
            a(json!([{"name": "grip", "vertices": [2]}])),
            "ancf:motions",
            json!([{"name": "grip", "vertex": 3}]),
        );
        let e = err(&v, "ancf:attachments[0].name");
        assert!(e.contains("already used"), "{e}");
        let v = with(
            a(json!([{"name": "m", "vertices": [0, 5]}])),
            "ancf:loads",
            json!({"vertex_forces": [{"name": "push", "vertex": 5}]}),
        );
        let (s, w) = load(&v).unwrap();
        assert!(
            w.iter().any(|w| w.contains("acts on the attachment")),
            "{w:?}"
        );
        assert_eq!(s.attachments[0].vertices, vec![VertexId(0), VertexId(5)]);
        let m = crate::model::Model::new(s).unwrap();
        let inputs: Vec<(&str, f64)> = m
            .inputs()
            .iter()
            .map(|x| (x.name.as_str(), x.start))
            .collect();
        assert_eq!(
            &inputs[4..],
            [
                ("m.x", 0.0),
                ("m.y", 0.5),
                ("m.z", 0.0),
                ("m.rx", 0.0),
                ("m.ry", 0.0),
                ("m.rz", 0.0)
            ]
        );
        let outputs: Vec<&str> = m.outputs().iter().map(|x| x.name.as_str()).collect();
        let n = outputs.len();
        assert_eq!(
            &outputs[n - 6..],
            [
                "m.force.x",
                "m.force.y",
                "m.force.z",
                "m.moment.x",
                "m.moment.y",
                "m.moment.z"
            ]
        );
    }

    /// The `reactions` output group: each support's force (and moment where
    /// it holds one) and each motion's force, after everything else.
    #[test]
    fn reaction_outputs_are_asked_for() {
        let v = with(
            base(),
            "ancf:supports",
            json!([{"vertices": [0, 5], "fix": "clamped"}, {"vertices": [3]}]),
        );
        let v = with(v, "ancf:motions", json!([{"name": "grip", "vertex": 2}]));
        let (s, _) = load(&v).unwrap();
        let plain = crate::model::Model::new(s).unwrap().outputs().len();
        let (s, _) = load(&with(v, "ancf:outputs", json!(["energies", "reactions"]))).unwrap();
        let m = crate::model::Model::new(s).unwrap();
        let names: Vec<&str> = m.outputs().iter().map(|x| x.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "energy.kinetic",
                "energy.strain",
                "energy.crease",
                "energy.input_work",
                "energy.dissipated",
                "support[0].force.x",
                "support[0].force.y",
                "support[0].force.z",
                "support[0].moment.x",
                "support[0].moment.y",
                "support[0].moment.z",
                "support[1].force.x",
                "support[1].force.y",
                "support[1].force.z",
                "grip.force.x",
                "grip.force.y",
                "grip.force.z",
            ]
        );
        assert!(plain > 3, "the default groups");
    }

    #[test]
    fn damping_and_material_keys() {
        let v = with(base(), "ancf:damping", json!({"alpha": 2.0}));
        let (s, _) = load(&v).unwrap();
        assert!(!s.auto_damping);
        assert_eq!((s.damping.alpha, s.damping.beta), (2.0, 0.0));
        let v = with(
            base(),
            "ancf:crease",
            json!({"length_scale": 0.02, "damping_per_length": 1e-4}),
        );
        let (s, _) = load(&v).unwrap();
        assert!(s.auto_damping);
        assert_eq!(s.damping.crease, 1e-4);
        let e = err(
            &with(base(), "ancf:material", json!({"thickness": -1})),
            "ancf:material.thickness",
        );
        assert!(e.contains("positive"), "{e}");
        let e = err(
            &with(base(), "ancf:material", json!({"poisson_ratio": 0.7})),
            "ancf:material.poisson_ratio",
        );
        assert!(e.contains("(-1, 0.5)"), "{e}");
        err(
            &with(base(), "ancf:material", json!({"youngs_modulus": 0})),
            "ancf:material.youngs_modulus",
        );
        err(
            &with(base(), "ancf:material", json!({"density": 0})),
            "ancf:material.density",
        );
        let (_, w) = load(&with(base(), "ancf:material", json!({"thickness": 0.2}))).unwrap();
        assert!(w[0].contains("thin-shell"), "{w:?}");
        let e = err(&with(base(), "ancf:stiffness", json!({})), "ancf:stiffness");
        assert!(e.contains("unknown key"), "{e}");
        let (s, _) = load(&with(base(), "ancf:name", json!("pair"))).unwrap();
        assert_eq!(s.name, "pair");
        let (s, _) = load(&with(base(), "file_title", json!("titled"))).unwrap();
        assert_eq!(s.name, "titled");
    }
}
