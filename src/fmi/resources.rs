//! What travels inside the FMU besides the binary: the scene file in
//! `resources/`, the GUID derived from it, and the resource-location URI
//! that the host passes to `fmi2Instantiate`.
//!
//! All scene reading goes through [`parse_scene`] (bytes to a validated
//! [`Scene`]), so that switching the FMU's scene from JSON of the `Scene`
//! struct to a FOLD file is a change in that one function and the
//! [`SCENE_FILE`] name.

use crate::mesh::MeshError;
use crate::model::Model;
use crate::scene::limits::LimitError;
use crate::scene::{Scene, SceneError};
use std::path::{Path, PathBuf};

/// Why a scene resource, a variable name or a resource location was refused.
#[derive(Debug)]
pub enum ResourceError {
    /// The scene file could not be read.
    Read {
        /// The file.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// An error in the scene file at `path`.
    InFile {
        /// The file.
        path: PathBuf,
        /// What is wrong in it.
        error: Box<ResourceError>,
    },
    /// The bytes are not JSON of a scene.
    Json(serde_json::Error),
    /// The mesh is invalid.
    Mesh(MeshError),
    /// A key of the scene is wrong (index out of range, over the size budget, ...).
    Scene(SceneError),
    /// A physical value is out of its limits.
    Limit(LimitError),
    /// The scene makes no model.
    Model(crate::model::Error),
    /// A variable name is not a legal FMI structured name.
    IllegalName(String),
    /// Two variables have the same name.
    DuplicateName(String),
    /// The resource location is not a `file:` URI.
    NotFileUri(String),
    /// The resource location names another host.
    RemoteHost {
        /// The URI.
        uri: String,
        /// Its host.
        host: String,
    },
    /// The resource location's path is not absolute.
    RelativeUri(String),
    /// The resource location has a malformed %-escape.
    BadEscape(String),
    /// The resource location's path is not UTF-8 (on Windows, paths are text).
    NotUtf8(String),
}

impl std::fmt::Display for ResourceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ResourceError::Read { path, source } => {
                write!(f, "cannot read scene {}: {source}", path.display())
            }
            ResourceError::InFile { path, error } => write!(f, "{}: {error}", path.display()),
            ResourceError::Json(e) => write!(f, "not a valid scene JSON: {e}"),
            ResourceError::Mesh(e) => write!(f, "mesh: {e}"),
            ResourceError::Scene(e) => write!(f, "{e}"),
            ResourceError::Limit(e) => write!(f, "{e}"),
            ResourceError::Model(e) => write!(f, "{e}"),
            ResourceError::IllegalName(name) => write!(
                f,
                "variable name {name:?} is not a legal FMI structured name (letters, digits, _, '.', [index])"
            ),
            ResourceError::DuplicateName(name) => {
                write!(f, "variable name {name:?} is used twice")
            }
            ResourceError::NotFileUri(uri) => {
                write!(f, "resource location {uri:?} is not a file: URI")
            }
            ResourceError::RemoteHost { uri, host } => write!(
                f,
                "resource location {uri:?} names host {host:?}; only local files are supported"
            ),
            ResourceError::RelativeUri(uri) => {
                write!(f, "resource location {uri:?} is not an absolute path")
            }
            ResourceError::BadEscape(uri) => {
                write!(f, "resource location {uri:?} has a malformed %-escape")
            }
            ResourceError::NotUtf8(uri) => write!(
                f,
                "resource location {uri:?} decodes to a path that is not UTF-8"
            ),
        }
    }
}

