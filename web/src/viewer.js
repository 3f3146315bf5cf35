// The viewcells web viewer: the scene, the view cells coloured by render cost or PVS size, and
// a chosen cell's PVS lit with the rest dimmed. Reads window.VIEWCELLS_DATA (data.js, written
// by `viewcells view`); bundled with three.js by esbuild into viewer.js.
// window.viewcells exposes the state for tests and scripts: ready, selected {point, cell, pvs},
// select(point), locate(point), pick(x, y), frameTimes(), drawn (frames drawn so far).
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

const D = window.VIEWCELLS_DATA;

function decode(text, Type) {
  const bin = atob(text);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
  return new Type(bytes.buffer);
}

// The colour scale of the toolkit's PNG and PLY views: blue, cyan, green, yellow, red.
function scale(t) {
  t = Math.min(1, Math.max(0, t));
  const c = (x) => Math.min(1, Math.max(0, x));
  return [c(Math.min(4 * t - 1.5, -4 * t + 4.5)), c(Math.min(4 * t - 0.5, -4 * t + 3.5)),
          c(Math.min(4 * t + 0.5, -4 * t + 2.5))];
}

// Point location in the .pvs file's BSP, by the toolkit's rule (points on a plane go to its
// negative side; outside the view box: -1).
const planes = D.bsp.planes, nodes = D.bsp.nodes, leafCell = D.bsp.leaf_cell, box = D.view_box;
function locate(p) {
  for (let k = 0; k < 3; ++k) if (!(p[k] >= box[k] && p[k] <= box[k + 3])) return -1;
  let n = 0;
  while (nodes[n][0] >= 0) {
    const [nx, ny, nz, offset, axis] = planes[nodes[n][0]];
    const d = axis >= 0 ? p[axis] - offset : nx * p[0] + ny * p[1] + nz * p[2] - offset;
    n = nodes[n][d > 0 ? 2 : 1];
  }
  return leafCell[n];
}

// --- scene ---------------------------------------------------------------------------------
const objects = {
  count: D.objects.count,
  triangles: decode(D.objects.triangles, Uint32Array),
  cost: decode(D.objects.cost, Float32Array),
  seeThrough: decode(D.objects.see_through, Uint8Array),
  firstVertex: decode(D.objects.first_vertex, Uint32Array),
  firstIndex: decode(D.objects.first_index, Uint32Array),
};
const scenePositions = decode(D.objects.positions, Float32Array);
const sceneIndices = decode(D.objects.indices, Uint32Array);
const sceneMaterial = new THREE.MeshLambertMaterial({ vertexColors: true, flatShading: true, side: THREE.DoubleSide });

// The scene in chunks of nearby objects (objects sorted along a Morton curve of their centres,
// about 32k triangles a chunk), each its own mesh: three.js skips the chunks outside the view,
// and a ray tests only the chunks whose bounds it meets.
const CHUNK_TRIANGLES = 32768;
const sceneBounds = new THREE.Box3();
const centres = new Float32Array(3 * objects.count);
for (let o = 0; o < objects.count; ++o) {
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let v = objects.firstVertex[o]; v < objects.firstVertex[o + 1]; ++v)
    for (let k = 0; k < 3; ++k) {
      lo[k] = Math.min(lo[k], scenePositions[3 * v + k]);
      hi[k] = Math.max(hi[k], scenePositions[3 * v + k]);
    }
  if (objects.firstVertex[o + 1] > objects.firstVertex[o]) {
    sceneBounds.expandByPoint(new THREE.Vector3(...lo));
    sceneBounds.expandByPoint(new THREE.Vector3(...hi));
  }
  for (let k = 0; k < 3; ++k) centres[3 * o + k] = (lo[k] + hi[k]) / 2;
}
function morton(o) {
  let code = 0;
  for (let k = 0; k < 3; ++k) {
    const lo = sceneBounds.min.getComponent(k), span = Math.max(1e-9, sceneBounds.max.getComponent(k) - lo);
    const q = Math.min(1023, Math.max(0, Math.floor(((centres[3 * o + k] - lo) / span) * 1024)));
    for (let b = 0; b < 10; ++b) code += ((q >> b) & 1) * 2 ** (3 * b + k);
  }
  return code;
}
const order = Array.from({ length: objects.count }, (_, o) => o);
const codes = order.map(morton);
order.sort((a, b) => codes[a] - codes[b] || a - b);

