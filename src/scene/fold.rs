//! FOLD 1.2 files as data: reading (with `file_frames` and frame
//! inheritance) and writing.
//!
//! [`parse`] checks the JSON syntax (errors carry line and column) and the
//! type of every key this crate uses (errors name the key and index); it
//! does not yet check geometry or cross references, which is the job of
//! [`crate::scene::from_fold`]. Unknown keys without a namespace are ignored,
//! as the FOLD specification asks; `ancf:` keys are kept raw in
//! [`FoldFile::ancf`] for [`crate::scene::keys`].
//!
//! ```
//! use origami_fmu::scene::fold::{self, FoldFile};
//! let text = r#"{"vertices_coords": [[0,0],[1,0],[0,1]], "faces_vertices": [[0,1,2]]}"#;
//! let (file, warnings) = fold::parse(text, None).unwrap();
//! assert_eq!(file.vertices_coords.len(), 3);
//! assert!(warnings.is_empty());
//! let again = fold::parse(&file.to_json(), None).unwrap().0;
//! assert_eq!(again.faces_vertices, file.faces_vertices);
//! ```

use super::error::{SceneError, suggestion};
use crate::text::num;
use serde_json::value::RawValue;
use serde_json::{Map, Value};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;

/// A FOLD edge assignment (`edges_assignment` letters).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Assignment {
    /// `M`: mountain crease.
    Mountain,
    /// `V`: valley crease.
    Valley,
    /// `F`: flat fold: a fold line that is unfolded (0 degrees) in this
    /// state. Read as a crease with target 0, except in Origami Simulator
    /// exports (and when `ancf:import.f_edges` or `--f-edges` says
    /// `smooth`), where F marks triangulation lines: smooth edges.
    Flat,
    /// `J`: join: not a fold line, it only joins two faces (a smooth edge).
    Join,
    /// `B`: boundary edge.
    Boundary,
    /// `U`: unassigned; read as a crease with a free (zero) target unless
    /// `edges_foldAngle` gives one.
    Unassigned,
    /// `C`: cut: the sheet is cut along the edge; both sides become
    /// boundary edges (the vertices along the cut are split).
    Cut,
}

impl Assignment {
    /// The FOLD letter.
    pub fn letter(self) -> &'static str {
        match self {
            Assignment::Mountain => "M",
            Assignment::Valley => "V",
            Assignment::Flat => "F",
            Assignment::Join => "J",
            Assignment::Boundary => "B",
            Assignment::Unassigned => "U",
            Assignment::Cut => "C",
        }
    }

    /// Parse a FOLD letter (upper or lower case).
    pub fn from_letter(s: &str) -> Option<Assignment> {
        Some(match s {
            "M" | "m" => Assignment::Mountain,
            "V" | "v" => Assignment::Valley,
            "F" | "f" => Assignment::Flat,
            "J" | "j" => Assignment::Join,
            "B" | "b" => Assignment::Boundary,
            "U" | "u" => Assignment::Unassigned,
            "C" | "c" => Assignment::Cut,
            _ => return None,
        })
    }

    /// True for M, V and U (the assignments read as creases).
    pub fn is_crease(self) -> bool {
        matches!(
            self,
            Assignment::Mountain | Assignment::Valley | Assignment::Unassigned
        )
    }
}

/// Which frame of a multi-frame file to read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FrameSelector {
    /// FOLD frame number: 0 is the top level, `k` is `file_frames[k-1]`.
    Index(usize),
    /// The first frame whose `frame_title` is this.
    Title(String),
}

impl std::str::FromStr for FrameSelector {
    type Err = std::convert::Infallible;
    /// A number selects by index, anything else by title.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.parse::<usize>() {
            Ok(k) => FrameSelector::Index(k),
            Err(_) => FrameSelector::Title(s.to_string()),
        })
    }
}