impl std::error::Error for ResourceError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ResourceError::Read { source, .. } => Some(source),
            ResourceError::InFile { error, .. } => Some(error.as_ref()),
            ResourceError::Json(e) => Some(e),
            ResourceError::Mesh(e) => Some(e),
            ResourceError::Scene(e) => Some(e),
            ResourceError::Limit(e) => Some(e),
            ResourceError::Model(e) => Some(e),
            _ => None,
        }
    }
}

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
pub fn load_scene_file(path: &Path) -> Result<Scene, ResourceError> {
    let bytes = std::fs::read(path).map_err(|source| ResourceError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_scene(&bytes).map_err(|e| ResourceError::InFile {
        path: path.to_path_buf(),
        error: Box::new(e),
    })
}

/// Parse and validate scene bytes. This is the one place that knows the
/// scene format; every message names the key or index and the reason.
pub fn parse_scene(bytes: &[u8]) -> Result<Scene, ResourceError> {
    check_budget(bytes).map_err(ResourceError::Scene)?;
    let mut scene: Scene = serde_json::from_slice(bytes).map_err(ResourceError::Json)?;
    // The derived Deserialize does not check the mesh: rebuild it through
    // the validating constructor (all edges listed, so nothing is added).
    let m = &scene.mesh;
    scene.mesh = crate::mesh::Mesh::new(
        m.coords().to_vec(),
        m.triangles().to_vec(),
        m.edges().to_vec(),
    )
    .map_err(ResourceError::Mesh)?;
    validate_scene(&scene)?;
    Ok(scene)
}

/// The size budget on the raw scene JSON, before it is parsed: the
/// number of triangles of `mesh`.
fn check_budget(bytes: &[u8]) -> Result<(), SceneError> {
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
        return Err(crate::scene::build::over_budget(
            "mesh.triangles",
            triangles,
            "the mesh has",
        ));
    }
    Ok(())
}

/// `Ok` when `ok`, else the [`SceneError::Invalid`] of `(key, reason)`.
fn check(ok: bool, msg: impl FnOnce() -> (String, String)) -> Result<(), ResourceError> {
    if ok {
        Ok(())
    } else {
        let (key, reason) = msg();
        Err(ResourceError::Scene(SceneError::invalid(key, reason)))
    }
}

/// Checks of the scene data beyond the mesh (indices in range, physical
/// values). Stands in for the scene module's own
/// validation until the FOLD reader lands.
fn validate_scene(s: &Scene) -> Result<(), ResourceError> {
    let nv = s.mesh.n_vertices();
    let ne = s.mesh.edges().len();
    check(!s.name.trim().is_empty(), || {
        ("name".into(), "empty".into())
    })?;
    check(s.fold_vertex_count <= nv, || {
        (
            "fold_vertex_count".into(),
            format!("{} but the mesh has {nv} vertices", s.fold_vertex_count),
        )
    })?;
    for (e, edge) in s.mesh.edges().iter().enumerate() {
        if let Some(f) = edge.fold_edge {
            check(f.index() < s.fold_edge_count, || {
                (
                    format!("mesh edge {e}"),
                    format!("fold_edge {f} >= fold_edge_count {}", s.fold_edge_count),
                )
            })?;
        }
    }
    crate::scene::limits::check_scene(s).map_err(ResourceError::Limit)?;
    for (i, a) in s.actuators.iter().enumerate() {
        check(a.start.is_finite(), || {
            (
                format!("actuators[{i}].start"),
                "not a finite number".into(),
            )
        })?;
        for &e in &a.edges {
            check(e.index() < ne, || {
                (
                    format!("actuators[{i}] ({})", a.name),
                    format!("edge {e} out of range (mesh has {ne} edges)"),
                )
            })?;
            check(s.mesh.edge(e).kind == crate::mesh::EdgeKind::Crease, || {
                (
                    format!("actuators[{i}] ({})", a.name),
                    format!("edge {e} is not a crease"),
                )
            })?;
        }
    }
    if let Some(sq) = &s.sequence {
        sq.check(s.fold_edge_count)
            .map_err(|m| ResourceError::Scene(SceneError::invalid("sequence", m)))?;
        let driver = s.actuators.iter().find(|a| a.name == sq.actuator);
        check(
            driver.is_some_and(|a| a.mode == crate::scene::ActuatorMode::RestAngle),
            || {
                (
                    "sequence.actuator".into(),
                    format!("no rest_angle actuator is named '{}'", sq.actuator),
                )
            },
        )?;
    }
    for (i, sup) in s.supports.iter().enumerate() {
        for &v in &sup.vertices {
            check(v.index() < nv, || {
                (
                    format!("supports[{i}]"),
                    format!("vertex {v} out of range (mesh has {nv} vertices)"),
                )
            })?;
        }
    }
    for (i, a) in s.attachments.iter().enumerate() {
        check(!a.vertices.is_empty(), || {
            (
                format!("attachments[{i}] ({})", a.name),
                "no vertices".into(),
            )
        })?;
        for &v in &a.vertices {
            check(v.index() < nv, || {
                (
                    format!("attachments[{i}] ({})", a.name),
                    format!("vertex {v} out of range (mesh has {nv} vertices)"),
                )
            })?;
        }
    }
    for (i, o) in s.obstacles.iter().enumerate() {
        let key = format!("obstacles[{i}] ({})", o.name);
        o.shape
            .check()
            .map_err(|e| ResourceError::Scene(SceneError::invalid(key.clone(), e.to_string())))?;
        crate::scene::limits::check("contact.friction", o.friction).map_err(|e| {
            ResourceError::Scene(SceneError::invalid(
                format!("{key}.friction"),
                e.to_string(),
            ))
        })?;
    }
    for (what, list) in [
        ("vertex_forces", &s.vertex_forces),
        ("vertex_motions", &s.vertex_motions),
    ] {
        for (i, vi) in list.iter().enumerate() {
            check(vi.vertex.index() < nv, || {
                (
                    format!("{what}[{i}] ({})", vi.name),
                    format!("vertex {} out of range (mesh has {nv} vertices)", vi.vertex),
                )
            })?;
        }
    }
    Ok(())
}