const chunks = [];
const objectChunk = new Int32Array(objects.count), objectVertex = new Uint32Array(objects.count),
      objectIndex = new Uint32Array(objects.count);
for (let at = 0; at < order.length;) {
  const ids = [];
  let vertices = 0, indices = 0;
  while (at < order.length && (ids.length === 0 || indices < 3 * CHUNK_TRIANGLES)) {
    const o = order[at++];
    ids.push(o);
    vertices += objects.firstVertex[o + 1] - objects.firstVertex[o];
    indices += objects.firstIndex[o + 1] - objects.firstIndex[o];
  }
  const positions = new Float32Array(3 * vertices), index = new Uint32Array(indices);
  let v = 0, i = 0;
  for (const o of ids) {
    const v0 = objects.firstVertex[o], v1 = objects.firstVertex[o + 1];
    objectChunk[o] = chunks.length;
    objectVertex[o] = v;
    objectIndex[o] = i;
    positions.set(scenePositions.subarray(3 * v0, 3 * v1), 3 * v);
    for (let k = objects.firstIndex[o]; k < objects.firstIndex[o + 1]; ++k) index[i++] = sceneIndices[k] - v0 + v;
    v += v1 - v0;
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(new Uint8Array(3 * vertices), 3, true));
  const fullIndex = new THREE.BufferAttribute(index, 1);
  geometry.setIndex(fullIndex);
  geometry.computeBoundingSphere();
  geometry.computeBoundingBox();
  chunks.push({ ids, geometry, fullIndex, mesh: new THREE.Mesh(geometry, sceneMaterial) });
}
const sceneGroup = new THREE.Group();
for (const c of chunks) sceneGroup.add(c.mesh);

function paintObject(o, rgb) {
  const colours = chunks[objectChunk[o]].geometry.attributes.color.array;
  const n = objects.firstVertex[o + 1] - objects.firstVertex[o];
  for (let v = objectVertex[o]; v < objectVertex[o] + n; ++v) {
    colours[3 * v] = rgb[0]; colours[3 * v + 1] = rgb[1]; colours[3 * v + 2] = rgb[2];
  }
}
const PLAIN = [190, 188, 180], GLASS = [120, 170, 220], LIT = [255, 214, 140], LIT_GLASS = [150, 220, 255],
      DIM = [52, 55, 62];
function paintScene(pvs) {
  const lit = pvs ? new Uint8Array(objects.count) : null;
  if (pvs) for (const o of pvs) lit[o] = 1;
  for (let o = 0; o < objects.count; ++o) {
    const glass = objects.seeThrough[o];
    paintObject(o, !pvs ? (glass ? GLASS : PLAIN) : lit[o] ? (glass ? LIT_GLASS : LIT) : DIM);
  }
  for (const c of chunks) c.geometry.attributes.color.needsUpdate = true;
}

// "Draw only the chosen cell's PVS": what an engine with this PVS would draw from there.
function drawOnly(pvs) {
  if (!pvs) {
    for (const c of chunks) { c.geometry.setIndex(c.fullIndex); c.mesh.visible = true; }
    return;
  }
  const byChunk = chunks.map(() => []);
  for (const o of pvs) byChunk[objectChunk[o]].push(o);
  chunks.forEach((c, k) => {
    const ids = byChunk[k];
    c.mesh.visible = ids.length > 0;
    let n = 0;
    for (const o of ids) n += objects.firstIndex[o + 1] - objects.firstIndex[o];
    const subset = new Uint32Array(n);
    let at = 0;
    for (const o of ids) {
      const count = objects.firstIndex[o + 1] - objects.firstIndex[o];
      subset.set(c.fullIndex.array.subarray(objectIndex[o], objectIndex[o] + count), at);
      at += count;
    }
    c.geometry.setIndex(new THREE.BufferAttribute(subset, 1));
  });
}
const sceneTrianglesDrawn = () =>
  chunks.reduce((sum, c) => sum + (c.mesh.visible ? c.geometry.index.count / 3 : 0), 0);

