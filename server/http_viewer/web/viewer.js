// objmap's web viewer: the map server's structure and objects in 3D, the inventory, each
// object's scores and the keyframe crops that saw it, removed objects as ghosts and the old
// places of moved ones (changes since a chosen session); follows the live map through
// /api/changes (a long poll) and asks /api/is_free for a box the user draws.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const STRUCTURE_REFRESH_MS = 2000;  // the structure is reloaded at most this often
const OBJECT_POINT_SIZE = 0.007;    // metres: 5 mm models, drawn a little larger to read as solid
const PICK_THRESHOLD = 0.012;       // metres around a model point that a click still hits
const MAX_CROPS = 12;

// What tests and curious users can read from the console: window.objmapViewer.
const state = {
  ready: false, error: null, version: 0, keyframes: 0, source: '',
  map: null,                 // the last /api/map answer
  objects: new Map(),        // id -> {summary, points (THREE.Points), box (THREE.LineSegments)}
  selected: null,            // id of the object shown in the panel
  updates: 0,                // map answers applied (1 after the first load)
  structureLoads: 0,         // structure answers requested
  frames: 0,                 // frames drawn
  ghosts: [],                // {kind: 'removed' | 'moved_from', id, objects: [THREE.Object3D]}
};
window.objmapViewer = state;

const sceneElement = document.getElementById('scene');
let renderer;
try {
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
} catch (error) {
  fail('WebGL is not available in this browser: ' + error.message);
  throw error;
}
renderer.setPixelRatio(window.devicePixelRatio);
sceneElement.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f4f2);
const camera = new THREE.PerspectiveCamera(55, 1, 0.01, 200);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;
const raycaster = new THREE.Raycaster();
raycaster.params.Points.threshold = PICK_THRESHOLD;
let structure = null;        // THREE.Points
let structureLoadedAt = 0;
let structureTimer = null;
let framed = false;
let freeBox = null;          // THREE.Box3Helper of the IsFree box
const corners = [];          // shift-clicked points

function fail(message) {
  state.error = message;
  const note = document.createElement('div');
  note.className = 'error';
  note.textContent = message;
  sceneElement.appendChild(note);
  document.getElementById('status').textContent = message;
}

function resize() {
  const width = sceneElement.clientWidth, height = sceneElement.clientHeight;
  renderer.setSize(width, height);
  camera.aspect = width / Math.max(1, height);
  camera.updateProjectionMatrix();
  requestRender();
}
// Drawn when something changed (the camera, the scene, the size), not continuously: an idle
// viewer costs no CPU, which matters where WebGL runs in software.
let renderQueued = false;
function requestRender() {
  if (renderQueued) return;
  renderQueued = true;
  requestAnimationFrame(() => {
    renderQueued = false;
    renderer.render(scene, camera);
    state.frames += 1;
  });
}
controls.addEventListener('change', requestRender);
window.addEventListener('resize', resize);
resize();

async function fetchJson(url, options) {
  const response = await fetch(url, options);
  const body = await response.json();
  if (!response.ok) throw new Error(body.error || response.statusText);
  return body;
}

async function fetchBytes(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error((await response.json()).error || response.statusText);
  return response.arrayBuffer();
}

// ---------------------------------------------------------------- structure

function upVector() {
  const up = state.map && state.map.up;
  return up ? new THREE.Vector3(up[0], up[1], up[2]).normalize() : new THREE.Vector3(0, 0, 1);
}

