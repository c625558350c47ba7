// Reads a multi-frame FOLD file (a `simulate --fold-out` motion) with the
// FOLD format's own library (npm `fold`) and with Rabbit Ear (npm
// `rabbit-ear`), frame by frame, and prints what they read as JSON: the
// frame count, and the last frame's vertices and fold angles. Exits 1
// naming the frame and what is wrong when a frame is not intact.
// Usage: NODE_PATH=.node/node_modules node tests/node/check_fold.js FILE
const fs = require('fs');
const FOLD = require('fold');
const ear = require('rabbit-ear');

function fail(msg) {
  console.error(`check_fold: ${msg}`);
  process.exit(1);
}

const file = JSON.parse(fs.readFileSync(process.argv[2], 'utf8'));
// The FOLD library writes it back (its own JSON writer) and reads the same.
const again = JSON.parse(FOLD.convert.toJSON(file));
if (JSON.stringify(again) !== JSON.stringify(file)) fail('FOLD.convert.toJSON changed the file');

// Frame k as the FOLD specification defines it: frame 0 the top level,
// frame k file_frames[k-1], with the keys it lacks from its frame_parent
// chain when frame_inherit is true.
const frames = [file].concat(file.file_frames || []);
function flat(k, seen = new Set()) {
  if (seen.has(k)) fail(`frame ${k}: frame_parent forms a cycle`);
  seen.add(k);
  const f = frames[k];
  const own = {};
  for (const key of Object.keys(f)) {
    if (key !== 'file_frames' && key !== 'frame_parent' && key !== 'frame_inherit') own[key] = f[key];
  }
  if (k === 0 || !f.frame_inherit) return own;
  const parent = f.frame_parent === undefined ? 0 : f.frame_parent;
  if (!(parent in frames)) fail(`frame ${k}: frame_parent ${parent} does not exist`);
  return Object.assign(flat(parent, seen), own);
}

const top = flat(0);
const nv = FOLD.filter.numVertices(top);
const ne = FOLD.filter.numEdges(top);
const nf = FOLD.filter.numFaces(top);
let agree = 0;
let checked = 0;
let last = null;
for (let k = 0; k < frames.length; k++) {
  const f = flat(k);
  const where = `frame ${k}`;
  // The FOLD library: counts, and the graph relations it derives.
  if (FOLD.filter.numVertices(f) !== nv) fail(`${where}: ${FOLD.filter.numVertices(f)} vertices, the crease pattern ${nv}`);
  if (FOLD.filter.numEdges(f) !== ne) fail(`${where}: ${FOLD.filter.numEdges(f)} edges, the crease pattern ${ne}`);
  if (FOLD.filter.numFaces(f) !== nf) fail(`${where}: ${FOLD.filter.numFaces(f)} faces, the crease pattern ${nf}`);
  const g = FOLD.convert.deepCopy(f);
  FOLD.convert.edges_vertices_to_vertices_vertices_unsorted(g);
  if (g.vertices_vertices.length !== nv) fail(`${where}: vertices_vertices has ${g.vertices_vertices.length} entries`);
  if (nf > 0) {
    FOLD.convert.faces_vertices_to_faces_edges(g);
    if (g.faces_edges.some(fe => fe.some(e => e === undefined))) fail(`${where}: a face side is not an edge`);
  }
  for (const p of f.vertices_coords) {
    if (!(p.length === 2 || p.length === 3) || !p.every(Number.isFinite)) fail(`${where}: a vertex is not 2 or 3 finite numbers`);
  }
  // Rabbit Ear: its graph of the frame.
  const r = ear.graph(f);
  if (r.vertices_coords.length !== nv || r.edges_vertices.length !== ne) fail(`${where}: Rabbit Ear's graph has other counts`);
  if (k > 0) {
    if (!ear.graph.isFoldedForm(f)) fail(`${where}: Rabbit Ear does not read it as a folded form`);
    const angles = f.edges_foldAngle;
    if (!angles || angles.length !== ne || !angles.every(Number.isFinite)) fail(`${where}: edges_foldAngle is not ${ne} finite numbers`);
    // Rabbit Ear's reading of each folded crease's angle against its letter.
    angles.forEach((a, e) => {
      const letter = top.edges_assignment && top.edges_assignment[e];
      if ((letter === 'M' || letter === 'V') && Math.abs(a) > 1) {
        checked += 1;
        if (ear.graph.edgeFoldAngleToAssignment(a) === letter) agree += 1;
      }
    });
    last = f;
  }
}
console.log(JSON.stringify({
  frames: frames.length - 1,
  vertices: nv,
  edges: ne,
  faces: nf,
  assignment_checked: checked,
  assignment_agree: agree,
  last_coords: last ? last.vertices_coords : null,
  last_angles: last ? last.edges_foldAngle : null,
}));