// --- cells ---------------------------------------------------------------------------------
const cells = {
  count: D.cells.count,
  pvs: D.cells.pvs,
  cost: decode(D.cells.cost, Float32Array),
  positions: decode(D.cells.positions, Float32Array),
  indices: decode(D.cells.indices, Uint32Array),
  firstVertex: decode(D.cells.first_vertex, Uint32Array),
  firstIndex: decode(D.cells.first_index, Uint32Array),
};
const cellGeometry = new THREE.BufferGeometry();
cellGeometry.setAttribute('position', new THREE.BufferAttribute(cells.positions, 3));
cellGeometry.setIndex(new THREE.BufferAttribute(cells.indices, 1));
const cellColours = new Float32Array(cells.positions.length);
cellGeometry.setAttribute('color', new THREE.BufferAttribute(cellColours, 3));
// The cutaway: everything above a horizontal plane is clipped away (roofs, ceilings, the upper
// storeys), and the cells' cross-sections at that height are drawn opaque in their colours,
// with the scene's own cross-section in dark lines: slice.png in 3D. The plane starts at the
// middle of the view box's height (as the PNG slice) and the panel's slider moves it.
const cut = new THREE.Plane(new THREE.Vector3(0, 0, -1), 0);
const clipping = [cut];
sceneMaterial.clippingPlanes = clipping;
// Cells pushed behind coplanar surfaces (polygon offset): no stripes where a cell's face meets a
// wall, a floor or the roof.
const cellMesh = new THREE.Mesh(cellGeometry, new THREE.MeshBasicMaterial({
  vertexColors: true, transparent: true, opacity: 0.22, depthWrite: false, side: THREE.DoubleSide,
  clippingPlanes: clipping, polygonOffset: true, polygonOffsetFactor: 2, polygonOffsetUnits: 2 }));
cellMesh.renderOrder = 1;

// Each cell's leaves: their vertices are consecutive and apart from the next leaf's, so a
// triangle whose lowest vertex lies beyond every vertex seen so far starts a leaf.
const cellLeaves = [];
for (let c = 0; c < cells.count; ++c) {
  const leaves = [];
  let seen = -1;
  for (let i = cells.firstIndex[c]; i < cells.firstIndex[c + 1]; i += 3) {
    const a = cells.indices[i], b = cells.indices[i + 1], d = cells.indices[i + 2];
    if (Math.min(a, b, d) > seen) leaves.push([]);
    leaves[leaves.length - 1].push(i);
    seen = Math.max(seen, a, b, d);
  }
  cellLeaves.push(leaves);
}
// The convex polygon where the plane z = h crosses a convex leaf (its triangles' edges that
// straddle the plane, hull of the crossings), as a fan of triangles.
function hull2(points) {
  const p = points.slice().sort((u, v) => u[0] - v[0] || u[1] - v[1]);
  const cross = (o, a, b) => (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  const lower = [], upper = [];
  for (const q of p) { while (lower.length >= 2 && cross(lower[lower.length - 2], lower[lower.length - 1], q) <= 0) lower.pop(); lower.push(q); }
  for (const q of p.reverse()) { while (upper.length >= 2 && cross(upper[upper.length - 2], upper[upper.length - 1], q) <= 0) upper.pop(); upper.push(q); }
  return lower.slice(0, -1).concat(upper.slice(0, -1));
}
function crossings(positions, indices, triangles, h, out) {
  for (const i of triangles)
    for (let e = 0; e < 3; ++e) {
      const a = indices[i + e], b = indices[i + (e + 1) % 3];
      const za = positions[3 * a + 2], zb = positions[3 * b + 2];
      if ((za < h) === (zb < h)) continue;
      const t = (h - za) / (zb - za);
      out.push([positions[3 * a] + t * (positions[3 * b] - positions[3 * a]),
                positions[3 * a + 1] + t * (positions[3 * b + 1] - positions[3 * a + 1])]);
    }
  return out;
}
const sectionMaterial = new THREE.MeshBasicMaterial({ vertexColors: true, side: THREE.DoubleSide });
const sectionMesh = new THREE.Mesh(new THREE.BufferGeometry(), sectionMaterial);
const sceneSection = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x101010 }));
sectionMesh.renderOrder = 3;
sceneSection.renderOrder = 4;
let sectionCells = [];  // the cells the plane crosses
function buildSections(h) {
  cut.constant = h;
  const pos = [], col = [];
  sectionCells = [];
  for (let c = 0; c < cells.count; ++c) {
    let crossed = false;
    for (const leaf of cellLeaves[c]) {
      const ring = hull2(crossings(cells.positions, cells.indices, leaf, h, []));
      if (ring.length < 3) continue;
      crossed = true;
      for (let k = 1; k + 1 < ring.length; ++k)
        for (const q of [ring[0], ring[k], ring[k + 1]]) {
          pos.push(q[0], q[1], h);
          col.push(cellColours[3 * cells.firstVertex[c]], cellColours[3 * cells.firstVertex[c] + 1],
                   cellColours[3 * cells.firstVertex[c] + 2]);
        }
    }
    if (crossed) sectionCells.push(c);
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(pos), 3));
  g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(col), 3));
  sectionMesh.geometry.dispose();
  sectionMesh.geometry = g;
  // The scene's walls where the plane cuts them, lifted a hair so that they lie on the sections.
  const lines = [];
  const lift = 1e-4 * Math.max(1, Math.abs(h));
  for (let o = 0; o < objects.count; ++o) {
    const tris = [];
    for (let i = objects.firstIndex[o]; i < objects.firstIndex[o + 1]; i += 3) tris.push(i);
    const pts = crossings(scenePositions, sceneIndices, tris, h, []);
    for (let k = 0; k + 1 < pts.length; k += 2) lines.push(pts[k][0], pts[k][1], h + lift, pts[k + 1][0], pts[k + 1][1], h + lift);
  }
  const lg = new THREE.BufferGeometry();
  lg.setAttribute('position', new THREE.BufferAttribute(new Float32Array(lines), 3));
  sceneSection.geometry.dispose();
  sceneSection.geometry = lg;
}