async function loadStructure() {
  structureLoadedAt = Date.now();
  state.structureLoads += 1;
  const response = await fetch('/api/structure');
  if (!response.ok) throw new Error((await response.json()).error);
  const voxel = parseFloat(response.headers.get('X-Objmap-Voxel-Size')) || 0.01;
  const positions = new Float32Array(await response.arrayBuffer());
  // Grey by height along up: the floor dark, the table tops lighter.
  const up = upVector();
  const count = positions.length / 3;
  const heights = new Float32Array(count);
  let low = Infinity, high = -Infinity;
  for (let i = 0; i < count; ++i) {
    heights[i] = positions[3 * i] * up.x + positions[3 * i + 1] * up.y + positions[3 * i + 2] * up.z;
    low = Math.min(low, heights[i]);
    high = Math.max(high, heights[i]);
  }
  const colours = new Float32Array(positions.length);
  for (let i = 0; i < count; ++i) {
    const g = 0.35 + 0.45 * (heights[i] - low) / Math.max(1e-6, high - low);
    colours[3 * i] = colours[3 * i + 1] = colours[3 * i + 2] = g;
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
  const points = new THREE.Points(geometry, new THREE.PointsMaterial({ size: voxel, vertexColors: true }));
  points.name = 'structure';
  if (structure) {
    scene.remove(structure);
    structure.geometry.dispose();
  }
  structure = points;
  scene.add(structure);
  if (!framed && count > 0) frame(geometry);
  requestRender();
}

function scheduleStructure() {
  if (structureTimer) return;
  const wait = Math.max(0, STRUCTURE_REFRESH_MS - (Date.now() - structureLoadedAt));
  structureTimer = setTimeout(() => {
    structureTimer = null;
    loadStructure().catch((error) => status('structure: ' + error.message));
  }, wait);
}

// The camera above the map, looking at its centre from one side, up kept up.
function frame(geometry) {
  geometry.computeBoundingSphere();
  const sphere = geometry.boundingSphere;
  const up = upVector();
  camera.up.copy(up);
  const side = Math.abs(up.z) < 0.9 ? new THREE.Vector3(0, 0, 1) : new THREE.Vector3(1, 0, 0);
  side.projectOnPlane(up).normalize();
  const distance = sphere.radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 0.8;
  camera.position.copy(sphere.center).addScaledVector(side, distance * 0.7).addScaledVector(up, distance * 0.7);
  camera.near = Math.max(0.01, distance / 1000);
  camera.far = distance * 10;
  camera.updateProjectionMatrix();
  controls.target.copy(sphere.center);
  controls.update();
  framed = true;
}

// ---------------------------------------------------------------- objects

function shown(summary) {
  return summary.in_inventory || document.getElementById('show-candidates').checked;
}

async function loadObject(summary) {
  const bytes = await fetchBytes(`/api/objects/${summary.id}/model`);
  const count = bytes.byteLength / 15;
  const positions = new Float32Array(bytes, 0, count * 3);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions.slice(), 3));
  const colour = new THREE.Color(summary.colour);
  const points = new THREE.Points(geometry, new THREE.PointsMaterial({ size: OBJECT_POINT_SIZE, color: colour }));
  points.name = `object ${summary.id}`;
  points.userData.objectId = summary.id;
  const box = new THREE.Box3(new THREE.Vector3(...summary.min), new THREE.Vector3(...summary.max));
  const outline = new THREE.Box3Helper(box, colour);
  return { summary, points, outline };
}

function removeObject(id) {
  const entry = state.objects.get(id);
  if (!entry) return;
  scene.remove(entry.points, entry.outline);
  entry.points.geometry.dispose();
  state.objects.delete(id);
  requestRender();
}

// Brings the scene to `map`: new and changed objects (re)loaded, gone ones removed.
async function applyObjects(map) {
  const wanted = new Map(map.objects.filter(shown).map((summary) => [summary.id, summary]));
  for (const id of [...state.objects.keys()]) if (!wanted.has(id)) removeObject(id);
  const loads = [];
  for (const summary of wanted.values()) {
    const entry = state.objects.get(summary.id);
    if (entry && entry.summary.changed_version === summary.changed_version) continue;
    loads.push(loadObject(summary).then((loaded) => {
      removeObject(summary.id);
      scene.add(loaded.points, loaded.outline);
      state.objects.set(summary.id, loaded);
      requestRender();
    }, (error) => status(`object ${summary.id}: ${error.message}`)));
  }
  await Promise.all(loads);
}

// ---------------------------------------------------------------- changes

const GHOST_COLOUR = 0x8a8a8a;