/// One frame of a FOLD file with the file metadata: the keys this crate
/// reads and writes. Optional arrays are `None` when the file omits them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FoldFile {
    /// `file_spec` (written as 1.2).
    pub file_spec: Option<f64>,
    /// `file_creator`.
    pub file_creator: Option<String>,
    /// `file_author`.
    pub file_author: Option<String>,
    /// `file_title`.
    pub file_title: Option<String>,
    /// `file_description`.
    pub file_description: Option<String>,
    /// `file_classes`.
    pub file_classes: Vec<String>,
    /// `frame_title`.
    pub frame_title: Option<String>,
    /// `frame_classes` (e.g. `creasePattern`).
    pub frame_classes: Vec<String>,
    /// `frame_attributes` (e.g. `2D`).
    pub frame_attributes: Vec<String>,
    /// `frame_unit` (`unit`, `m`, `cm`, `mm`, `um`, `nm`, `in`, `pt`).
    pub frame_unit: Option<String>,
    /// `vertices_coords`: 2D or 3D points.
    pub vertices_coords: Vec<Vec<f64>>,
    /// `edges_vertices`.
    pub edges_vertices: Option<Vec<[usize; 2]>>,
    /// `edges_assignment`.
    pub edges_assignment: Option<Vec<Assignment>>,
    /// `edges_foldAngle` in degrees, valley positive; `None` entries are
    /// JSON `null` (no target given). Read from the pre-1.1 spelling
    /// `edges_foldAngles` too.
    pub edges_fold_angle: Option<Vec<Option<f64>>>,
    /// `faces_vertices`: polygons, counter-clockwise. Empty when the file
    /// has none: the scene builder then traces the faces of the planar
    /// graph of `edges_vertices`.
    pub faces_vertices: Vec<Vec<usize>>,
    /// The `ancf:` physics keys, raw (full key including the prefix).
    pub ancf: Map<String, Value>,
}

/// Metres per FOLD `frame_unit` for the real units; `None` for `unit` (the
/// FOLD default: no physical unit, see [`crate::scene::build::DEFAULT_SIZE`])
/// and for unknown names.
pub fn unit_scale(unit: &str) -> Option<f64> {
    Some(match unit {
        "m" => 1.0,
        "cm" => 1e-2,
        "mm" => 1e-3,
        "um" | "µm" => 1e-6,
        "nm" => 1e-9,
        "in" => 0.0254,
        "pt" => 0.0254 / 72.0,
        _ => return None,
    })
}

/// The `frame_unit` values [`unit_scale`] knows.
pub const UNITS: &[&str] = &["unit", "m", "cm", "mm", "um", "nm", "in", "pt"];

/// FOLD keys this reader uses or knows (for misspelling warnings): the
/// keys of the FOLD 1.2 specification, every `vertices_`/`edges_`/`faces_`
/// relation between the three (Rabbit Ear writes `edges_edges`, for
/// example), and the keys FOLD's own converters write.
const KNOWN_KEYS: &[&str] = &[
    "file_spec",
    "file_creator",
    "file_author",
    "file_title",
    "file_description",
    "file_classes",
    "file_frames",
    "frame_title",
    "frame_description",
    "frame_classes",
    "frame_attributes",
    "frame_unit",
    "frame_parent",
    "frame_inherit",
    "vertices_coords",
    "vertices_vertices",
    "vertices_faces",
    "vertices_edges",
    "vertices_flatUnfoldCoords",
    "edges_vertices",
    "edges_edges",
    "edges_faces",
    "edges_assignment",
    "edges_foldAngle",
    "edges_foldAngles",
    "edges_length",
    "edges_orders",
    "faces_vertices",
    "faces_edges",
    "faces_faces",
    "faces_flatFoldTransform",
    "faces_flatFoldOrientation",
    "faceOrders",
    "edgeOrders",
];

/// JSON type name for messages.
pub(crate) fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

pub(crate) fn expect_array<'a>(v: &'a Value, key: &str) -> Result<&'a Vec<Value>, SceneError> {
    v.as_array().ok_or_else(|| {
        SceneError::invalid(key, format!("expected an array, found {}", type_name(v)))
    })
}

pub(crate) fn expect_number(v: &Value, key: &str) -> Result<f64, SceneError> {
    match v.as_f64() {
        Some(x) if x.is_finite() => Ok(x),
        Some(x) => Err(SceneError::invalid(
            key,
            format!("{} is not finite", num(x)),
        )),
        None => Err(SceneError::invalid(
            key,
            format!("expected a number, found {}", type_name(v)),
        )),
    }
}

pub(crate) fn expect_string<'a>(v: &'a Value, key: &str) -> Result<&'a str, SceneError> {
    v.as_str().ok_or_else(|| {
        SceneError::invalid(key, format!("expected a string, found {}", type_name(v)))
    })
}

/// A non-negative integer (an integral float like `3.0` is accepted).
pub(crate) fn expect_index(v: &Value, key: &str) -> Result<usize, SceneError> {
    if let Some(u) = v.as_u64() {
        return usize::try_from(u)
            .map_err(|_| SceneError::invalid(key, format!("{u} is too large")));
    }
    if let Some(i) = v.as_i64() {
        return Err(SceneError::invalid(
            key,
            format!("expected a non-negative integer, found {i}"),
        ));
    }
    if let Some(x) = v.as_f64() {
        if x >= 0.0 && x.fract() == 0.0 && x < 9.007_199_254_740_992e15 {
            return Ok(x as usize);
        }
        return Err(SceneError::invalid(
            key,
            format!("expected a non-negative integer, found {}", num(x)),
        ));
    }
    Err(SceneError::invalid(
        key,
        format!("expected a non-negative integer, found {}", type_name(v)),
    ))
}

