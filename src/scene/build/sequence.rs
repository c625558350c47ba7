//! `ancf:sequence` (or a file's keyframes) checked against the pattern:
//! each stage's creases selected, its targets in radians, the shares, and
//! the actuator that walks the stages.

use super::edges::FoldEdges;
use super::invalid;
use super::physics::select_edges;
use crate::ids::{EdgeId, FoldEdgeId};
use crate::scene::error::SceneError;
use crate::scene::keys::{EdgeSelection, StageSpec, StageTarget};
use crate::scene::sequence::{INPUT, MAX_TARGETS, Sequence, Stage};
use crate::scene::{Actuator, ActuatorMode, Scene};
use crate::text::num;
use std::collections::{BTreeSet, HashMap};

/// Resolve the stages against the FOLD edges and set the sequence and its
/// actuator (`fold`, the first input) on the scene. Errors name the stage:
/// a selection of no crease, edges that are not creases, targets beyond
/// +-180 degrees, a crease another rest-angle actuator drives.
pub(super) fn apply_sequence(
    scene: &mut Scene,
    specs: Vec<StageSpec>,
    edges: &FoldEdges,
    warnings: &mut Vec<String>,
) -> Result<(), SceneError> {
    let creases = edges.creases();
    // Who else drives a crease's rest angle (FOLD edge e is mesh edge e
    // before refinement).
    let mut owner: HashMap<usize, String> = HashMap::new();
    for (i, a) in scene.actuators.iter().enumerate() {
        if a.name == INPUT {
            return Err(invalid(
                format!("ancf:actuators[{i}].name"),
                format!(
                    "ancf:sequence drives the input '{INPUT}'; rename this actuator (a sequence \
                     and another actuator cannot share an input)"
                ),
            ));
        }
        if a.mode == ActuatorMode::RestAngle {
            for e in &a.edges {
                owner.insert(
                    e.index(),
                    format!("the rest_angle actuator '{}' (ancf:actuators[{i}])", a.name),
                );
            }
        }
    }
    let equal = 1.0 / specs.len() as f64;
    let mut stages = Vec::with_capacity(specs.len());
    let mut total = 0usize;
    let mut folded = BTreeSet::new();
    for spec in specs {
        let stage = resolve_stage(&spec, &creases, edges, &owner)?;
        total += stage.len();
        if total > MAX_TARGETS {
            return Err(invalid(
                spec.key,
                format!(
                    "the sequence names {total} crease targets by this stage; at most \
                     {MAX_TARGETS} in all"
                ),
            ));
        }
        folded.extend(stage.iter().map(|&(e, _)| e));
        stages.push(Stage {
            title: spec.title,
            share: spec.share.unwrap_or(equal),
            targets: stage,
        });
    }
    // Given shares add up to 1 within the tolerance: make it exact.
    let sum: f64 = stages.iter().map(|s| s.share).sum();
    for s in &mut stages {
        s.share /= sum;
    }
    let passive: Vec<usize> = creases
        .iter()
        .copied()
        .filter(|&e| edges.target[e] != 0.0)
        .filter(|e| !folded.contains(&FoldEdgeId(*e)) && !owner.contains_key(e))
        .collect();
    if !passive.is_empty() {
        let shown: Vec<String> = passive.iter().take(8).map(|e| e.to_string()).collect();
        warnings.push(format!(
            "ancf:sequence: {} crease(s) with a fold angle are in no stage and no actuator \
             (FOLD edges {}{}); they stay passive (rest angle 0)",
            passive.len(),
            shown.join(", "),
            if passive.len() > 8 { ", ..." } else { "" }
        ));
    }
    scene.actuators.insert(
        0,
        Actuator {
            name: INPUT.to_string(),
            edges: folded.iter().map(|&e| EdgeId::of_fold_edge(e)).collect(),
            mode: ActuatorMode::RestAngle,
            start: 0.0,
        },
    );
    scene.sequence = Some(Sequence {
        actuator: INPUT.to_string(),
        stages,
    });
    Ok(())
}

/// One stage's creases and their targets (rad), in edge order.
fn resolve_stage(
    spec: &StageSpec,
    creases: &[usize],
    edges: &FoldEdges,
    owner: &HashMap<usize, String>,
) -> Result<Vec<(FoldEdgeId, f64)>, SceneError> {
    let sel_key = format!("{}.edges", spec.key);
    let selected = select_edges(&spec.edges, &sel_key, creases, edges, &mut Vec::new())?;
    if selected.is_empty() {
        let why = match &spec.edges {
            EdgeSelection::Assignment(a) => format!("no crease has assignment {}", a.letter()),
            _ => "the pattern has no creases".to_string(),
        };
        return Err(invalid(
            sel_key,
            format!("selects no crease ({why}); a stage must fold at least one crease"),
        ));
    }
    if let StageTarget::Fraction(_) = spec.target
        && selected.iter().all(|&e| edges.target[e] == 0.0)
    {
        return Err(invalid(
            format!("{}.fraction", spec.key),
            "every crease the stage selects has the fold angle 0 in the file (U or F edges \
             without edges_foldAngle), so a fraction of it folds nothing; give degrees",
        ));
    }
    let mut out = Vec::with_capacity(selected.len());
    for (j, &e) in selected.iter().enumerate() {
        if let Some(who) = owner.get(&e) {
            return Err(invalid(
                sel_key,
                format!(
                    "FOLD edge {e} is also driven by {who}; a crease follows one rest angle \
                     (leave it out of the actuator or of the stage)"
                ),
            ));
        }
        let (angle, key) = match &spec.target {
            StageTarget::Fraction(f) => (f * edges.target[e], format!("{}.fraction", spec.key)),
            StageTarget::Degrees(d) => (d.to_radians(), format!("{}.degrees", spec.key)),
            StageTarget::DegreesEach(list) => {
                (list[j].to_radians(), format!("{}.degrees[{j}]", spec.key))
            }
        };
        let deg = angle.to_degrees();
        if deg.is_nan() || deg.abs() > 180.0 + 1e-9 {
            return Err(invalid(
                key,
                format!(
                    "takes FOLD edge {e} to {} degrees; fold angles are within [-180, 180]",
                    num(deg)
                ),
            ));
        }
        out.push((
            FoldEdgeId(e),
            angle.clamp(-std::f64::consts::PI, std::f64::consts::PI),
        ));
    }
    out.sort_by_key(|&(e, _)| e);
    Ok(out)
}
