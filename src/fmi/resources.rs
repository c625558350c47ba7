//! What travels inside the FMU besides the binary: the scene file in
//! `resources/`, the GUID derived from it, and the resource-location URI
//! that the host passes to `fmi2Instantiate`.
//!
//! All scene reading goes through [`parse_scene`] (bytes to a validated
//! [`Scene`]), so that switching the FMU's scene from JSON of the `Scene`
//! struct to a FOLD file is a change in that one function and the
//! [`SCENE_FILE`] name.

use crate::model::Model;
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The `modelIdentifier`: one shared library for every scene.
pub const MODEL_IDENTIFIER: &str = "origami_fmu";

/// Name of the scene file inside the FMU's `resources/` folder.
pub const SCENE_FILE: &str = "scene.json";

/// Version of this crate, part of every GUID: an FMU only instantiates with
/// the library version that built it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The GUID of an FMU whose `resources/` scene file has the bytes `scene`:
/// a 128-bit FNV-1a hash of the crate version and those bytes, written as
/// `{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}`. Stable across platforms and
/// Rust versions.
pub fn guid(scene: &[u8]) -> String {
    let [a, b] = hash128(&[b"origami-fmu", VERSION.as_bytes(), scene]);
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// Two 64-bit FNV-1a hashes (different offset bases) of `parts`, each part
/// followed by a 0xff byte: the GUID's hash and the checksum of a
/// serialized FMU state. Any change confined to one byte changes both
/// (each FNV-1a step is a bijection of the running hash for a given byte),
/// so a single flipped bit is always detected.
pub(crate) fn hash128(parts: &[&[u8]]) -> [u64; 2] {
    let fnv = |seed: u64| {
        let mut h = seed;
        for part in parts {
            for &b in *part {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
            h ^= 0xff;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        h
    };
    [fnv(0xcbf2_9ce4_8422_2325), fnv(0x6c62_272e_07bb_0142)]
}

/// The canonical bytes of a scene as the FMU stores it in
/// `resources/`[`SCENE_FILE`].
pub fn scene_bytes(scene: &Scene) -> Vec<u8> {
    let mut v = serde_json::to_vec_pretty(scene).expect("a Scene always serializes");
    v.push(b'\n');
    v
}

/// Read and validate a scene file (today: JSON of the [`Scene`] struct).
pub fn load_scene_file(path: &Path) -> Result<Scene, String> {
    let bytes =
        std::fs::read(path).map_err(|e| format!("cannot read scene {}: {e}", path.display()))?;
    parse_scene(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Parse and validate scene bytes. This is the one place that knows the
/// scene format; every message names the key or index and the reason.
pub fn parse_scene(bytes: &[u8]) -> Result<Scene, String> {
    check_budget(bytes)?;
    let mut scene: Scene =
        serde_json::from_slice(bytes).map_err(|e| format!("not a valid scene JSON: {e}"))?;
    // The derived Deserialize does not check the mesh: rebuild it through
    // the validating constructor (all edges listed, so nothing is added).
    let m = &scene.mesh;
    scene.mesh = crate::mesh::Mesh::new(
        m.coords().to_vec(),
        m.triangles().to_vec(),
        m.edges().to_vec(),
    )
    .map_err(|e| format!("mesh: {e}"))?;
    validate_scene(&scene)?;
    Ok(scene)
}

/// The size budget on the raw scene JSON, before it is parsed: the
/// number of triangles of `mesh`.
fn check_budget(bytes: &[u8]) -> Result<(), String> {
    use serde_json::value::RawValue;
    use std::collections::BTreeMap;
    type Raw<'a> = BTreeMap<String, &'a RawValue>;
    let Ok(scene) = serde_json::from_slice::<Raw>(bytes) else {
        return Ok(()); // the parse says what is wrong
    };
    let triangles = scene
        .get("mesh")
        .and_then(|m| serde_json::from_str::<Raw>(m.get()).ok())
        .and_then(|m| Some(crate::scene::fold::array_counts(m.get("triangles")?).0))
        .unwrap_or(0);
    if triangles > crate::scene::build::MAX_FACETS {
        return Err(
            crate::scene::build::over_budget("mesh.triangles", triangles, "the mesh has")
                .to_string(),
        );
    }
    Ok(())
}

fn check(ok: bool, msg: impl FnOnce() -> String) -> Result<(), String> {
    if ok { Ok(()) } else { Err(msg()) }
}

/// Checks of the scene data beyond the mesh (indices in range, physical
/// values). Stands in for the scene module's own
/// validation until the FOLD reader lands.
fn validate_scene(s: &Scene) -> Result<(), String> {
    let nv = s.mesh.n_vertices();
    let ne = s.mesh.edges().len();
    check(!s.name.trim().is_empty(), || "name: empty".into())?;
    check(s.fold_vertex_count <= nv, || {
        format!(
            "fold_vertex_count: {} but the mesh has {nv} vertices",
            s.fold_vertex_count
        )
    })?;
    for (e, edge) in s.mesh.edges().iter().enumerate() {
        if let Some(f) = edge.fold_edge {
            check(f.index() < s.fold_edge_count, || {
                format!(
                    "mesh edge {e}: fold_edge {f} >= fold_edge_count {}",
                    s.fold_edge_count
                )
            })?;
        }
    }
    crate::scene::limits::check_scene(s).map_err(|e| e.to_string())?;
    for (i, a) in s.actuators.iter().enumerate() {
        check(a.start.is_finite(), || {
            format!("actuators[{i}].start: not a finite number")
        })?;
        for &e in &a.edges {
            check(e.index() < ne, || {
                format!(
                    "actuators[{i}] ({}): edge {e} out of range (mesh has {ne} edges)",
                    a.name
                )
            })?;
            check(s.mesh.edge(e).kind == crate::mesh::EdgeKind::Crease, || {
                format!("actuators[{i}] ({}): edge {e} is not a crease", a.name)
            })?;
        }
    }
    for (i, sup) in s.supports.iter().enumerate() {
        for &v in &sup.vertices {
            check(v.index() < nv, || {
                format!("supports[{i}]: vertex {v} out of range (mesh has {nv} vertices)")
            })?;
        }
    }
    for (i, a) in s.attachments.iter().enumerate() {
        check(!a.vertices.is_empty(), || {
            format!("attachments[{i}] ({}): no vertices", a.name)
        })?;
        for &v in &a.vertices {
            check(v.index() < nv, || {
                format!(
                    "attachments[{i}] ({}): vertex {v} out of range (mesh has {nv} vertices)",
                    a.name
                )
            })?;
        }
    }
    for (what, list) in [
        ("vertex_forces", &s.vertex_forces),
        ("vertex_motions", &s.vertex_motions),
    ] {
        for (i, vi) in list.iter().enumerate() {
            check(vi.vertex.index() < nv, || {
                format!(
                    "{what}[{i}] ({}): vertex {} out of range (mesh has {nv} vertices)",
                    vi.name, vi.vertex
                )
            })?;
        }
    }
    Ok(())
}

/// Check that every variable name of `model` is a legal FMI structured
/// name and unique (actuator and vertex-input names come from the scene).
pub fn check_variable_names(model: &Model) -> Result<(), String> {
    let mut seen = std::collections::HashSet::new();
    for v in model
        .parameters()
        .iter()
        .chain(model.inputs())
        .chain(model.outputs())
    {
        check(is_structured_name(&v.name), || {
            format!(
                "variable name {:?} is not a legal FMI structured name (letters, digits, _, '.', [index])",
                v.name
            )
        })?;
        check(seen.insert(v.name.as_str()), || {
            format!("variable name {:?} is used twice", v.name)
        })?;
    }
    Ok(())
}

/// True when `name` is a legal FMI 2.0 structured name made of plain
/// identifiers: `a.b[3].c` (quoted names are not used by this FMU).
pub fn is_structured_name(name: &str) -> bool {
    name.split('.').all(|part| {
        let (base, idx) = match part.find('[') {
            Some(k) => (&part[..k], Some(&part[k..])),
            None => (part, None),
        };
        let mut chars = base.chars();
        let first_ok = matches!(chars.next(), Some(c) if c == '_' || c.is_ascii_alphabetic());
        let rest_ok = chars.all(|c| c == '_' || c.is_ascii_alphanumeric());
        let idx_ok = match idx {
            None => true,
            Some(i) => i
                .strip_prefix('[')
                .and_then(|i| i.strip_suffix(']'))
                .is_some_and(|inner| {
                    inner
                        .split(',')
                        .all(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
                }),
        };
        first_ok && rest_ok && idx_ok
    })
}

/// The folder named by a resource-location URI as hosts pass it:
/// `file:///abs/path`, `file://localhost/abs/path` or `file:/abs/path`,
/// percent-encoded, with or without a trailing slash. Other hosts and
/// schemes are rejected with the reason.
pub fn resource_dir_from_uri(uri: &str) -> Result<PathBuf, String> {
    let lower = uri.get(..5).map(str::to_ascii_lowercase);
    if lower.as_deref() != Some("file:") {
        return Err(format!("resource location {uri:?} is not a file: URI"));
    }
    let rest = &uri[5..];
    let path = if let Some(after) = rest.strip_prefix("//") {
        let slash = after.find('/').unwrap_or(after.len());
        let host = &after[..slash];
        if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
            return Err(format!(
                "resource location {uri:?} names host {host:?}; only local files are supported"
            ));
        }
        &after[slash..]
    } else {
        rest
    };
    if !path.starts_with('/') {
        return Err(format!("resource location {uri:?} is not an absolute path"));
    }
    let bytes = percent_decode(path)
        .ok_or_else(|| format!("resource location {uri:?} has a malformed %-escape"))?;
    use std::os::unix::ffi::OsStringExt;
    Ok(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
}

fn percent_decode(s: &str) -> Option<Vec<u8>> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris() {
        let p = |u: &str| resource_dir_from_uri(u);
        assert_eq!(
            p("file:///tmp/a%20b/resources").unwrap(),
            PathBuf::from("/tmp/a b/resources")
        );
        assert_eq!(
            p("file:///tmp/x/resources/").unwrap(),
            PathBuf::from("/tmp/x/resources/")
        );
        assert_eq!(
            p("file://localhost/tmp/x").unwrap(),
            PathBuf::from("/tmp/x")
        );
        assert_eq!(p("FILE:/tmp/x").unwrap(), PathBuf::from("/tmp/x"));
        assert!(p("file://server/share/x").unwrap_err().contains("server"));
        assert!(p("http://x/y").is_err());
        assert!(p("file:relative/x").is_err());
        assert!(p("file:///tmp/%zz").is_err());
        assert!(p("file:///tmp/%4").is_err());
    }

    #[test]
    fn names() {
        for ok in [
            "fold",
            "vertex[3].x",
            "crease[12].angle",
            "a_b.c[1,2]",
            "_x",
        ] {
            assert!(is_structured_name(ok), "{ok}");
        }
        for bad in [
            "", "3a", "a b", "a..b", "a[]", "a[x]", "a[1", "a-b", "a.[1]",
        ] {
            assert!(!is_structured_name(bad), "{bad}");
        }
    }

    #[test]
    fn guid_is_stable_and_content_bound() {
        let g = guid(b"{}");
        assert_eq!(g.len(), 38);
        assert_eq!(g, guid(b"{}"));
        assert_ne!(g, guid(b"{ }"));
    }
}
