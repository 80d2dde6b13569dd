// rdtf-view's page: the models rdtf-view hears on the bus (over its WebSocket, docs/view.md), the
// selected one drawn by ModelView, sliders that command joints, and the test hook
// window.rdtfView.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { ModelView } from './model.js';
import { retain } from './files.js';

const $ = (id) => document.getElementById(id);
const models = new Map();  // id -> {info, view, loading, links, joints, targets}
let selected = null;
let socket = null;
let frame = 0;
const refusals = [];
let dirty = true;        // a frame is due (render(), below)
let moved = false;       // a LINK_STATE moved a link since the last frame (a frame for motion)
let everyFrame = false;  // the frame-rate benchmark's hook
function invalidate() { dirty = true; }
const notices = [];

// --- three.js scene ---------------------------------------------------------------------------
// Multisampling is nearly free on a GPU, but a software rasterizer (SwiftShader or llvmpipe: a
// machine or VM without a GPU, a remote desktop) shades every sample on the CPU, and its raster
// is then most of save -> pixels (docs/view.md, "Timing"). So it is off there, unless the URL
// asks: ?msaa=on|off.
function probeRenderer() {
  const gl = document.createElement('canvas').getContext('webgl2');
  if (!gl) return { name: 'none', software: false };
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  gl.getExtension('WEBGL_lose_context')?.loseContext();
  return { name, software: /SwiftShader|llvmpipe|softpipe|software/i.test(name) };
}
const gpu = probeRenderer();
const msaaAsked = new URLSearchParams(location.search).get('msaa');
const antialias = msaaAsked === 'on' ? true : msaaAsked === 'off' ? false : !gpu.software;
// The drawing buffer is not preserved (a copy of the whole frame each frame otherwise, on the CPU
// under a software rasterizer: the one-pixel read that stamps a revision's frame, renderFrame(),
// runs in the same task as its render), and the canvas is opaque (the scene has a background).
const renderer = new THREE.WebGLRenderer({ antialias, alpha: false });
renderer.setPixelRatio(window.devicePixelRatio);
$('view').appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x303238);
const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 1000);
camera.position.set(1.2, 1.0, 1.6);
const controls = new OrbitControls(camera, renderer.domElement);
controls.addEventListener('change', () => invalidate());
scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 2.0));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(3, 5, 4);
scene.add(sun);
const grid = new THREE.GridHelper(4, 40, 0x777777, 0x4a4a4a);
scene.add(grid);
// `world` holds the models in their scene frame; the up switch turns it (Z up: +Z drawn up).
const world = new THREE.Group();
scene.add(world);
let cameraFitted = false;