fn string_list(v: &Value, key: &str) -> Result<Vec<String>, SceneError> {
    // FOLD allows a single string where a list is expected in some writers.
    if let Some(s) = v.as_str() {
        return Ok(vec![s.to_string()]);
    }
    expect_array(v, key)?
        .iter()
        .enumerate()
        .map(|(i, x)| expect_string(x, &format!("{key}[{i}]")).map(str::to_string))
        .collect()
}

#[doc(hidden)]
/// A FOLD file's frames with their keys, the values unparsed (borrowed
/// from the text): the text is read once, and reading a frame costs the
/// size of that frame and its parents, so that every frame of a file can
/// be looked at in time linear in the file (the message of a folded frame
/// names the frames that are crease patterns). Frame 0 is the top level,
/// frame `k` is `file_frames[k-1]`.
pub struct Frames<'a> {
    frames: Vec<BTreeMap<String, &'a RawValue>>,
}

/// The JSON type of a raw value, for messages.
fn raw_type(v: &RawValue) -> &'static str {
    match v.get().as_bytes().first() {
        Some(b'{') => "an object",
        Some(b'[') => "an array",
        Some(b'"') => "a string",
        Some(b't' | b'f') => "a boolean",
        Some(b'n') => "null",
        _ => "a number",
    }
}

/// A raw value parsed (it is valid JSON: the text was checked when read).
fn value(v: &RawValue) -> Result<Value, SceneError> {
    serde_json::from_str(v.get()).map_err(|e| SceneError::from_json(&e))
}

/// A raw object's keys and raw values; `None` when it is not an object.
fn object(v: &RawValue) -> Option<BTreeMap<String, &RawValue>> {
    serde_json::from_str(v.get()).ok()
}

