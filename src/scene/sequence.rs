//! A folding sequence: ordered stages that one rest-angle input walks.
//!
//! Each stage names creases and the fold angle each reaches at its end;
//! creases it does not name keep the angle they had. The input (the `fold`
//! actuator, 0 -> 1) is cut into the stages by their shares of the drive:
//! within stage `k`, from `b_k` to `b_{k+1}`, its creases go linearly from
//! where the earlier stages left them to its targets. The rest angles are
//! continuous in the input, so the drive moves back through the stages in
//! reverse order when the input decreases. Outside [0, 1] the input is
//! clamped (the sequence starts flat and ends at its last stage).
//!
//! Written as `ancf:sequence` (docs/scenes.md) or read from a FOLD file's
//! frames as keyframes ([`super::keyframes`]); the model evaluates it in
//! its input path (`src/model/inputs.rs`).

use crate::ids::FoldEdgeId;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Most stages of a sequence (a FOLD file of more frames is refused).
pub const MAX_STAGES: usize = 10_000;

/// Most (stage, crease) targets of a sequence in all: 64 MB of targets.
pub const MAX_TARGETS: usize = 4_000_000;

/// The name of the input a sequence is driven by.
pub const INPUT: &str = "fold";

/// How far from 1 the shares may add up to (relative round-off of a
/// hand-written list such as thirds).
pub const SHARE_TOLERANCE: f64 = 1e-6;

/// One stage: the creases it folds, where they end, and its share of the
/// drive.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    /// A label for pictures, the CLI and messages.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub title: Option<String>,
    /// Its share of the input's range (0, 1]; the shares add up to 1.
    pub share: f64,
    /// Each crease it folds (FOLD edge) and its fold angle at the stage's
    /// end (rad, valley positive), in increasing edge order.
    pub targets: Vec<(FoldEdgeId, f64)>,
}

/// The stages one rest-angle actuator walks, in order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sequence {
    /// The name of the rest-angle actuator (input) that drives it.
    pub actuator: String,
    /// The stages, first to last.
    pub stages: Vec<Stage>,
}

/// Where the drive is: the stage and the progress through it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Position {
    /// Stage index (0-based). At a boundary, the stage just finished.
    pub stage: usize,
    /// Progress through the stage, 0..=1.
    pub progress: f64,
}

impl Sequence {
    /// The drive at the start of each stage and 1 at the end: `b_0 = 0 <
    /// b_1 < ... < b_K = 1` (the last set to 1 exactly).
    pub fn breakpoints(&self) -> Vec<f64> {
        breakpoints(self.stages.iter().map(|s| s.share))
    }

    /// Where input value `u` is (clamped to [0, 1]; NaN reads as 0).
    pub fn locate(&self, u: f64) -> Position {
        locate(&self.breakpoints(), u)
    }

    /// A stage's label: its title, or "stage k".
    pub fn stage_name(&self, k: usize) -> String {
        match self.stages.get(k).and_then(|s| s.title.as_deref()) {
            Some(t) => t.to_string(),
            None => format!("stage {k}"),
        }
    }

    /// "stage 2/5 (petal folds), 40 %": the position `p`, for progress
    /// lines and pictures (stages counted from 1 there).
    pub fn describe(&self, p: Position) -> String {
        let title = self
            .stages
            .get(p.stage)
            .and_then(|s| s.title.as_deref())
            .map(|t| format!(" ({t})"))
            .unwrap_or_default();
        format!(
            "stage {}/{}{title}, {:.0} %",
            p.stage + 1,
            self.stages.len(),
            100.0 * p.progress
        )
    }

    /// For each FOLD edge the sequence folds, its (stage, target) entries in
    /// stage order.
    pub fn entries(&self) -> HashMap<FoldEdgeId, Vec<(usize, f64)>> {
        let mut by_edge: HashMap<FoldEdgeId, Vec<(usize, f64)>> = HashMap::new();
        for (k, s) in self.stages.iter().enumerate() {
            for &(e, t) in &s.targets {
                by_edge.entry(e).or_default().push((k, t));
            }
        }
        by_edge
    }