function resize() {
  dirty = true;
  const w = $('view').clientWidth, h = $('view').clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

const now = () => performance.timeOrigin + performance.now();
const justSwapped = [];  // models whose new revision this frame draws first
const onePixel = new Uint8Array(4);
function renderFrame() {
  controls.update();
  renderer.render(scene, camera);
  ++frame;
  if (!justSwapped.length) return;
  // The frame that first draws a revision: wait until its pixels are in the drawing buffer (a
  // one-pixel read waits for the GPU process to raster the frame; Chromium's gl.finish() does
  // not), then stamp it (ms since the epoch: the latency benchmark's save -> pixels end point).
  const submitted = now();
  const gl = renderer.getContext();
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, onePixel);
  const at = now();
  for (const m of justSwapped.splice(0)) {
    m.drawnAt = at;
    if (m.view) Object.assign(m.view.timing, { submitted_at: submitted, drawn_at: at });
  }
}
// Frames are rendered when something changed (a state, the camera, a toggle, a new revision),
// not 60 times a second: under SwiftShader every frame costs CPU that rdtfd, the bus and the
// next revision need, and frames queued in the GPU process delay the pixels of the next one.
// And a frame waits until the GPU process has rastered the one before it (a fence, polled at each
// animation frame): a software rasterizer takes longer than a refresh interval to raster one, and
// the frames queued behind it would hold up the first frame of the next revision.
let lastFrameFence = null;
function gpuCaughtUp() {
  if (!lastFrameFence) return true;
  const gl = renderer.getContext();
  const status = gl.getSyncParameter(lastFrameFence, gl.SYNC_STATUS);  // null once the context is lost
  if (status !== null && status !== gl.SIGNALED) return false;
  gl.deleteSync(lastFrameFence);
  lastFrameFence = null;
  return true;
}
// And while a save of the drawn model settles in rdtfd (its SAVING), a software rasterizer draws
// no frames for motion alone: the one in flight when the new revision came held up that
// revision's first frame (docs/benchmarks.md, "The panel's readouts, and motion held while a
// save settles"). The model stands still from the save until its new revision is drawn, about
// the settle period; the hold ends then, or with an ERROR, or at the latest a second after the
// settle period (a save that changed nothing gives no revision). A hold running is not extended
// by another SAVING. Frames for anything else (the camera, a toggle) are drawn, with the newest
// poses. A GPU draws a frame in a fraction of a millisecond: nothing is held there.
const HOLD_AFTER_SETTLE_MS = 1000;
const motionHold = { id: null, until: 0, count: 0 };
function holdMotion(id, settleMs) {
  if (!gpu.software || id !== selected || motionHeld()) return;
  Object.assign(motionHold, { id, until: performance.now() + Math.min(settleMs, 60000) + HOLD_AFTER_SETTLE_MS });
  ++motionHold.count;
}
function releaseMotion(id) {
  if (motionHold.id === id) Object.assign(motionHold, { id: null, until: 0 });
}
function motionHeld() {
  return motionHold.id !== null && motionHold.id === selected && performance.now() < motionHold.until;
}
function render() {
  requestAnimationFrame(render);
  const due = dirty || (moved && !motionHeld());
  if (!due && !everyFrame) return;
  if (!everyFrame && !gpuCaughtUp()) return;  // still due: drawn at a later animation frame
  dirty = false;
  moved = false;
  renderFrame();
  if (everyFrame) return;  // the frame-rate benchmark draws at every animation frame regardless
  const gl = renderer.getContext();
  lastFrameFence = gl.fenceSync(gl.SYNC_GPU_COMMANDS_COMPLETE, 0);
  gl.flush();
}
requestAnimationFrame(render);

function fitCamera(view) {
  invalidate();
  const box = new THREE.Box3().setFromObject(view.root);
  if (box.isEmpty()) return;
  const centre = box.getCenter(new THREE.Vector3());
  const size = box.getSize(new THREE.Vector3()).length();
  controls.target.copy(centre);
  camera.position.copy(centre).add(new THREE.Vector3(0.7, 0.5, 0.9).multiplyScalar(size * 1.1));
  camera.near = size / 1000;
  camera.far = size * 100;
  camera.updateProjectionMatrix();
  cameraFitted = true;
}

function visibleParts() {
  return { frames: $('show-frames').checked, com: $('show-com').checked, inertia: $('show-inertia').checked };
}
for (const id of ['show-frames', 'show-com', 'show-inertia']) {
  $(id).addEventListener('change', () => {
    for (const m of models.values()) if (m.view) m.view.setVisible(visibleParts());
    invalidate();
  });
}
function setUp(up) {
  invalidate();
  world.rotation.set(up === 'z' ? -Math.PI / 2 : 0, 0, 0);
  $('up').value = up;
}
$('up').addEventListener('change', () => setUp($('up').value));