impl<'a> Frames<'a> {
    /// Read the frames of FOLD text (JSON syntax errors carry line and
    /// column).
    pub fn new(text: &'a str) -> Result<Frames<'a>, SceneError> {
        let root: &RawValue = serde_json::from_str(text).map_err(|e| SceneError::from_json(&e))?;
        let top = object(root).ok_or_else(|| {
            SceneError::invalid(
                "(top level)",
                format!("a FOLD file is a JSON object, found {}", raw_type(root)),
            )
        })?;
        let mut frames = Vec::new();
        if let Some(ff) = top.get("file_frames") {
            let list: Vec<&RawValue> = serde_json::from_str(ff.get()).map_err(|_| {
                SceneError::invalid(
                    "file_frames",
                    format!("expected an array, found {}", raw_type(ff)),
                )
            })?;
            for (i, f) in list.into_iter().enumerate() {
                frames.push(object(f).ok_or_else(|| {
                    SceneError::invalid(
                        format!("file_frames[{i}]"),
                        format!("expected an object, found {}", raw_type(f)),
                    )
                })?);
            }
        }
        frames.insert(0, top);
        Ok(Frames { frames })
    }

    /// Number of frames (the top level included).
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Always false: the top level is a frame.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The `frame_title` of every frame (`None` where it has none).
    pub fn titles(&self) -> Vec<Option<String>> {
        self.frames
            .iter()
            .map(|f| {
                f.get("frame_title")
                    .and_then(|t| serde_json::from_str::<String>(t.get()).ok())
            })
            .collect()
    }

    /// Whether frame `k` itself (not a parent) has the key `key`.
    pub fn has_own(&self, k: usize, key: &str) -> bool {
        self.frames.get(k).is_some_and(|f| f.contains_key(key))
    }

    /// The number of the frame `frame` picks, as [`Frames::frame`] picks it.
    pub fn index(&self, frame: Option<&FrameSelector>) -> Result<usize, SceneError> {
        let frames = &self.frames;
        let top = &frames[0];
        Ok(match frame {
            None => {
                if top.contains_key("vertices_coords") || frames.len() == 1 {
                    0
                } else {
                    1
                }
            }
            Some(FrameSelector::Index(k)) => {
                if *k >= frames.len() {
                    return Err(SceneError::invalid(
                        "file_frames",
                        format!(
                            "frame {k} was asked for, but the file has {} frame(s) (0 = top level)",
                            frames.len()
                        ),
                    ));
                }
                *k
            }
            Some(FrameSelector::Title(t)) => self
                .titles()
                .iter()
                .position(|f| f.as_deref() == Some(t.as_str()))
                .ok_or_else(|| {
                    SceneError::invalid("frame_title", format!("no frame is titled '{t}'"))
                })?,
        })
    }

    /// Pick a frame as [`parse`] does and read it.
    pub fn frame(
        &self,
        frame: Option<&FrameSelector>,
    ) -> Result<(FoldFile, Vec<String>), SceneError> {
        let frames = &self.frames;
        let top = &frames[0];
        let prefix = |k: usize| {
            if k == 0 {
                String::new()
            } else {
                format!("file_frames[{}].", k - 1)
            }
        };
        let selected = self.index(frame)?;

        // Resolve frame inheritance: the chain from the selected frame up.
        let mut chain = vec![selected];
        let mut k = selected;
        let inherits = |k: usize| {
            frames[k]
                .get("frame_inherit")
                .is_some_and(|v| v.get() == "true")
        };
        while k != 0 && inherits(k) {
            let key = format!("{}frame_parent", prefix(k));
            let parent = match frames[k].get("frame_parent") {
                Some(p) => expect_index(&value(p)?, &key)?,
                None => 0,
            };
            if parent >= frames.len() {
                return Err(SceneError::invalid(
                    key,
                    format!("frame {parent} does not exist"),
                ));
            }
            if chain.contains(&parent) {
                return Err(SceneError::invalid(key, "frame inheritance forms a cycle"));
            }
            chain.push(parent);
            k = parent;
        }
        // Merge: parents first, the selected frame last; remember where each
        // key came from for error messages. file_* and ancf:* keys of the top
        // level are always visible.
        let mut merged: HashMap<&str, (&RawValue, String)> = HashMap::new();
        for (key, v) in top {
            if key.starts_with("file_") || key.starts_with("ancf:") {
                merged.insert(key, (*v, String::new()));
            }
        }
        for &k in chain.iter().rev() {
            for (key, v) in &frames[k] {
                if key == "file_frames" {
                    continue;
                }
                merged.insert(key, (*v, prefix(k)));
            }
        }
        read_frame(&merged)
    }
}

/// The titles of a file's frames (index 0 is the top level, `k` is
/// `file_frames[k-1]`); `None` for a frame without `frame_title`.
pub fn frame_titles(text: &str) -> Result<Vec<Option<String>>, SceneError> {
    Ok(Frames::new(text)?.titles())
}

/// Parse FOLD text and pick a frame (`None`: the top level if it has
/// `vertices_coords`, else the first of `file_frames`). Returns the frame
/// and warnings (misspelt FOLD keys, both angle spellings present).
pub fn parse(
    text: &str,
    frame: Option<&FrameSelector>,
) -> Result<(FoldFile, Vec<String>), SceneError> {
    Frames::new(text)?.frame(frame)
}

/// How many elements the array `v` has, and how many elements its
/// elements have in all (0 for elements that are not arrays), without
/// building either: what the size budget looks at before a large array is
/// parsed.
pub(crate) fn array_counts(v: &RawValue) -> (usize, usize) {
    struct Outer(usize, usize);
    struct Inner(usize);
    impl<'de> serde::Deserialize<'de> for Inner {
        fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct V;
            impl<'de> serde::de::Visitor<'de> for V {
                type Value = Inner;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("any value")
                }
                fn visit_seq<A: serde::de::SeqAccess<'de>>(
                    self,
                    mut a: A,
                ) -> Result<Inner, A::Error> {
                    let mut n = 0;
                    while a.next_element::<serde::de::IgnoredAny>()?.is_some() {
                        n += 1;
                    }
                    Ok(Inner(n))
                }
                fn visit_map<A: serde::de::MapAccess<'de>>(
                    self,
                    mut a: A,
                ) -> Result<Inner, A::Error> {
                    while a
                        .next_entry::<serde::de::IgnoredAny, serde::de::IgnoredAny>()?
                        .is_some()
                    {}
                    Ok(Inner(0))
                }
                fn visit_bool<E>(self, _: bool) -> Result<Inner, E> {
                    Ok(Inner(0))
                }
                fn visit_i64<E>(self, _: i64) -> Result<Inner, E> {
                    Ok(Inner(0))
                }
                fn visit_u64<E>(self, _: u64) -> Result<Inner, E> {
                    Ok(Inner(0))
                }
                fn visit_f64<E>(self, _: f64) -> Result<Inner, E> {
                    Ok(Inner(0))
                }
                fn visit_str<E>(self, _: &str) -> Result<Inner, E> {
                    Ok(Inner(0))
                }
                fn visit_unit<E>(self) -> Result<Inner, E> {
                    Ok(Inner(0))
                }
            }
            d.deserialize_any(V)
        }
    }
    impl<'de> serde::Deserialize<'de> for Outer {
        fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct V;
            impl<'de> serde::de::Visitor<'de> for V {
                type Value = Outer;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("an array")
                }
                fn visit_seq<A: serde::de::SeqAccess<'de>>(
                    self,
                    mut a: A,
                ) -> Result<Outer, A::Error> {
                    let (mut n, mut inner) = (0, 0);
                    while let Some(Inner(k)) = a.next_element()? {
                        n += 1;
                        inner += k;
                    }
                    Ok(Outer(n, inner))
                }
            }
            d.deserialize_seq(V)
        }
    }
    // Not an array: counted as empty; the key's parse says what is wrong.
    serde_json::from_str::<Outer>(v.get()).map_or((0, 0), |o| (o.0, o.1))
}