    /// The FOLD edges the sequence folds, in increasing order.
    pub fn edges(&self) -> Vec<FoldEdgeId> {
        let mut es: Vec<FoldEdgeId> = self.entries().into_keys().collect();
        es.sort_unstable();
        es
    }

    /// Checks of a sequence read from untrusted bytes (an FMU's scene):
    /// stages within [`MAX_STAGES`] and [`MAX_TARGETS`], each with a
    /// finite positive share and at least one target, the shares adding up
    /// to 1, edges below `fold_edge_count`, listed once per stage, with
    /// finite angles within [-pi, pi]. The error names the stage.
    pub fn check(&self, fold_edge_count: usize) -> Result<(), String> {
        if self.stages.is_empty() {
            return Err("the sequence has no stages".into());
        }
        if self.stages.len() > MAX_STAGES {
            return Err(format!(
                "{} stages; at most {MAX_STAGES}",
                self.stages.len()
            ));
        }
        let total: usize = self.stages.iter().map(|s| s.targets.len()).sum();
        if total > MAX_TARGETS {
            return Err(format!(
                "{total} crease targets in all; at most {MAX_TARGETS}"
            ));
        }
        let pi = std::f64::consts::PI;
        for (k, s) in self.stages.iter().enumerate() {
            if !(s.share.is_finite() && s.share > 0.0 && s.share <= 1.0 + SHARE_TOLERANCE) {
                return Err(format!("stage {k}: share {} is not in (0, 1]", s.share));
            }
            if s.targets.is_empty() {
                return Err(format!("stage {k} folds no crease"));
            }
            for w in s.targets.windows(2) {
                if w[0].0 >= w[1].0 {
                    return Err(format!(
                        "stage {k}: edges must be listed once, in increasing order ({} then {})",
                        w[0].0, w[1].0
                    ));
                }
            }
            for &(e, t) in &s.targets {
                if e.index() >= fold_edge_count {
                    return Err(format!(
                        "stage {k}: FOLD edge {e} does not exist ({fold_edge_count} edges)"
                    ));
                }
                if !(t.is_finite() && t.abs() <= pi * (1.0 + 1e-12)) {
                    return Err(format!(
                        "stage {k}: the target {t} rad of FOLD edge {e} is not within [-pi, pi]"
                    ));
                }
            }
        }
        let sum: f64 = self.stages.iter().map(|s| s.share).sum();
        if (sum - 1.0).abs() > SHARE_TOLERANCE {
            return Err(format!("the shares add up to {sum}, not 1"));
        }
        Ok(())
    }
}

/// The breakpoints of stages of the given shares (see
/// [`Sequence::breakpoints`]).
pub fn breakpoints(shares: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut b = vec![0.0];
    let mut sum = 0.0;
    for s in shares {
        sum += s;
        b.push(sum);
    }
    if let Some(last) = b.last_mut() {
        *last = 1.0;
    }
    b
}