function cellValue(c, mode) { return mode === 'pvs' ? cells.pvs[c].length : cells.cost[c]; }
function paintCells(mode) {
  let max = 0;
  for (let c = 0; c < cells.count; ++c) max = Math.max(max, cellValue(c, mode));
  max = max > 0 ? max : 1;
  for (let c = 0; c < cells.count; ++c) {
    const rgb = scale(cellValue(c, mode) / max);
    for (let v = cells.firstVertex[c]; v < cells.firstVertex[c + 1]; ++v) cellColours.set(rgb, 3 * v);
  }
  cellGeometry.attributes.color.needsUpdate = true;
  if (cutaway.checked) buildSections(Number(cutSlider.value));
  document.getElementById('range').textContent = mode === 'pvs'
    ? `PVS size: 0 to ${max} objects`
    : `r(PVS) = sum of max(${D.cost_model.a}, ${D.cost_model.b} × triangles): 0 to ${Math.round(max)}`;
}

// The chosen cell, drawn on its own: translucent white and its edges.
const selectedGroup = new THREE.Group();
function showSelectedCell(c) {
  selectedGroup.clear();
  if (c < 0) return;
  const v0 = cells.firstVertex[c], v1 = cells.firstVertex[c + 1];
  const i0 = cells.firstIndex[c], i1 = cells.firstIndex[c + 1];
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(cells.positions.slice(3 * v0, 3 * v1), 3));
  g.setIndex(Array.from(cells.indices.subarray(i0, i1), (i) => i - v0));
  const fill = new THREE.Mesh(g, new THREE.MeshBasicMaterial({
    color: 0xffffff, transparent: true, opacity: 0.25, depthWrite: false, side: THREE.DoubleSide,
    clippingPlanes: clipping }));
  fill.renderOrder = 2;
  selectedGroup.add(fill);
  selectedGroup.add(new THREE.LineSegments(new THREE.EdgesGeometry(g),
                                           new THREE.LineBasicMaterial({ color: 0xffffff, clippingPlanes: clipping })));
}