/// Check that every variable name of `model` is a legal FMI structured
/// name and unique (actuator and vertex-input names come from the scene).
pub fn check_variable_names(model: &Model) -> Result<(), ResourceError> {
    let mut seen = std::collections::HashSet::new();
    for v in model
        .parameters()
        .iter()
        .chain(model.inputs())
        .chain(model.outputs())
    {
        if !is_structured_name(&v.name) {
            return Err(ResourceError::IllegalName(v.name.clone()));
        }
        if !seen.insert(v.name.as_str()) {
            return Err(ResourceError::DuplicateName(v.name.clone()));
        }
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
/// percent-encoded, with or without a trailing slash; on Windows
/// `file:///C:/abs/path` names the drive path `C:/abs/path`. Other hosts
/// and schemes are rejected with the reason.
pub fn resource_dir_from_uri(uri: &str) -> Result<PathBuf, ResourceError> {
    let lower = uri.get(..5).map(str::to_ascii_lowercase);
    if lower.as_deref() != Some("file:") {
        return Err(ResourceError::NotFileUri(uri.into()));
    }
    let rest = &uri[5..];
    let path = if let Some(after) = rest.strip_prefix("//") {
        let slash = after.find('/').unwrap_or(after.len());
        let host = &after[..slash];
        if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
            return Err(ResourceError::RemoteHost {
                uri: uri.into(),
                host: host.into(),
            });
        }
        &after[slash..]
    } else {
        rest
    };
    if !path.starts_with('/') {
        return Err(ResourceError::RelativeUri(uri.into()));
    }
    let bytes = percent_decode(path).ok_or_else(|| ResourceError::BadEscape(uri.into()))?;
    path_from_bytes(bytes, uri)
}

/// A decoded URI path as the system's path: any bytes on unix.
#[cfg(unix)]
fn path_from_bytes(bytes: Vec<u8>, _uri: &str) -> Result<PathBuf, ResourceError> {
    use std::os::unix::ffi::OsStringExt;
    Ok(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
}

/// A decoded URI path as the system's path: UTF-8 text on Windows, the
/// drive path without the URI's leading slash.
#[cfg(not(unix))]
fn path_from_bytes(bytes: Vec<u8>, uri: &str) -> Result<PathBuf, ResourceError> {
    let text = String::from_utf8(bytes).map_err(|_| ResourceError::NotUtf8(uri.into()))?;
    Ok(PathBuf::from(windows_path(&text)))
}

/// The Windows path of a decoded `file:` URI path: `/C:/dir` is the drive
/// path `C:/dir` (RFC 8089, appendix E.2); any other path is kept.
#[cfg_attr(unix, allow(dead_code))]
fn windows_path(path: &str) -> &str {
    let b = path.as_bytes();
    let drive = b.len() >= 3 && b[0] == b'/' && b[1].is_ascii_alphabetic() && b[2] == b':';
    if drive && (b.len() == 3 || b[3] == b'/') {
        &path[1..]
    } else {
        path
    }
}

/// The `file:` URI of the absolute path `path`, percent-encoded, as
/// [`resource_dir_from_uri`] reads it back: `file:///tmp/x` on unix,
/// `file:///C:/x` on Windows. For tests and hosts written in Rust.
pub fn file_uri(path: &Path) -> String {
    #[cfg(unix)]
    let (text, lead) = {
        use std::os::unix::ffi::OsStrExt;
        (path.as_os_str().as_bytes().to_vec(), "")
    };
    #[cfg(not(unix))]
    let (text, lead) = {
        let s = path.to_string_lossy().replace('\\', "/");
        // `\\?\C:\x` (a canonicalized path) is the drive path `C:\x`.
        let s = s.strip_prefix("//?/").map(str::to_string).unwrap_or(s);
        let lead = if s.starts_with('/') { "" } else { "/" };
        (s.into_bytes(), lead)
    };
    let mut uri = format!("file://{lead}");
    for b in text {
        if b.is_ascii_alphanumeric() || b"-._~/:".contains(&b) {
            uri.push(char::from(b));
        } else {
            uri.push_str(&format!("%{b:02X}"));
        }
    }
    uri
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
        assert!(
            p("file://server/share/x")
                .unwrap_err()
                .to_string()
                .contains("server")
        );
        assert!(p("http://x/y").is_err());
        assert!(p("file:relative/x").is_err());
        assert!(p("file:///tmp/%zz").is_err());
        assert!(p("file:///tmp/%4").is_err());
    }

    /// `file:///C:/x` is the drive path `C:/x` on Windows, and a rooted
    /// path on unix; `file_uri` reads back to the same path either way.
    #[test]
    fn windows_drive_uris() {
        assert_eq!(windows_path("/C:/a b/resources"), "C:/a b/resources");
        assert_eq!(windows_path("/z:"), "z:");
        assert_eq!(windows_path("/tmp/x"), "/tmp/x");
        assert_eq!(windows_path("/C:x"), "/C:x");
        assert_eq!(windows_path("/1:/x"), "/1:/x");
        let p = resource_dir_from_uri("file:///C:/a%20b/resources").unwrap();
        #[cfg(windows)]
        assert_eq!(p, PathBuf::from(r"C:\a b\resources"));
        #[cfg(unix)]
        assert_eq!(p, PathBuf::from("/C:/a b/resources"));
        let dir = std::env::temp_dir().join("origami fmu 100%").join("ré");
        let uri = file_uri(&dir);
        assert!(uri.starts_with("file:///"), "{uri}");
        assert!(uri.contains("origami%20fmu%20100%25/r%C3%A9"), "{uri}");
        assert_eq!(resource_dir_from_uri(&uri).unwrap(), dir);
    }

    /// Scene resources fail with typed errors that keep their cause.
    #[test]
    fn scene_errors_are_typed() {
        use std::error::Error as _;
        let missing = Path::new("/nonexistent/origami-fmu/scene.json");
        let e = load_scene_file(missing).unwrap_err();
        match &e {
            ResourceError::Read { path, source } => {
                assert_eq!(path, missing);
                assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
            }
            other => panic!("{other:?}"),
        }
        assert!(
            e.to_string().starts_with("cannot read scene /nonexistent"),
            "{e}"
        );
        let e = parse_scene(b"{").unwrap_err();
        assert!(matches!(e, ResourceError::Json(_)), "{e:?}");
        assert!(e.to_string().starts_with("not a valid scene JSON: "), "{e}");
        assert!(e.source().is_some());
        let e = resource_dir_from_uri("file://server/x").unwrap_err();
        assert!(
            matches!(&e, ResourceError::RemoteHost { host, .. } if host == "server"),
            "{e:?}"
        );
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
