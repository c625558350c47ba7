//! The size of the sheet: the factor from file units to metres (a unit, or a
//! size for the longest side) and the note that says how it was chosen,
//! and the range of sizes the model handles.

use super::invalid;
use crate::scene::error::{SceneError, suggestion};
use crate::scene::fold::{FoldFile, UNITS, unit_scale};
use crate::scene::{LoadOptions, keys};
use nalgebra::Vector2;

/// Smallest sheet size (m) the model is asked to handle.
pub const MIN_EXTENT: f64 = 1e-9;
/// Largest sheet size, and largest distance from the origin (m).
pub const MAX_EXTENT: f64 = 1e6;

/// The length (m) of the longest side of the bounding box of a sheet
/// whose file gives no physical unit (no `frame_unit`, or FOLD's default
/// `unit`): such a sheet is scaled to it, a 10 cm sheet of paper.
pub const DEFAULT_SIZE: f64 = 0.1;

pub(super) fn bbox(coords: &[Vector2<f64>]) -> (Vector2<f64>, Vector2<f64>) {
    let mut lo = coords[0];
    let mut hi = coords[0];
    for c in coords {
        lo = lo.inf(c);
        hi = hi.sup(c);
    }
    (lo, hi)
}

/// The sheet (in metres) within [`MIN_EXTENT`] and [`MAX_EXTENT`] across,
/// and no farther than [`MAX_EXTENT`] from the origin.
pub(super) fn check_extent(coords: &[Vector2<f64>]) -> Result<(), SceneError> {
    let (lo, hi) = bbox(coords);
    let extent = (hi - lo).norm();
    let far = coords.iter().map(|c| c.amax()).fold(0.0, f64::max);
    if !((MIN_EXTENT..=MAX_EXTENT).contains(&extent) && far <= MAX_EXTENT) {
        return Err(invalid(
            "vertices_coords",
            format!(
                "the sheet is {extent:.3e} m across and reaches {far:.3e} m from the origin; the \
                 model handles {MIN_EXTENT:e} m to {MAX_EXTENT:e} m (check frame_unit, --unit or \
                 --size)"
            ),
        ));
    }
    Ok(())
}

/// A number for a note: four significant digits.
fn short(x: f64) -> String {
    if x == 0.0 || (1e-3..1e4).contains(&x.abs()) {
        let s = format!("{x:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{x:.3e}")
    }
}