// --- view ----------------------------------------------------------------------------------
const container = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.localClippingEnabled = true;
// The resolution is the panel's choice (#scale in the address): drawing half or a quarter of
// the pixels is what keeps software WebGL (no GPU) moving on a large level.
const pixelRatio = () => (window.devicePixelRatio || 1) * Number(document.getElementById('scale').value);
renderer.setPixelRatio(pixelRatio());
renderer.setSize(container.clientWidth, container.clientHeight);
container.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x15171c);
scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.4);
sun.position.set(0.4, -0.6, 1);
scene.add(sun, sceneGroup, cellMesh, selectedGroup, sectionMesh, sceneSection);

// The play space (where the bake assumed players stand): its floors in green, a little above
// them, clipped by the cutaway like the scene. Absent in data from before it (format 1 without
// play_space) and on maps (their play space is BSP leaves).
const playData = D.play_space || { rule: '', positions: '', indices: '' };
const playIndices = playData.indices ? decode(playData.indices, Uint32Array) : new Uint32Array(0);
const playMesh = new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshBasicMaterial({
  color: 0x33d94d, transparent: true, opacity: 0.45, depthWrite: false, side: THREE.DoubleSide,
  clippingPlanes: clipping }));
if (playIndices.length) {
  playMesh.geometry.setAttribute('position',
    new THREE.BufferAttribute(decode(playData.positions, Float32Array), 3));
  playMesh.geometry.setIndex(new THREE.BufferAttribute(playIndices, 1));
}
playMesh.renderOrder = 2;
scene.add(playMesh);

// The cut's controls: on by default at the middle of the view box's height; #cut=Z or #cut=off.
const cutaway = document.getElementById('cutaway'), cutSlider = document.getElementById('cut');
cutSlider.min = box[2];
cutSlider.max = box[5];
cutSlider.step = (box[5] - box[2]) / 200;
{
  const asked = new URLSearchParams(location.hash.slice(1)).get('cut');
  cutaway.checked = asked !== 'off';
  const z = Number(asked);
  cutSlider.value = asked !== null && asked !== 'off' && Number.isFinite(z) ? z : (box[2] + box[5]) / 2;
}
function applyCut() {
  const on = cutaway.checked;
  cutSlider.disabled = !on;
  document.getElementById('cutz').textContent = on ? `z = ${Number(cutSlider.value).toFixed(2)}` : 'off';
  clipping.length = 0;
  if (on) clipping.push(cut);
  sceneSection.visible = on;
  sectionMesh.visible = on && cellsMode() !== 'none';
  if (on) buildSections(Number(cutSlider.value));
  for (const m of [sceneMaterial, cellMesh.material, playMesh.material]) m.needsUpdate = true;
  dirty = true;
}

const size = new THREE.Vector3(), centre = new THREE.Vector3();
sceneBounds.getSize(size); sceneBounds.getCenter(centre);
const diagonal = size.length();
const camera = new THREE.PerspectiveCamera(60, container.clientWidth / container.clientHeight,
                                           diagonal * 1e-4, diagonal * 10);
camera.up.set(0, 0, 1);
const controls = new OrbitControls(camera, renderer.domElement);

// The start view: #camera=x,y,z&target=x,y,z in the address, else from above one corner.
const hash = new URLSearchParams(location.hash.slice(1));
const vec = (s) => { const v = (s || '').split(',').map(Number); return v.length === 3 && v.every(Number.isFinite) ? v : null; };
// From above one corner, looking down at the cut (or at the middle without it).
const lookAt = [(box[0] + box[3]) / 2, (box[1] + box[4]) / 2, cutaway.checked ? Number(cutSlider.value) : centre.z];
const target = vec(hash.get('target')) || lookAt;
const eye = vec(hash.get('camera')) ||
    [lookAt[0] - 0.3 * size.x, lookAt[1] - 0.55 * size.y, lookAt[2] + 0.9 * Math.max(size.x, size.y)];
camera.position.fromArray(eye);
controls.target.fromArray(target);
controls.update();

window.addEventListener('resize', () => {
  camera.aspect = container.clientWidth / container.clientHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(container.clientWidth, container.clientHeight);
});

// --- choosing a cell -----------------------------------------------------------------------
const state = { ready: false, selected: null, follow: false };
const totalTriangles = objects.triangles.reduce((a, b) => a + b, 0);
const fmt = (x) => x.toLocaleString('en-US', { maximumFractionDigits: 0 });