// The first session whose changes are shown (0: every session).
function changesSince() {
  return Number(document.getElementById('change-session').value) || 0;
}

// A translucent box with a dashed outline where an object was.
function ghostBox(min, max, colour) {
  const box = new THREE.Box3(new THREE.Vector3(...min), new THREE.Vector3(...max));
  const size = box.getSize(new THREE.Vector3());
  const centre = box.getCenter(new THREE.Vector3());
  const fill = new THREE.Mesh(new THREE.BoxGeometry(size.x, size.y, size.z),
    new THREE.MeshBasicMaterial({ color: colour, transparent: true, opacity: 0.18, depthWrite: false }));
  fill.position.copy(centre);
  const edges = new THREE.LineSegments(new THREE.EdgesGeometry(fill.geometry),
    new THREE.LineDashedMaterial({ color: colour, dashSize: 0.02, gapSize: 0.015 }));
  edges.position.copy(centre);
  edges.computeLineDistances();
  return [fill, edges];
}

// Ghosts of removed objects and of the places moved objects left, for changes seen in the
// selected session or later; an arrow-like line from each old place to where the object is now.
function applyGhosts(map) {
  for (const ghost of state.ghosts) {
    scene.remove(...ghost.objects);
    for (const object of ghost.objects) object.geometry.dispose();
  }
  state.ghosts = [];
  const since = changesSince();
  for (const tombstone of map.tombstones || []) {
    if (!tombstone.removed || tombstone.removed.session < since) continue;
    const objects = ghostBox(tombstone.min, tombstone.max, GHOST_COLOUR);
    state.ghosts.push({ kind: 'removed', id: tombstone.id, objects });
  }
  for (const object of map.objects) {
    for (const place of object.previous_places || []) {
      if (place.seen_empty.session < since) continue;
      const objects = ghostBox(place.min, place.max, new THREE.Color(object.colour).getHex());
      const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints([
        new THREE.Vector3(...place.centroid), new THREE.Vector3(...object.centroid)]),
      new THREE.LineBasicMaterial({ color: new THREE.Color(object.colour) }));
      objects.push(line);
      state.ghosts.push({ kind: 'moved_from', id: object.id, objects });
    }
  }
  for (const ghost of state.ghosts) scene.add(...ghost.objects);
  requestRender();
}

function renderChanges(map) {
  const select = document.getElementById('change-session');
  const chosen = select.value;
  const options = ['<option value="0">every session</option>'].concat(
    (map.sessions || []).map((id) => `<option value="${id}">session ${id} and later</option>`));
  if (select.dataset.sessions !== options.join('')) {
    select.innerHTML = options.join('');
    select.dataset.sessions = options.join('');
    if ([...select.options].some((o) => o.value === chosen)) select.value = chosen;
  }
  const since = changesSince();
  const body = document.querySelector('#changes tbody');
  body.innerHTML = '';
  for (const change of (map.changes || []).filter((c) => c.seen.session >= since)) {
    const row = document.createElement('tr');
    row.dataset.kind = change.kind;
    row.innerHTML = `<td>${change.kind}</td><td></td><td>${change.class}</td><td>${change.seen.session}</td>`;
    row.children[1].appendChild(objectLink(change.id));
    body.appendChild(row);
  }
}
document.getElementById('change-session').addEventListener('change', () => {
  if (!state.map) return;
  renderChanges(state.map);
  applyGhosts(state.map);
});

// ---------------------------------------------------------------- panel

function status(text) { document.getElementById('status').textContent = text; }

function objectLink(id) {
  const link = document.createElement('a');
  link.className = 'object-link';
  link.textContent = '#' + id;
  link.addEventListener('click', () => select(id));
  return link;
}