/// The size budget on the raw arrays of a frame, before they are parsed:
/// the facets the faces give (or the vertices, for faces traced from the
/// edges), and the vertices and edges a pattern within the budget can have.
fn check_budget(merged: &HashMap<&str, (&RawValue, String)>) -> Result<(), SceneError> {
    use crate::scene::build::{MAX_FACETS, facet_estimate, over_budget};
    let n = |key: &str| merged.get(key).map(|(v, _)| array_counts(v));
    let nv = n("vertices_coords").map_or(0, |c| c.0);
    let faces = n("faces_vertices");
    let estimate = facet_estimate(nv, faces.filter(|f| f.0 > 0));
    if estimate > MAX_FACETS {
        return Err(over_budget(
            "faces_vertices",
            estimate,
            "the pattern would triangulate into about",
        ));
    }
    // Sides of faces within the budget: fewer than 3 per facet; so are
    // their vertices and edges.
    let most = 3 * MAX_FACETS;
    for key in [
        "vertices_coords",
        "edges_vertices",
        "edges_assignment",
        "edges_foldAngle",
    ] {
        if let Some((len, _)) = n(key)
            && len > most
        {
            return Err(SceneError::invalid(
                key,
                format!(
                    "{len} entries; a pattern within the size budget of {MAX_FACETS} facets has \
                     at most {most} (docs/scenes.md, \"Size budget\")"
                ),
            ));
        }
    }
    Ok(())
}

/// Read the keys of one merged frame (`merged`: key -> raw value and the
/// prefix of the frame it comes from).
fn read_frame(
    merged: &HashMap<&str, (&RawValue, String)>,
) -> Result<(FoldFile, Vec<String>), SceneError> {
    check_budget(merged)?;
    let mut warnings = Vec::new();
    let mut out = FoldFile::default();
    let get = |key: &str| -> Result<Option<(Value, String)>, SceneError> {
        match merged.get(key) {
            Some((v, p)) => Ok(Some((value(v)?, format!("{p}{key}")))),
            None => Ok(None),
        }
    };

    if let Some((v, key)) = get("file_spec")? {
        out.file_spec = Some(expect_number(&v, &key)?);
    }
    let opt_string = |key: &str| -> Result<Option<String>, SceneError> {
        match get(key)? {
            Some((v, k)) => Ok(Some(expect_string(&v, &k)?.to_string())),
            None => Ok(None),
        }
    };
    out.file_creator = opt_string("file_creator")?;
    out.file_author = opt_string("file_author")?;
    out.file_title = opt_string("file_title")?;
    out.file_description = opt_string("file_description")?;
    out.frame_title = opt_string("frame_title")?;
    out.frame_unit = opt_string("frame_unit")?;
    for (field, key) in [
        (&mut out.file_classes, "file_classes"),
        (&mut out.frame_classes, "frame_classes"),
        (&mut out.frame_attributes, "frame_attributes"),
    ] {
        if let Some((v, k)) = get(key)? {
            *field = string_list(&v, &k)?;
        }
    }

    let (v, key) = get("vertices_coords")?.ok_or_else(|| {
        SceneError::invalid(
            "vertices_coords",
            "missing; a scene needs vertices_coords and faces_vertices",
        )
    })?;
    out.vertices_coords = read_coords(&v, &key)?;

    match get("faces_vertices")? {
        Some((v, key)) => out.faces_vertices = read_faces(&v, &key)?,
        None if !merged.contains_key("edges_vertices") => {
            return Err(SceneError::invalid(
                "faces_vertices",
                "missing, and so is edges_vertices; a scene needs the facets as \
                 counter-clockwise polygons in faces_vertices, or the crease pattern's \
                 edges in edges_vertices (the faces are then traced from them)",
            ));
        }
        None => {} // traced from edges_vertices by the scene builder
    }

    if let Some((v, key)) = get("edges_vertices")? {
        out.edges_vertices = Some(read_edges(&v, &key)?);
    }
    if let Some((v, key)) = get("edges_assignment")? {
        out.edges_assignment = Some(read_assignments(&v, &key)?);
    }
    let angles = match (get("edges_foldAngle")?, get("edges_foldAngles")?) {
        (Some(new), Some(_)) => {
            warnings.push(
                "edges_foldAngles (pre-1.1 spelling) is ignored because edges_foldAngle is present"
                    .to_string(),
            );
            Some(new)
        }
        (a, b) => a.or(b),
    };
    if let Some((v, key)) = angles {
        out.edges_fold_angle = Some(read_angles(&v, &key)?);
    }

    for (key, (v, _)) in merged {
        if key.starts_with("ancf:") {
            out.ancf.insert(key.to_string(), value(v)?);
        } else if !key.contains(':') && !KNOWN_KEYS.contains(key) {
            let hint = suggestion(key, KNOWN_KEYS);
            if !hint.is_empty() {
                warnings.push(format!("unknown key '{key}' is ignored{hint}"));
            }
        }
    }
    warnings.sort();
    Ok((out, warnings))
}