const drawMode = () => document.getElementById('draw').value;
function select(point) {
  const chosen = selectCell(point);
  drawOnly(drawMode() === 'pvs' && chosen && chosen.cell >= 0 ? chosen.pvs : null);
  dirty = true;
  return chosen;
}
function selectCell(point) {
  const cell = point ? locate(point) : -1;
  if (!point) {
    state.selected = null;
    paintScene(null);
    showSelectedCell(-1);
    document.getElementById('selection').textContent = 'Nothing chosen.';
    return state.selected;
  }
  const p = point.map((x) => +x.toFixed(4));
  if (cell < 0) {
    state.selected = { point: p, cell: -1, pvs: [] };
    paintScene(null);
    showSelectedCell(-1);
    document.getElementById('selection').textContent = `(${p.join(', ')}) is outside the view space.`;
    return state.selected;
  }
  const pvs = cells.pvs[cell];
  let triangles = 0, cost = 0;
  for (const o of pvs) { triangles += objects.triangles[o]; cost += objects.cost[o]; }
  state.selected = { point: p, cell, pvs: pvs.slice() };
  paintScene(pvs);
  showSelectedCell(cellsMode() === 'none' ? -1 : cell);
  cellMesh.visible = cellsMode() === 'all';
  document.getElementById('selection').textContent =
      `cell ${cell} of ${cells.count} at (${p.join(', ')})\n` +
      `sees ${fmt(pvs.length)} of ${fmt(objects.count)} objects, ` +
      `${fmt(triangles)} of ${fmt(totalTriangles)} triangles\n` +
      `r(PVS) = ${fmt(cost)}`;
  return state.selected;
}

const cellsMode = () => document.getElementById('cells').value;
document.getElementById('cells').addEventListener('change', () => {
  cellMesh.visible = cellsMode() === 'all';
  sectionMesh.visible = cutaway.checked && cellsMode() !== 'none';
  showSelectedCell(state.selected && cellsMode() !== 'none' ? state.selected.cell : -1);
  dirty = true;
});
document.getElementById('colour').addEventListener('change', (e) => { paintCells(e.target.value); dirty = true; });
document.getElementById('draw').addEventListener('change', () => {
  const sel = state.selected;
  drawOnly(drawMode() === 'pvs' && sel && sel.cell >= 0 ? sel.pvs : null);
  dirty = true;
});
const follow = document.getElementById('follow');
follow.addEventListener('change', () => { state.follow = follow.checked; lastFollowCell = null; dirty = true; });

const raycaster = new THREE.Raycaster();
// A click (not a drag) on a surface: the viewpoint is a little in front of the surface, on the
// ray towards the camera.
// pick(x, y): the point in front of the surface under normalised device coordinates (x, y),
// chosen and returned, or null when the ray hits nothing.
function pick(x, y) {
  raycaster.setFromCamera(new THREE.Vector2(x, y), camera);
  const hit = raycaster.intersectObjects(chunks.filter((c) => c.mesh.visible).map((c) => c.mesh), false)[0];
  if (!hit) return null;
  const back = Math.min(hit.distance * 0.5, diagonal * 0.002);
  const p = hit.point.clone().addScaledVector(raycaster.ray.direction, -back);
  follow.checked = state.follow = false;
  return select(p.toArray());
}
let down = null;
renderer.domElement.addEventListener('pointerdown', (e) => { down = [e.clientX, e.clientY]; });
renderer.domElement.addEventListener('pointerup', (e) => {
  if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
  const r = renderer.domElement.getBoundingClientRect();
  pick(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1);
});
window.addEventListener('keydown', (e) => {
  if (e.key === 'Escape') select(null);
  if (e.key === 'f' || e.key === 'F') { follow.checked = state.follow = !state.follow; lastFollowCell = null; dirty = true; }
});

