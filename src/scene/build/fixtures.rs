//! What the loader's tests share: a two-square sheet with one valley
//! crease, and helpers to change a key, load, and read an error.

use crate::scene::{Scene, SceneError, from_str};
use serde_json::{Value, json};

/// Two unit squares side by side with the valley crease 1-4 (FOLD edge 6),
/// in metres.
pub(super) fn base() -> Value {
    json!({
        "file_spec": 1.2,
        "frame_unit": "m",
        "vertices_coords": [[0,0],[1,0],[2,0],[2,1],[1,1],[0,1]],
        "edges_vertices": [[0,1],[1,2],[2,3],[3,4],[4,5],[5,0],[1,4]],
        "edges_assignment": ["B","B","B","B","B","B","V"],
        "edges_foldAngle": [null,null,null,null,null,null,90],
        "faces_vertices": [[0,1,4,5],[1,2,3,4]]
    })
}
pub(super) fn with(mut v: Value, key: &str, x: Value) -> Value {
    v[key] = x;
    v
}
pub(super) fn load(v: &Value) -> Result<(Scene, Vec<String>), SceneError> {
    from_str(&v.to_string())
}
/// The error message, checked to start with `key: `.
pub(super) fn err(v: &Value, key: &str) -> String {
    let e = load(v).expect_err("should fail");
    assert_eq!(e.key(), Some(key), "{e}");
    e.to_string()
}