/// `vertices_coords`: 2 or 3 numbers per vertex.
fn read_coords(v: &Value, key: &str) -> Result<Vec<Vec<f64>>, SceneError> {
    let mut out = Vec::new();
    for (i, c) in expect_array(v, key)?.iter().enumerate() {
        let ki = format!("{key}[{i}]");
        let arr = expect_array(c, &ki)?;
        if arr.len() != 2 && arr.len() != 3 {
            return Err(SceneError::invalid(
                ki,
                format!("expected 2 or 3 coordinates, found {}", arr.len()),
            ));
        }
        let p = arr
            .iter()
            .enumerate()
            .map(|(j, x)| expect_number(x, &format!("{ki}[{j}]")))
            .collect::<Result<Vec<f64>, _>>()?;
        out.push(p);
    }
    Ok(out)
}

/// `faces_vertices`: a list of vertex indices per face.
fn read_faces(v: &Value, key: &str) -> Result<Vec<Vec<usize>>, SceneError> {
    let mut out = Vec::new();
    for (f, face) in expect_array(v, key)?.iter().enumerate() {
        let kf = format!("{key}[{f}]");
        let idx = expect_array(face, &kf)?
            .iter()
            .enumerate()
            .map(|(j, x)| expect_index(x, &format!("{kf}[{j}]")))
            .collect::<Result<Vec<usize>, _>>()?;
        out.push(idx);
    }
    Ok(out)
}

/// `edges_vertices`: two vertex indices per edge.
fn read_edges(v: &Value, key: &str) -> Result<Vec<[usize; 2]>, SceneError> {
    let mut edges = Vec::new();
    for (e, ev) in expect_array(v, key)?.iter().enumerate() {
        let ke = format!("{key}[{e}]");
        let arr = expect_array(ev, &ke)?;
        if arr.len() != 2 {
            return Err(SceneError::invalid(
                ke,
                format!("an edge has 2 vertices, found {}", arr.len()),
            ));
        }
        edges.push([
            expect_index(&arr[0], &format!("{ke}[0]"))?,
            expect_index(&arr[1], &format!("{ke}[1]"))?,
        ]);
    }
    Ok(edges)
}

/// `edges_assignment`: a letter per edge (null: unassigned).
fn read_assignments(v: &Value, key: &str) -> Result<Vec<Assignment>, SceneError> {
    let mut asg = Vec::new();
    for (e, a) in expect_array(v, key)?.iter().enumerate() {
        let ke = format!("{key}[{e}]");
        if a.is_null() {
            // FOLD tools write null for "not known": unassigned.
            asg.push(Assignment::Unassigned);
            continue;
        }
        let s = expect_string(a, &ke)?;
        asg.push(Assignment::from_letter(s).ok_or_else(|| {
            SceneError::invalid(
                ke,
                format!("unknown assignment \"{s}\"; expected one of M, V, F, J, B, U, C"),
            )
        })?);
    }
    Ok(asg)
}

/// `edges_foldAngle`: degrees per edge (null: not given).
fn read_angles(v: &Value, key: &str) -> Result<Vec<Option<f64>>, SceneError> {
    let mut out = Vec::new();
    for (e, a) in expect_array(v, key)?.iter().enumerate() {
        if a.is_null() {
            out.push(None);
        } else {
            out.push(Some(expect_number(a, &format!("{key}[{e}]"))?));
        }
    }
    Ok(out)
}