// --- frames ---------------------------------------------------------------------------------
// A frame is drawn when something changed (the camera, a choice, the window), or on every
// animation frame with #spin=1 (turning about the target) or #spin=eye (turning on the spot),
// for measuring. frameTimes() are
// the times between drawn frames that followed each other.
const frameTimes = [];
let last = null, lastFollowCell = null, dirty = true, drawn = 0;
const spin = hash.get('spin');
controls.addEventListener('change', () => { dirty = true; });
window.addEventListener('resize', () => { dirty = true; });
function frame(now) {
  requestAnimationFrame(frame);
  if (spin === '1' || spin === 'eye') {
    const [pivot, moved] = spin === 'eye' ? [camera.position, controls.target] : [controls.target, camera.position];
    const o = moved.clone().sub(pivot).applyAxisAngle(new THREE.Vector3(0, 0, 1), 0.01);
    moved.copy(pivot).add(o);
    dirty = true;
  }
  controls.update();
  if (state.follow) {
    const p = camera.position.toArray();
    const c = locate(p);
    if (c !== lastFollowCell) { lastFollowCell = c; select(p); }
  }
  if (!dirty) { last = null; return; }
  dirty = false;
  renderer.render(scene, camera);
  ++drawn;
  if (last !== null) frameTimes.push(now - last);
  if (frameTimes.length > 240) frameTimes.shift();
  last = now;
  if (frameTimes.length && frameTimes.length % 10 === 0) {
    const recent = frameTimes.slice(-30);
    document.getElementById('fps').textContent =
        `${(recent.reduce((a, b) => a + b, 0) / recent.length).toFixed(1)} ms per frame`;
  }
}

document.getElementById('title').textContent = `viewcells: ${D.scene.split('/').pop()}`;
document.getElementById('summary').textContent =
    `${fmt(cells.count)} view cells (${D.rule}) · ${fmt(objects.count)} objects · ${fmt(totalTriangles)} triangles`;
// #cells=all|selected|none and #colour=cost|pvs in the address set the panel's choices.
for (const [key, id] of [['cells', 'cells'], ['colour', 'colour'], ['draw', 'draw'], ['scale', 'scale']]) {
  const value = hash.get(key), el = document.getElementById(id);
  if (value && [...el.options].some((o) => o.value === value)) el.value = value;
}
cellMesh.visible = cellsMode() === 'all';
sectionMesh.visible = cutaway.checked && cellsMode() !== 'none';
renderer.setPixelRatio(pixelRatio());
document.getElementById('scale').addEventListener('change', () => {
  renderer.setPixelRatio(pixelRatio());
  dirty = true;
});
if (hash.get('follow') === '1') follow.checked = state.follow = true;
paintScene(null);
paintCells(document.getElementById('colour').value);
cutaway.addEventListener('change', applyCut);
cutSlider.addEventListener('input', applyCut);
applyCut();
// #play=0 hides the play space; the checkbox is off and says why when there is none.
{
  const box = document.getElementById('play'), why = document.getElementById('playrule');
  box.checked = playIndices.length > 0 && hash.get('play') !== '0';
  box.disabled = playIndices.length === 0;
  why.textContent = playIndices.length ? '' : (playData.rule ? `(none: ${playData.rule})` : '(none)');
  why.title = playData.rule;
  playMesh.visible = box.checked;
  box.addEventListener('change', () => { playMesh.visible = box.checked; dirty = true; });
}
window.viewcells = {
  get ready() { return state.ready; },
  get selected() { return state.selected; },
  select, locate, pick,
  frameTimes: () => frameTimes.slice(),
  get drawn() { return drawn; },
  get sceneTrianglesDrawn() { return sceneTrianglesDrawn(); },
  get chunks() { return chunks.length; },
  // The cutaway: its height (null when off), the cells its plane crosses, and each cell's
  // colour as the page draws it (8-bit sRGB), for tests.
  get cut() { return cutaway.checked ? Number(cutSlider.value) : null; },
  get sectionCells() { return sectionCells.slice(); },
  get cellCount() { return cells.count; },
  // The play space's floors: triangles, and whether they are drawn.
  get playSpace() { return { triangles: playIndices.length / 3, visible: playMesh.visible, rule: playData.rule }; },
  cellColour: (c) => {
    const v = 3 * cells.firstVertex[c];
    const col = new THREE.Color(cellColours[v], cellColours[v + 1], cellColours[v + 2]).convertLinearToSRGB();
    return [col.r, col.g, col.b].map((x) => Math.round(255 * x));
  },
  camera, controls,
};
requestAnimationFrame((t) => { frame(t); state.ready = true; });