/// Where `u` is among the breakpoints `b` ([`Sequence::locate`]).
pub fn locate(b: &[f64], u: f64) -> Position {
    let n = b.len().saturating_sub(1);
    if n == 0 {
        return Position {
            stage: 0,
            progress: 0.0,
        };
    }
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
    // The first stage whose end is at or past u.
    let stage = b[1..].partition_point(|&end| end < u).min(n - 1);
    let (lo, hi) = (b[stage], b[stage + 1]);
    let progress = if hi > lo {
        ((u - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        1.0
    };
    Position { stage, progress }
}

/// The fold angle of a crease with the (stage, target) entries `entries`
/// (in stage order) at position `p`: where the earlier stages left it,
/// moved toward its target if stage `p.stage` names it.
pub fn angle_at(entries: &[(usize, f64)], p: Position) -> f64 {
    let before = entries.partition_point(|&(k, _)| k < p.stage);
    let prior = if before > 0 {
        entries[before - 1].1
    } else {
        0.0
    };
    match entries.get(before) {
        Some(&(k, t)) if k == p.stage => prior + p.progress * (t - prior),
        _ => prior,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seq(shares: &[f64], targets: &[&[(usize, f64)]]) -> Sequence {
        Sequence {
            actuator: INPUT.into(),
            stages: shares
                .iter()
                .zip(targets)
                .map(|(&share, t)| Stage {
                    title: None,
                    share,
                    targets: t.iter().map(|&(e, a)| (FoldEdgeId(e), a)).collect(),
                })
                .collect(),
        }
    }

    /// Each stage's creases move within its share, the others hold; the
    /// angle is continuous across the boundaries and back.
    #[test]
    fn stages_walk_in_order_and_hold() {
        let s = seq(&[0.25, 0.75], &[&[(0, 1.0)], &[(0, 2.0), (1, -1.0)]]);
        assert_eq!(s.breakpoints(), vec![0.0, 0.25, 1.0]);
        let e = s.entries();
        let a = |edge: usize, u: f64| angle_at(&e[&FoldEdgeId(edge)], s.locate(u));
        assert_eq!(a(0, 0.0), 0.0);
        assert!((a(0, 0.125) - 0.5).abs() < 1e-15);
        assert_eq!(a(0, 0.25), 1.0);
        assert_eq!(a(1, 0.25), 0.0);
        assert!((a(0, 0.625) - 1.5).abs() < 1e-15);
        assert!((a(1, 0.625) + 0.5).abs() < 1e-15);
        assert_eq!(a(0, 1.0), 2.0);
        assert_eq!(a(1, 1.0), -1.0);
        // Clamped outside [0, 1]; NaN reads as 0.
        assert_eq!(a(0, 3.0), 2.0);
        assert_eq!(a(0, -1.0), 0.0);
        assert_eq!(a(0, f64::NAN), 0.0);
        // Continuous at the boundary from both sides.
        let d = 1e-12;
        assert!((a(0, 0.25 - d) - a(0, 0.25 + d)).abs() < 1e-10);
        assert!((a(1, 0.25 - d) - a(1, 0.25 + d)).abs() < 1e-10);
    }

    /// A boundary belongs to the stage that just finished; progress runs 0..1.
    #[test]
    fn locate_names_the_stage_and_progress() {
        let b = breakpoints([0.5, 0.3, 0.2].into_iter());
        assert_eq!(b.len(), 4);
        assert_eq!(b[3], 1.0);
        let at = |u: f64| {
            let p = locate(&b, u);
            (p.stage, p.progress)
        };
        assert_eq!(at(0.0), (0, 0.0));
        assert_eq!(at(0.5), (0, 1.0));
        let (stage, progress) = at(0.65);
        assert_eq!(stage, 1);
        assert!((progress - 0.5).abs() < 1e-12);
        assert_eq!(at(1.0), (2, 1.0));
        assert_eq!(at(7.0), (2, 1.0));
    }

    #[test]
    fn check_names_the_stage() {
        let ok = seq(&[0.5, 0.5], &[&[(0, 1.0)], &[(1, 1.0)]]);
        assert_eq!(ok.check(2), Ok(()));
        assert!(ok.check(1).unwrap_err().contains("stage 1: FOLD edge 1"));
        let e = seq(&[0.5, 0.4], &[&[(0, 1.0)], &[(1, 1.0)]]).check(2);
        assert!(e.unwrap_err().contains("add up to 0.9"));
        let e = seq(&[0.5, 0.5], &[&[(0, 1.0)], &[]]).check(2);
        assert!(e.unwrap_err().contains("stage 1 folds no crease"));
        let e = seq(&[1.0], &[&[(0, 4.0)]]).check(2);
        assert!(e.unwrap_err().contains("stage 0: the target 4"));
        let e = seq(&[1.0], &[&[(1, 1.0), (0, 1.0)]]).check(2);
        assert!(e.unwrap_err().contains("increasing order"));
        let e = seq(&[f64::NAN], &[&[(0, 1.0)]]).check(2);
        assert!(e.unwrap_err().contains("share"));
        assert!(seq(&[], &[]).check(2).unwrap_err().contains("no stages"));
    }

    #[test]
    fn describe_counts_from_one() {
        let mut s = seq(&[0.5, 0.5], &[&[(0, 1.0)], &[(1, 1.0)]]);
        s.stages[1].title = Some("petals".into());
        assert_eq!(s.describe(s.locate(0.25)), "stage 1/2, 50 %");
        assert_eq!(s.describe(s.locate(0.75)), "stage 2/2 (petals), 50 %");
        assert_eq!(s.stage_name(0), "stage 0");
    }
}