impl FoldFile {
    /// The FOLD JSON text: one key per line, one vertex, edge or face per
    /// line, keys in the order of the FOLD specification, `ancf:` keys last.
    pub fn to_json(&self) -> String {
        let mut entries: Vec<(String, String)> = Vec::new();
        let json = |v: &Value| serde_json::to_string(v).expect("JSON values serialize");
        let s = |x: &str| json(&Value::String(x.to_string()));
        entries.push((
            "file_spec".into(),
            json(&Value::from(self.file_spec.unwrap_or(1.2))),
        ));
        for (k, v) in [
            ("file_creator", &self.file_creator),
            ("file_author", &self.file_author),
            ("file_title", &self.file_title),
            ("file_description", &self.file_description),
        ] {
            if let Some(v) = v {
                entries.push((k.into(), s(v)));
            }
        }
        let list = |l: &[String]| json(&Value::from(l.to_vec()));
        if !self.file_classes.is_empty() {
            entries.push(("file_classes".into(), list(&self.file_classes)));
        }
        if let Some(t) = &self.frame_title {
            entries.push(("frame_title".into(), s(t)));
        }
        if !self.frame_classes.is_empty() {
            entries.push(("frame_classes".into(), list(&self.frame_classes)));
        }
        if !self.frame_attributes.is_empty() {
            entries.push(("frame_attributes".into(), list(&self.frame_attributes)));
        }
        if let Some(u) = &self.frame_unit {
            entries.push(("frame_unit".into(), s(u)));
        }
        let rows = |items: Vec<String>| {
            if items.is_empty() {
                return "[]".to_string();
            }
            format!("[\n    {}\n  ]", items.join(",\n    "))
        };
        let chunks = |items: Vec<String>, per_line: usize| {
            let lines: Vec<String> = items.chunks(per_line).map(|c| c.join(", ")).collect();
            rows(lines)
        };
        let num = |x: f64| json(&Value::from(x));
        entries.push((
            "vertices_coords".into(),
            rows(
                self.vertices_coords
                    .iter()
                    .map(|p| {
                        format!(
                            "[{}]",
                            p.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", ")
                        )
                    })
                    .collect(),
            ),
        ));
        if let Some(ev) = &self.edges_vertices {
            entries.push((
                "edges_vertices".into(),
                chunks(ev.iter().map(|[a, b]| format!("[{a}, {b}]")).collect(), 8),
            ));
        }
        if let Some(ea) = &self.edges_assignment {
            entries.push((
                "edges_assignment".into(),
                chunks(
                    ea.iter().map(|a| format!("\"{}\"", a.letter())).collect(),
                    20,
                ),
            ));
        }
        if let Some(fa) = &self.edges_fold_angle {
            entries.push((
                "edges_foldAngle".into(),
                chunks(
                    fa.iter()
                        .map(|a| a.map_or_else(|| "null".to_string(), num))
                        .collect(),
                    8,
                ),
            ));
        }
        entries.push((
            "faces_vertices".into(),
            rows(
                self.faces_vertices
                    .iter()
                    .map(|f| json(&Value::from(f.clone())))
                    .collect(),
            ),
        ));
        for (k, v) in &self.ancf {
            let pretty = serde_json::to_string_pretty(v).expect("JSON values serialize");
            entries.push((k.clone(), pretty.replace('\n', "\n  ")));
        }
        let mut out = String::from("{\n");
        for (i, (k, v)) in entries.iter().enumerate() {
            let sep = if i + 1 < entries.len() { "," } else { "" };
            let _ = writeln!(out, "  {}: {v}{sep}", s(k));
        }
        out.push_str("}\n");
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> SceneError {
        parse(text, None).unwrap_err()
    }

    #[test]
    fn malformed_json_has_line_and_column() {
        let e = err("{\n \"vertices_coords\": [[0, 0]\n");
        assert!(matches!(e, SceneError::Json { line: 3, .. }), "{e:?}");
        let e = err("{\"a\": tru}");
        assert!(matches!(e, SceneError::Json { line: 1, .. }), "{e:?}");
    }