function renderInventory(map) {
  const body = document.querySelector('#inventory tbody');
  body.replaceChildren();
  document.getElementById('inventory').dataset.version = map.version;
  for (const entry of map.inventory) {
    const row = body.insertRow();
    row.dataset.class = entry.class;
    row.dataset.count = entry.count;
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = entry.colour;
    row.insertCell().append(swatch);
    row.insertCell().textContent = entry.class;
    row.insertCell().textContent = entry.count;
    row.insertCell().append(...entry.objects.map(objectLink));
  }
  document.getElementById('source').textContent = map.source;
  const total = map.inventory.reduce((sum, entry) => sum + entry.count, 0);
  status(`version ${map.version} · ${map.keyframes} keyframes · ${total} objects in the inventory`);
}

async function select(id) {
  state.selected = id;
  const section = document.getElementById('object');
  let detail;
  try {
    detail = await fetchJson(`/api/objects/${id}`);
  } catch (error) {
    section.hidden = true;
    status(error.message);
    return;
  }
  section.hidden = false;
  section.dataset.objectId = id;
  document.getElementById('object-title').textContent = `${detail.class} #${detail.id}`;
  document.getElementById('object-facts').textContent =
      `confidence ${detail.confidence.toFixed(2)} · ${detail.observations} observations in ` +
      `${detail.keyframes} keyframes · ${detail.points} model points` +
      (detail.in_inventory ? '' : ' · not in the inventory') +
      (detail.state === 'removed' ? ` · removed (seen gone in session ${detail.removed.session})` : '') +
      (detail.state === 'moved' ? ` · moved (${detail.previous_places.length} earlier place(s))` : '');
  const scores = document.getElementById('object-scores');
  scores.replaceChildren();
  for (const { class: name, score } of detail.scores) {
    const row = scores.insertRow();
    row.insertCell().textContent = name;
    row.insertCell().textContent = score.toFixed(2);
  }
  const crops = document.getElementById('object-sightings');
  crops.replaceChildren();
  for (const sighting of detail.sightings.slice(0, MAX_CROPS)) {
    const figure = document.createElement('figure');
    const image = document.createElement('img');
    image.src = sighting.image;
    image.alt = `keyframe ${sighting.keyframe}`;
    const caption = document.createElement('figcaption');
    caption.textContent = `kf ${sighting.keyframe} · ${sighting.class} ${sighting.score.toFixed(2)}`;
    figure.append(image, caption);
    crops.append(figure);
  }
  for (const [objectId, entry] of state.objects) {
    entry.points.material.size = objectId === id ? OBJECT_POINT_SIZE * 1.8 : OBJECT_POINT_SIZE;
  }
  requestRender();
}

// ---------------------------------------------------------------- picking and the IsFree box