/// The factor from file coordinates to metres, and the note that says how
/// it was chosen: `--size`/`--unit` ([`LoadOptions`]), else
/// `ancf:import.size`/`unit`, else a real `frame_unit`, else
/// [`DEFAULT_SIZE`] on the longest side.
pub(super) fn choose_scale(
    fold: &FoldFile,
    options: &LoadOptions,
    import: &keys::Import,
    coords: &[Vector2<f64>],
) -> Result<(f64, String), SceneError> {
    let (lo, hi) = bbox(coords);
    let side = (hi - lo).amax();
    if !(side > 0.0 && side.is_finite()) {
        return Err(invalid(
            "vertices_coords",
            "the sheet has no extent (all vertices at one point)",
        ));
    }
    if options.size.is_some() && options.unit.is_some() {
        return Err(invalid("--size", "give either a size or a unit, not both"));
    }
    if let Some(s) = options.size
        && !(s > 0.0 && s.is_finite())
    {
        return Err(invalid(
            "--size",
            format!("{s} is not a positive length (m)"),
        ));
    }
    let dims = |k: f64| {
        format!(
            "{} m x {} m",
            short(k * (hi.x - lo.x)),
            short(k * (hi.y - lo.y))
        )
    };
    let by_size = |s: f64, why: String| -> (f64, String) {
        let k = s / side;
        (
            k,
            format!(
                "size: {}: {why} scales the longest side to {} m (1 file unit = {} m)",
                dims(k),
                short(s),
                short(k)
            ),
        )
    };
    let by_unit = |u: &str, why: String| -> (f64, String) {
        let k = unit_scale(u).expect("checked unit");
        (
            k,
            format!("size: {}: {why} (1 file unit = {} m)", dims(k), short(k)),
        )
    };
    if let Some(s) = options.size {
        return Ok(by_size(s, format!("--size {}", short(s))));
    }
    if let Some(u) = &options.unit {
        let u = keys::check_unit("--unit", u)?;
        return Ok(by_unit(&u, format!("--unit {u}")));
    }
    if let Some(s) = import.size {
        return Ok(by_size(s, format!("ancf:import.size {}", short(s))));
    }
    if let Some(u) = &import.unit {
        return Ok(by_unit(u, format!("ancf:import.unit \"{u}\"")));
    }
    match fold.frame_unit.as_deref() {
        Some("unit") | None => {
            let (k, note) = by_size(
                DEFAULT_SIZE,
                format!(
                    "{} (no physical unit): the default size",
                    if fold.frame_unit.is_some() {
                        "frame_unit \"unit\""
                    } else {
                        "no frame_unit"
                    }
                ),
            );
            Ok((
                k,
                format!("{note}; --size, --unit or ancf:import change it"),
            ))
        }
        Some(u) => {
            if unit_scale(u).is_none() {
                return Err(invalid(
                    "frame_unit",
                    format!(
                        "unknown unit \"{u}\"{}; expected one of {} (or give --unit or --size)",
                        suggestion(u, UNITS),
                        UNITS.join(", ")
                    ),
                ));
            }
            Ok(by_unit(u, format!("frame_unit \"{u}\"")))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{base, err, load, with};
    use super::*;
    use crate::scene::build::from_fold_with;
    use serde_json::json;

    #[test]
    fn units() {
        let (mm, _) = load(&with(base(), "frame_unit", json!("mm"))).unwrap();
        assert_eq!(mm.mesh.coords()[2].x, 2e-3);
        let (inch, _) = load(&with(base(), "frame_unit", json!("in"))).unwrap();
        assert!((inch.mesh.coords()[2].x - 0.0508).abs() < 1e-15);
        let e = err(&with(base(), "frame_unit", json!("mn")), "frame_unit");
        assert!(e.contains("did you mean"), "{e}");
        // a unitless sheet is scaled to DEFAULT_SIZE on its longest side,
        // whatever its coordinates; "unit" is no unit
        for unit in [None, Some("unit")] {
            let mut v = with(
                base(),
                "vertices_coords",
                json!([[0, 0], [100, 0], [200, 0], [200, 100], [100, 100], [0, 100]]),
            );
            match unit {
                Some(u) => v["frame_unit"] = json!(u),
                None => {
                    v.as_object_mut().unwrap().remove("frame_unit");
                }
            }
            let parsed = crate::scene::fold::parse(&v.to_string(), None).unwrap().0;
            let l = from_fold_with(&parsed, &LoadOptions::default()).unwrap();
            assert!(l.warnings.is_empty(), "{:?}", l.warnings);
            assert_eq!(l.scene.mesh.coords()[2].x, DEFAULT_SIZE);
            assert!((l.scene.mesh.coords()[3].y - 0.5 * DEFAULT_SIZE).abs() < 1e-15);
            assert!(
                l.notes[0].starts_with("size: 0.1 m x 0.05 m:") && l.notes[0].contains("default"),
                "{:?}",
                l.notes
            );
            // --size and --unit, and the ancf:import key
            let o = LoadOptions {
                size: Some(0.3),
                ..Default::default()
            };
            let l = from_fold_with(&parsed, &o).unwrap();
            assert!((l.scene.mesh.coords()[2].x - 0.3).abs() < 1e-15);
            let o = LoadOptions {
                unit: Some("mm".into()),
                ..Default::default()
            };
            let l = from_fold_with(&parsed, &o).unwrap();
            assert!((l.scene.mesh.coords()[2].x - 0.2).abs() < 1e-15);
            assert!(l.notes[0].contains("--unit mm"), "{:?}", l.notes);
            let o = LoadOptions {
                unit: Some("mn".into()),
                ..Default::default()
            };
            let e = from_fold_with(&parsed, &o).unwrap_err().to_string();
            assert!(
                e.starts_with("--unit:") && e.contains("did you mean"),
                "{e}"
            );
            let (s, _) = load(&with(v.clone(), "ancf:import", json!({"size": 0.5}))).unwrap();
            assert!((s.mesh.coords()[2].x - 0.5).abs() < 1e-15);
            let (s, _) = load(&with(v.clone(), "ancf:import", json!({"unit": "cm"}))).unwrap();
            assert!((s.mesh.coords()[2].x - 2.0).abs() < 1e-15);
        }
        // a real unit is kept; --size rescales it anyway
        let v = with(base(), "frame_unit", json!("cm"));
        let parsed = crate::scene::fold::parse(&v.to_string(), None).unwrap().0;
        let l = from_fold_with(&parsed, &LoadOptions::default()).unwrap();
        assert_eq!(l.scene.mesh.coords()[2].x, 0.02);
        assert!(l.notes[0].contains("frame_unit \"cm\""), "{:?}", l.notes);
        let o = LoadOptions {
            size: Some(1.0),
            ..Default::default()
        };
        assert_eq!(
            from_fold_with(&parsed, &o).unwrap().scene.mesh.coords()[2].x,
            1.0
        );
        // absurd sizes
        let v = with(
            base(),
            "vertices_coords",
            json!([[0, 0], [1, 0], [2e300, 0], [2, 1], [1, 1], [0, 1]]),
        );
        err(&v, "vertices_coords");
        let v = with(base(), "frame_unit", json!("nm"));
        let v = with(
            v,
            "vertices_coords",
            json!([
                [0, 0],
                [1e-3, 0],
                [2e-3, 0],
                [2e-3, 1e-3],
                [1e-3, 1e-3],
                [0, 1e-3]
            ]),
        );
        let e = err(&v, "vertices_coords");
        assert!(e.contains("check frame_unit"), "{e}");
    }
}