// --- hover: link names ------------------------------------------------------------------------
const raycaster = new THREE.Raycaster();
renderer.domElement.addEventListener('pointermove', (event) => {
  const rect = renderer.domElement.getBoundingClientRect();
  const pointer = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
    -((event.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
  const hit = raycaster.intersectObjects(world.children, true).find((h) => h.object.userData.rdtfLink);
  const tip = $('tooltip');
  if (!hit) { tip.style.display = 'none'; return; }
  tip.textContent = hit.object.userData.rdtfLink;
  tip.style.left = `${event.clientX + 12}px`;
  tip.style.top = `${event.clientY + 12}px`;
  tip.style.display = 'block';
});

// --- models -----------------------------------------------------------------------------------
function entry(id) {
  if (!models.has(id)) models.set(id, { info: { id, status: 'pending' }, view: null, loading: null, targets: {} });
  return models.get(id);
}

function diagnosticsOf(info) {
  return [...((info.error && info.error.diagnostics) || []), ...((info.validation && info.validation.diagnostics) || [])];
}

// The same description again (rdtfd answers every REQUEST and republishes now and then): the
// timing of its arrival aside, nothing to show or draw anew.
function sameInfo(a, b) {
  const { timing: ta, ...restA } = a;
  const { timing: tb, ...restB } = b;
  return JSON.stringify(restA) === JSON.stringify(restB);
}

async function onModel(info) {
  const m = entry(info.id);
  const previous = m.info;
  m.info = info;
  if (info.status === 'error' || info.status === 'removed') releaseMotion(info.id);  // no revision follows
  if (selected === null && info.status !== 'removed') selected = info.id;
  if (info.status === 'removed' || !info.gltf) {
    if (info.status === 'removed' && m.view) {
      world.remove(m.view.root);
      m.view.dispose();
      m.view = null;
    }
  } else if ((!m.view || m.view.revision !== info.revision) && (!m.loading || m.loading.revision !== info.revision)) {
    // A new revision: load it beside the drawn one, then swap in one step (the camera stays).
    const view = new ModelView(info);
    m.loading = view;
    try {
      await view.load();
    } catch (e) {
      console.error(`rdtf-view: ${info.id} revision ${info.revision}:`, e);
      notices.push(`${info.id} revision ${info.revision} could not be drawn: ${e.message}`);
      releaseMotion(info.id);
      if (m.loading === view) m.loading = null;
      refreshPanel();
      return;
    }
    if (m.loading !== view || m.info.status === 'removed') { view.dispose(); return; }
    m.loading = null;
    // The old revision is disposed after the new one is drawn: its materials' shader programs,
    // which the new revision's materials share, stay compiled (three.js frees a program when
    // nothing uses it, and compiling them again costs SwiftShader tens of ms).
    const old = m.view;
    if (old) world.remove(old.root);
    m.view = view;
    world.add(view.root);
    m.drawnAt = null;  // until the frame that draws it is rendered
    justSwapped.push(m);
    view.setVisible(visibleParts());
    if (m.lastState) applyState(m, m.lastState);
    if (!cameraFitted && info.id === selected) fitCamera(view);
    if (m.view) m.view.highlight(diagnosticsOf(m.info));
    view.root.visible = info.id === selected;
    // Drawn now, not at the next animation frame (up to a refresh interval later); the panel
    // after it, so that its layout and paint do not come first.
    renderFrame();
    releaseMotion(info.id);
    refreshPanel();
    if (old) old.dispose();
    retainDrawn();
    return;
  }
  if (previous && m.view && m.view.revision === info.revision && sameInfo(previous, info)) return;
  if (m.view) m.view.highlight(diagnosticsOf(m.info));
  refreshPanel();
  retainDrawn();
}

// The page keeps the file contents of the revisions drawn or loading only.
function retainDrawn() {
  const keep = new Set();
  for (const m of models.values()) for (const v of [m.view, m.loading]) if (v) v.hashes.forEach((h) => keep.add(h));
  retain(keep);
}

// A frame only when a link moved: joint positions and the time are shown in the panel, not drawn.
function applyState(m, state) {
  if (!m.view) return;
  if (state.links && state.links.revision === m.view.revision && m.view.setLinkState(state.links)) moved = true;
  if (state.joints && state.joints.revision === m.view.revision) m.view.setJointState(state.joints);
}

function onState(state) {
  const m = entry(state.id);
  m.lastState = state;
  applyState(m, state);
  if (state.id === selected) scheduleReadouts();
}

// --- panel ------------------------------------------------------------------------------------
function refreshPanel() {
  invalidate();  // which model is shown, what is red
  for (const [id, m] of models) if (m.view) m.view.root.visible = id === selected;
  const list = $('models');
  list.replaceChildren(...[...models.values()].map((m) => {
    const li = document.createElement('li');
    li.className = m.info.id === selected ? 'selected' : '';
    li.innerHTML = `<span></span> <span class="status-${m.info.status}">${m.info.status}</span>`;
    li.firstChild.textContent = `${m.info.id}${m.info.revision ? ` r${m.info.revision}` : ''}`;
    li.addEventListener('click', () => selectModel(m.info.id));
    return li;
  }));
  const m = models.get(selected);
  const details = $('details');
  const diagnostics = $('diagnostics');
  diagnostics.replaceChildren();
  $('sliders').replaceChildren();
  if (!m) { details.textContent = ''; return; }
  const info = m.info;
  const verdict = info.validated ? (info.validation_passed ? 'passed' : 'FAILED') : 'not validated';
  details.textContent = info.revision
    ? `revision ${info.revision} (${(info.content_hash || '').slice(0, 12)}), validation ${verdict}; ` +
      `total mass ${Number(info.total_mass).toPrecision(6)} kg, centre of mass ` +
      `[${(info.com_scene || []).map((x) => Number(x).toFixed(4)).join(', ')}] m`
    : `status ${info.status}`;
  if (info.error) {
    const head = document.createElement('div');
    head.className = 'diagnostic error';
    head.textContent = `save rejected: ${info.error.live_revision ? `revision ${info.error.live_revision} stays live` : 'nothing live yet'}`;
    diagnostics.appendChild(head);
  }
  for (const d of diagnosticsOf(info)) {
    const div = document.createElement('div');
    div.className = `diagnostic ${d.severity}`;
    const code = document.createElement('span');
    code.className = 'code';
    code.textContent = `${d.severity} ${d.code} `;
    const place = document.createElement('span');
    place.className = 'place';
    place.textContent = `${d.file}${d.pointer ? `:${d.pointer}` : ''}${d.line ? `:${d.line}` : ''}` +
      `${d.byte_offset !== undefined ? `:@${d.byte_offset}` : ''} `;
    div.append(code, place, document.createTextNode(d.message));
    diagnostics.appendChild(div);
  }
  if (m.view) {
    const h = m.view.highlighted;
    if (h.links.length || h.joints.length) {
      const div = document.createElement('div');
      div.textContent = `in red: ${[...h.joints.map((j) => `joint ${j}`), ...h.links.map((l) => `link ${l}`)].join(', ')}`;
      diagnostics.appendChild(div);
    }
    buildSliders(m);
  }
  $('notices').textContent = [...notices.slice(-3), ...refusals.slice(-3).map((r) => `refused: ${r}`)].join('\n');
}

function buildSliders(m) {
  for (const j of m.view.joints) {
    if (!['revolute', 'continuous', 'prismatic'].includes(j.type)) continue;
    const div = document.createElement('div');
    div.className = 'slider';
    const lower = j.lower ?? -Math.PI, upper = j.upper ?? Math.PI;
    div.innerHTML = `<label></label><input type="range" step="any">`;
    const input = div.querySelector('input');
    input.min = lower; input.max = upper;
    input.value = m.targets[j.name] ?? m.view.jointPositions.get(j.name) ?? 0;
    input.dataset.joint = j.name;
    input.dataset.label = j.gltf_name === j.name ? j.name : `${j.gltf_name} (URDF ${j.name})`;
    div.querySelector('label').title = input.dataset.label;
    input.dataset.gains = Number.isFinite(j.kp) ? ` kp ${j.kp.toPrecision(3)} kd ${j.kd.toPrecision(3)}` : '';
    const unit = j.type === 'prismatic' ? ['kg', 'N/m', 'N s/m'] : ['kg m^2', 'N m/rad', 'N m s/rad'];
    div.title = Number.isFinite(j.kp)
      ? `gains of this joint's commands: kp ${j.kp} ${unit[1]}, kd ${j.kd} ${unit[2]} ` +
        `(it moves ${j.moved_inertia} ${unit[0]}; docs/view.md, "Sliders")`
      : '';
    input.addEventListener('input', () => setJoint(m.info.id, j.name, Number(input.value)));
    $('sliders').appendChild(div);
  }
  refreshSliderValues();
}

function refreshSliderValues() {
  const m = models.get(selected);
  if (!m || !m.view) return;
  for (const input of $('sliders').querySelectorAll('input')) {
    const name = input.dataset.joint;
    const q = m.view.jointPositions.get(name);
    const target = m.targets[name];
    const text = `${input.dataset.label}: ${q === undefined ? '-' : q.toFixed(3)}` +
      `${target === undefined ? '' : ` (target ${target.toFixed(3)})`}${input.dataset.gains}`;
    if (input.previousSibling.textContent !== text) input.previousSibling.textContent = text;
  }
}
// The joint readouts follow the states at most READOUT_HZ times a second. Each change of the
// panel's text is a layout, a paint and a frame of the browser's compositor; under a software
// rasterizer, 50 of them a second (one per state) made the first frame of a new revision wait
// for the compositor: save -> pixels 101-110 ms at the median against 87-88 ms without them
// (docs/benchmarks.md, "The panel's readouts, and motion held while a save settles").
const READOUT_HZ = 10;
let readoutsDue = null;
function scheduleReadouts() {
  if (readoutsDue !== null) return;
  readoutsDue = setTimeout(() => { readoutsDue = null; refreshSliderValues(); }, 1000 / READOUT_HZ);
}

// --- socket -----------------------------------------------------------------------------------
const waiters = [];  // setJoint promises: resolved by the next answer about their model
function connect() {
  socket = new WebSocket(`ws://${location.host}/ws`);
  socket.onopen = () => { $('connection').textContent = `connected to ${location.host}`; };
  socket.onclose = () => {
    $('connection').textContent = 'disconnected: retrying';
    setTimeout(connect, 1000);
  };
  socket.onmessage = (event) => {
    const received = now();
    const message = JSON.parse(event.data);
    if (message.type === 'model' && message.timing) message.timing.received_at = received;
    switch (message.type) {
      case 'model': onModel(message); break;
      case 'saving': holdMotion(message.id, message.settle_ms); break;
      case 'state': onState(message); break;
      case 'targets':
        entry(message.id).targets = message.targets;
        settle((w) => w.model === message.id, '');
        if (message.id === selected) refreshSliderValues();
        break;
      case 'refused':
        refusals.push(message.reason);
        settle(() => true, message.reason);
        refreshPanel();
        break;
      case 'known': forgetAllBut(new Set(message.ids)); break;
      case 'notice':
        notices.push(`${message.id}: ${message.diagnostics.map((d) => d.message).join('; ')}`);
        refreshPanel();
        break;
    }
  };
}
// The models rdtf-view knows, sent as the socket opens: a page that outlived a restart of
// rdtf-view drops the ones the new one does not know (a model deleted meanwhile stayed drawn as
// "live" and took slider targets nobody applied).
function forgetAllBut(ids) {
  for (const [id, m] of models) {
    if (ids.has(id)) continue;
    if (m.view) {
      world.remove(m.view.root);
      m.view.dispose();
    }
    m.loading = null;  // A load in flight sees it was dropped and disposes what it made.
    releaseMotion(id);
    models.delete(id);
    if (selected === id) selected = null;
  }
  if (selected === null && models.size > 0) selectModel(models.keys().next().value);
  refreshPanel();
}
function selectModel(id) {
  selected = id;
  refreshPanel();
  if (models.get(id)?.view) fitCamera(models.get(id).view);
}
function settle(match, reason) {
  const i = waiters.findIndex(match);
  if (i >= 0) waiters.splice(i, 1)[0].resolve(reason);
}
function setJoint(modelId, jointName, value) {
  return new Promise((resolve) => {
    waiters.push({ model: modelId, resolve });
    socket.send(JSON.stringify({ type: 'set_joint', model: modelId, joint: jointName, value }));
  });
}
connect();

// --- test hook (docs/view.md) -----------------------------------------------------------------
window.rdtfView = {
  // Every model: positions of the drawn revision in the scene frame, as drawn now.
  state() {
    return {
      frame,
      selected,
      renderer: { name: gpu.name, software: gpu.software, antialias,
        draw_calls: renderer.info.render.calls, triangles: renderer.info.render.triangles },
      models: [...models.values()].map((m) => ({
        id: m.info.id,
        revision: m.view ? m.view.revision : null,
        latest_revision: m.info.revision ?? null,
        content_hash: m.view ? m.view.info.content_hash : null,
        status: m.info.status,
        diagnostics: diagnosticsOf(m.info),
        error: m.info.error ?? null,
        targets: m.targets,
        drawn_at: m.drawnAt ?? null,
        timing: m.view ? m.view.timing : null,
        links: [], joints: [],
        ...(m.view ? m.view.state() : {}),
      })),
      refusals: refusals.slice(),
      sliders: [...$('sliders').querySelectorAll('label')].map((l) => l.textContent),
      motion_hold: { model: motionHeld() ? motionHold.id : null, saves_heard: motionHold.count },
    };
  },
  // What the slider does; resolves to "" when rdtf-view took it, else the reason it refused.
  setJoint,
  select(id) { selectModel(id); },
  setUp,
  show(parts) {
    for (const [k, id] of [['frames', 'show-frames'], ['com', 'show-com'], ['inertia', 'show-inertia']]) {
      if (k in parts) $(id).checked = !!parts[k];
    }
    for (const m of models.values()) if (m.view) m.view.setVisible(visibleParts());
    invalidate();
  },
  // Renders every animation frame (true) or only when something changed (false, the default):
  // for the frame-rate benchmark.
  renderEveryFrame(on) { everyFrame = !!on; },
  // Sends raw text on the page's socket (tests of hostile messages).
  sendRaw(text) { socket.send(text); },
};
