//! A run's motion as a multi-frame FOLD file (`simulate --fold-out`): the
//! crease pattern at the top level, in metres, and one frame per output
//! with the simulated `vertices_coords` (3D, m) and `edges_foldAngle`
//! (degrees, valley positive), each inheriting the edges and faces from
//! the top level. Rabbit Ear, Origami Simulator and the FOLD library read
//! it; this crate reads it back as a folding sequence, one stage per frame
//! (docs/scenes.md, "Frames as keyframes").

use crate::ids::{FoldEdgeId, VertexId};
use crate::model::Model;
use crate::scene::FoldFile;
use serde_json::{Map, Value, json};
use std::io::Write;
use std::path::Path;

/// The frames recorded so far with the crease pattern they fold.
pub struct Motion {
    /// The top level: the crease pattern in the model's frame (metres).
    top: FoldFile,
    /// Number of FOLD edges (the length of each frame's angles).
    edges: usize,
    /// The frames as JSON objects, in time order.
    frames: Vec<Value>,
}

impl Motion {
    /// A motion of `model`, whose scene was read from the FOLD frame `cp`:
    /// the top level is `cp` with the model's flat reference coordinates
    /// (m, as the model reads the sheet), `frame_unit` "m", and its `ancf:`
    /// keys but the sequence and the import (a motion read back is a
    /// sequence of its frames, already in metres).
    pub fn new(cp: &FoldFile, model: &Model) -> Motion {
        let scene = model.scene();
        let mut top = cp.clone();
        top.vertices_coords = (0..scene.fold_vertex_count)
            .map(|i| {
                let x = scene.mesh.coord(VertexId(i));
                vec![x.x, x.y]
            })
            .collect();
        top.frame_unit = Some("m".into());
        top.file_creator = Some("origami-fmu simulate".into());
        if !top.file_classes.iter().any(|c| c == "animation") {
            top.file_classes.push("animation".into());
        }
        top.frame_classes = vec!["creasePattern".into()];
        top.frame_attributes = vec!["2D".into()];
        top.ancf.remove("ancf:sequence");
        top.ancf.remove("ancf:import");
        let edges = cp
            .edges_vertices
            .as_ref()
            .map_or(scene.fold_edge_count, Vec::len);
        Motion {
            top,
            edges,
            frames: Vec::new(),
        }
    }

    /// Record `model` now as a frame: every FOLD vertex's position and
    /// every FOLD edge's fold angle (its `crease[e].angle` for a crease, 0
    /// for other edges), in degrees.
    pub fn record(&mut self, model: &Model) {
        let scene = model.scene();
        let coords: Vec<Value> = (0..scene.fold_vertex_count)
            .map(|i| json!(model.vertex_position(VertexId(i))))
            .collect();
        let mut angles = vec![0.0; self.edges];
        for (FoldEdgeId(e), a) in model.crease_angles() {
            if let Some(x) = angles.get_mut(e) {
                *x = a.to_degrees();
            }
        }
        let mut frame = Map::new();
        frame.insert(
            "frame_title".into(),
            json!(format!("t = {} s", model.time())),
        );
        frame.insert("frame_parent".into(), json!(0));
        frame.insert("frame_inherit".into(), json!(true));
        frame.insert("frame_classes".into(), json!(["foldedForm"]));
        frame.insert("frame_attributes".into(), json!(["3D"]));
        frame.insert("vertices_coords".into(), Value::Array(coords));
        frame.insert("edges_foldAngle".into(), json!(angles));
        self.frames.push(Value::Object(frame));
    }

    /// Number of frames recorded.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether no frame is recorded.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The FOLD text: the top level one key per line, each frame on a line.
    pub fn to_json(&self) -> String {
        let top = self.top.to_json();
        let body = top.trim_end().trim_end_matches('}').trim_end();
        let mut out = String::with_capacity(top.len() + 64 * self.frames.len());
        out.push_str(body);
        out.push_str(",\n  \"file_frames\": [");
        for (k, f) in self.frames.iter().enumerate() {
            let sep = if k + 1 < self.frames.len() { "," } else { "" };
            out.push_str("\n    ");
            out.push_str(&serde_json::to_string(f).expect("JSON values serialize"));
            out.push_str(sep);
        }
        out.push_str("\n  ]\n}\n");
        out
    }

    /// Write the FOLD file to `path`.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
        f.write_all(self.to_json().as_bytes())?;
        f.flush()
    }
}