    #[test]
    fn missing_required_arrays() {
        let e = err(r#"{"faces_vertices": []}"#);
        assert_eq!(e.key(), Some("vertices_coords"));
        let e = err(r#"{"vertices_coords": []}"#);
        assert_eq!(e.key(), Some("faces_vertices"));
        // edges without faces: the faces are traced later
        let (f, _) = parse(r#"{"vertices_coords": [], "edges_vertices": []}"#, None).unwrap();
        assert!(f.faces_vertices.is_empty() && f.edges_vertices.is_some());
        let e = err("[1, 2]");
        assert!(e.to_string().contains("JSON object"), "{e}");
    }

    #[test]
    fn type_errors_name_the_index() {
        let e = err(r#"{"vertices_coords": [[0,0],[1,"x"]], "faces_vertices": []}"#);
        assert_eq!(e.key(), Some("vertices_coords[1][1]"));
        assert!(e.to_string().contains("expected a number"), "{e}");
        let e = err(r#"{"vertices_coords": [[0,0,0,0]], "faces_vertices": []}"#);
        assert_eq!(e.key(), Some("vertices_coords[0]"));
        let e = err(r#"{"vertices_coords": [[0,0]], "faces_vertices": [[0, -1, 2]]}"#);
        assert_eq!(e.key(), Some("faces_vertices[0][1]"));
        assert!(e.to_string().contains("non-negative integer"), "{e}");
        let e = err(
            r#"{"vertices_coords": [[0,0]], "faces_vertices": [], "edges_vertices": [[0,1,2]]}"#,
        );
        assert_eq!(e.key(), Some("edges_vertices[0]"));
        let e = err(
            r#"{"vertices_coords": [[0,0]], "faces_vertices": [], "edges_assignment": ["M", "X"]}"#,
        );
        assert_eq!(e.key(), Some("edges_assignment[1]"));
        assert!(e.to_string().contains("unknown assignment \"X\""), "{e}");
    }

    #[test]
    fn old_angle_spelling_and_nulls() {
        let (f, w) = parse(
            r#"{"vertices_coords": [[0,0]], "faces_vertices": [], "edges_foldAngles": [null, 90, -45.5]}"#,
            None,
        )
        .unwrap();
        assert_eq!(
            f.edges_fold_angle,
            Some(vec![None, Some(90.0), Some(-45.5)])
        );
        assert!(w.is_empty());
        // integral floats are indices
        let (f, _) = parse(
            r#"{"vertices_coords": [[0,0]], "faces_vertices": [[0.0, 1, 2]]}"#,
            None,
        )
        .unwrap();
        assert_eq!(f.faces_vertices[0], vec![0, 1, 2]);
    }

    #[test]
    fn misspelt_keys_warn_and_unknown_keys_are_ignored() {
        let (_, w) = parse(
            r#"{"vertices_coords": [[0,0]], "faces_vertices": [], "edges_foldangle": [], "my_key": 1, "other:x": 2, "edges_edges": [], "faces_flatFoldOrientation": []}"#,
            None,
        )
        .unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("did you mean 'edges_foldAngle'"), "{w:?}");
    }

    #[test]
    fn frames_and_inheritance() {
        let text = r#"{
            "file_spec": 1.2, "ancf:refine": 1,
            "file_frames": [
                {"frame_title": "cp", "vertices_coords": [[0,0],[1,0],[0,1]], "faces_vertices": [[0,1,2]]},
                {"frame_title": "folded", "frame_inherit": true, "frame_parent": 1,
                 "vertices_coords": [[0,0,0],[1,0,0],[0,1,0]]},
                {"frame_inherit": true, "frame_parent": 3}
            ]}"#;
        // default: top level has no vertices, so the first of file_frames
        let (f, _) = parse(text, None).unwrap();
        assert_eq!(f.frame_title.as_deref(), Some("cp"));
        assert_eq!(f.ancf.len(), 1);
        let (f, _) = parse(text, Some(&FrameSelector::Title("folded".into()))).unwrap();
        assert_eq!(f.vertices_coords[1], vec![1.0, 0.0, 0.0]);
        assert_eq!(f.faces_vertices, vec![vec![0, 1, 2]]); // inherited
        let e = parse(text, Some(&FrameSelector::Index(3))).unwrap_err();
        assert!(e.to_string().contains("cycle"), "{e}");
        let e = parse(text, Some(&FrameSelector::Index(9))).unwrap_err();
        assert_eq!(e.key(), Some("file_frames"));
        let e = parse(text, Some(&FrameSelector::Title("nope".into()))).unwrap_err();
        assert!(e.to_string().contains("nope"), "{e}");
        // errors inside a frame name the frame
        let bad = r#"{"file_frames": [{"vertices_coords": [[0,"a"]], "faces_vertices": []}]}"#;
        let e = parse(bad, None).unwrap_err();
        assert_eq!(e.key(), Some("file_frames[0].vertices_coords[0][1]"));
    }

    #[test]
    fn writer_round_trips() {
        let f = FoldFile {
            file_creator: Some("test".into()),
            frame_classes: vec!["creasePattern".into()],
            frame_unit: Some("mm".into()),
            vertices_coords: vec![vec![0.0, 0.0], vec![1.5, 0.0], vec![0.1, 1.0 / 3.0]],
            edges_vertices: Some(vec![[0, 1], [1, 2], [2, 0]]),
            edges_assignment: Some(vec![Assignment::Boundary; 3]),
            edges_fold_angle: Some(vec![None, Some(-180.0), Some(12.25)]),
            faces_vertices: vec![vec![0, 1, 2]],
            ancf: serde_json::from_str(
                r#"{"ancf:refine": 2, "ancf:material": {"thickness": 1e-4}}"#,
            )
            .unwrap(),
            ..Default::default()
        };
        let text = f.to_json();
        let (g, w) = parse(&text, None).unwrap();
        assert!(w.is_empty());
        assert_eq!(g.file_spec, Some(1.2));
        let mut f2 = f.clone();
        f2.file_spec = Some(1.2);
        assert_eq!(g, f2);
    }
}