function pointerRay(event) {
  const rect = renderer.domElement.getBoundingClientRect();
  const ndc = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
                                -((event.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(ndc, camera);
}

function pickObject() {
  const hits = raycaster.intersectObjects([...state.objects.values()].map((e) => e.points), false);
  return hits.length > 0 ? hits[0].object.userData.objectId : null;
}

let pressed = null;
renderer.domElement.addEventListener('pointerdown', (event) => { pressed = { x: event.clientX, y: event.clientY }; });
renderer.domElement.addEventListener('pointerup', (event) => {
  if (!pressed || Math.hypot(event.clientX - pressed.x, event.clientY - pressed.y) > 4) return;
  pointerRay(event);
  if (event.shiftKey) {
    const targets = [...state.objects.values()].map((e) => e.points);
    if (structure) targets.push(structure);
    const hits = raycaster.intersectObjects(targets, false);
    if (hits.length > 0) addCorner(hits[0].point);
    return;
  }
  const id = pickObject();
  if (id !== null) select(id);
});

function formatPoint(p) { return [p.x, p.y, p.z].map((v) => v.toFixed(3)).join(','); }

function addCorner(point) {
  corners.push(point.clone());
  if (corners.length > 2) corners.shift();
  if (corners.length < 2) {
    document.getElementById('box-min').value = formatPoint(point);
    document.getElementById('box-max').value = '';
    return;
  }
  const box = new THREE.Box3().setFromPoints(corners);
  // Two clicks on one surface give a flat box: give it a few centimetres along each axis.
  box.expandByVector(new THREE.Vector3(0.02, 0.02, 0.02));
  document.getElementById('box-min').value = formatPoint(box.min);
  document.getElementById('box-max').value = formatPoint(box.max);
  showBox(box, 0x3366cc);
}

function parsePoint(text) {
  const values = text.split(',').map(Number);
  return values.length === 3 && values.every(Number.isFinite) ? new THREE.Vector3(...values) : null;
}

function showBox(box, colour) {
  if (freeBox) scene.remove(freeBox);
  freeBox = new THREE.Box3Helper(box, colour);
  scene.add(freeBox);
  requestRender();
}

async function askFree() {
  const answer = document.getElementById('free-answer');
  const min = parsePoint(document.getElementById('box-min').value);
  const max = parsePoint(document.getElementById('box-max').value);
  if (!min || !max) {
    answer.className = '';
    answer.textContent = 'min and max need three numbers each, x,y,z';
    return;
  }
  const unknownFree = document.getElementById('unknown-free').checked;
  const query = new URLSearchParams({ min: formatPoint(min), max: formatPoint(max), unknown_is_free: unknownFree });
  try {
    const result = await fetchJson('/api/is_free?' + query);
    answer.className = result.free ? 'free' : 'occupied';
    answer.textContent = (result.free ? 'free' : 'not free') +
        ` · ${result.occupied} occupied, ${result.unknown} unknown voxels` +
        (result.objects_inside.length ? ` · objects inside: ${result.objects_inside.map((id) => '#' + id).join(' ')}` : '');
    answer.dataset.free = result.free;
    showBox(new THREE.Box3(min.clone().min(max), max.clone().max(min)), result.free ? 0x22aa22 : 0xcc2222);
  } catch (error) {
    answer.className = 'occupied';
    answer.textContent = error.message;
  }
}
document.getElementById('ask-free').addEventListener('click', askFree);

// ---------------------------------------------------------------- the live map

async function refresh() {
  const map = await fetchJson('/api/map');
  state.map = map;
  state.version = map.version;
  state.keyframes = map.keyframes;
  state.source = map.source;
  renderInventory(map);
  renderChanges(map);
  await applyObjects(map);
  applyGhosts(map);
  if (state.selected !== null) {
    const known = map.objects.concat(map.tombstones || []);
    if (known.some((o) => o.id === state.selected)) select(state.selected);
    else document.getElementById('object').hidden = true;
  }
  state.updates += 1;
}
document.getElementById('show-candidates').addEventListener('change', () => state.map && applyObjects(state.map));

async function follow() {
  for (;;) {
    try {
      const feed = await fetchJson(`/api/changes?since=${state.version}&timeout_ms=20000`);
      if (feed.changes.length > 0 || feed.version !== state.version) {
        await refresh();
        scheduleStructure();
      }
    } catch (error) {
      status('not following the map (' + error.message + '); retrying');
      await new Promise((resolve) => setTimeout(resolve, 2000));
    }
  }
}

// Where a click lands on object `id` (client pixels), picked the way a click is: for tests and
// for links that want to point at an object. null when no point of it is visible.
state.screenPointOf = (id) => {
  const entry = state.objects.get(id);
  if (!entry) return null;
  const rect = renderer.domElement.getBoundingClientRect();
  const positions = entry.points.geometry.attributes.position;
  const step = Math.max(1, Math.floor(positions.count / 200));
  const p = new THREE.Vector3();
  for (let i = 0; i < positions.count; i += step) {
    p.fromBufferAttribute(positions, i).project(camera);
    if (Math.abs(p.x) > 0.98 || Math.abs(p.y) > 0.98 || p.z > 1) continue;
    const x = rect.left + (p.x + 1) / 2 * rect.width, y = rect.top + (1 - p.y) / 2 * rect.height;
    pointerRay({ clientX: x, clientY: y });
    if (pickObject() === id) return { x, y };
  }
  return null;
};
state.pickableIds = () => [...state.objects.keys()];

(async () => {
  try {
    await refresh();
    await loadStructure();
    state.ready = true;
  } catch (error) {
    fail('cannot load the map: ' + error.message);
    return;
  }
  follow();
})();
