// rdtf-view's benchmarks (bench/view_bench.sh runs this inside a network namespace of its own:
// LCM multicast on loopback only). Starts rdtfd and rdtf-view from BUILD (argv[2]) on temporary
// folders and Debian's headless chromium (SwiftShader WebGL), then measures:
//   latency: a save of arm3.gltf (the joint limit edited, so each save is a new content) to the
//            rendered frame that first draws the new revision (the page's drawn_at, ms since the
//            epoch, against the time the file was written, on the same clock), N saves;
//            with --big, the same for a 1M-triangle model;
//   fps:     frames rendered in 10 s with the 1M-triangle model drawn (--big);
//   memory:  rdtf-view's VmRSS with 100 models live (copies of arm3 under 100 names).
// Prints one JSON line per result.
//   robot:   with --robot NAME, tests/data/robots/NAME.urdf imported (`rdtf import`) and drawn:
//            frames rendered in 10 s (every frame, all overlays shown) and draw calls a frame.
// --web-dir DIR serves the page from DIR (another version of clients/view/web, side by side).
// Usage: node bench_view.mjs BUILD REPO [--saves N] [--big] [--models N] [--no-validate] [--msaa on|off] [--after-settle]
//                                       [--robot NAME] [--web-dir DIR]
// (--no-validate: rdtfd's ODE check off, so the latency is conversion, bus and drawing alone)
import puppeteer from 'puppeteer-core';
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import crypto from 'node:crypto';

const [build, repo] = process.argv.slice(2, 4);
const flag = (name, fallback) => {
  const i = process.argv.indexOf(name);
  return i < 0 ? fallback : (process.argv[i + 1] && !process.argv[i + 1].startsWith('--') ? Number(process.argv[i + 1]) : true);
};
const saves = flag('--saves', 50);
const big = flag('--big', false);
const modelCount = flag('--models', 100);
const validate = !process.argv.includes('--no-validate');
// --after-settle: rdtfd converts a save only once it has settled (convert_while_settling false),
// as before it converted while settling; the default is rdtfd's own.
const afterSettle = process.argv.includes('--after-settle');
// --msaa on|off: the page's multisampling as asked in its URL (default: the page's own choice,
// off under a software rasterizer such as this benchmark's SwiftShader).
const option = (name) => { const i = process.argv.indexOf(name); return i < 0 ? null : process.argv[i + 1]; };
const robot = option('--robot');
const webDir = option('--web-dir');
const msaaAt = process.argv.indexOf('--msaa');
const msaa = msaaAt < 0 ? null : process.argv[msaaAt + 1];
const now = () => performance.timeOrigin + performance.now();
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const root = fs.mkdtempSync(path.join(os.tmpdir(), 'rdtf-view-bench-'));
const watch = path.join(root, 'models');
fs.mkdirSync(watch);
const fixture = path.join(repo, 'tests/data/blender');
fs.copyFileSync(path.join(fixture, 'arm3.bin'), path.join(watch, 'arm3.bin'));
const arm3 = JSON.parse(fs.readFileSync(path.join(fixture, 'arm3.gltf'), 'utf8'));
const writeArm = (name, upper) => {
  for (const n of arm3.nodes) if (n.name === 'shoulder') n.extras.rdtf_upper = upper;
  fs.writeFileSync(path.join(watch, name), JSON.stringify(arm3));
};
writeArm('arm3.gltf', 1.0);
fs.writeFileSync(path.join(root, 'rdtfd.json'), JSON.stringify({ simulate: true, validate, status_period_ms: 200,
  ...(afterSettle ? { convert_while_settling: false } : {}) }));

const children = [];
const run = (file, args, log) => {
  const child = spawn(file, args, { stdio: ['ignore', fs.openSync(path.join(root, log), 'w'), fs.openSync(path.join(root, `${log}.err`), 'w')] });
  children.push(child);
  return child;
};
process.on('exit', () => {
  children.forEach((c) => c.kill('SIGKILL'));
  fs.rmSync(root, { recursive: true, force: true });
});
run(path.join(build, 'daemon/rdtfd'), ['--config', path.join(root, 'rdtfd.json'), '--watch', watch, '--output', path.join(root, 'out'), '--settle-ms', '50'], 'rdtfd.log');
const view = run(path.join(build, 'clients/view/rdtf-view'), ['--port', '8765', ...(webDir ? ['--web-dir', webDir] : [])], 'view.log');
await sleep(500);
const rss = () => Number(/VmRSS:\s+(\d+)/.exec(fs.readFileSync(`/proc/${view.pid}/status`, 'utf8'))[1]);

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium', headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-dev-shm-usage', '--window-size=1280,800'],
  defaultViewport: { width: 1280, height: 800 },
});
const page = await browser.newPage();
page.on('pageerror', (e) => console.error(`page error: ${e.message}`));
page.on('console', (m) => { if (m.type() === 'error') console.error(`page console: ${m.text()} ${m.location()?.url ?? ''}`); });
// rdtf-view may still be starting (a cold start on a busy machine): try again for up to 10 s.
for (let tries = 0; ; ++tries) {
  try {
    await page.goto(`http://127.0.0.1:8765/${msaa ? `?msaa=${msaa}` : ''}`, { waitUntil: 'load' });
    break;
  } catch (e) {
    if (tries >= 20 || !/ERR_CONNECTION_REFUSED/.test(e.message)) throw e;
    await sleep(500);
  }
}
console.log(JSON.stringify({ renderer: await page.evaluate(() => window.rdtfView.state().renderer) }));
const model = (id) => page.evaluate((i) => window.rdtfView.state().models.find((m) => m.id === i) || null, id);
// rdtfd's content_hash of a model file and the files it refers to (docs/lcm.md): SHA-256 over
// each file's length (8 bytes, little endian) and bytes.
const contentHash = (files) => {
  const h = crypto.createHash('sha256');
  for (const f of files) {
    const bytes = fs.readFileSync(f);
    const size = Buffer.alloc(8);
    size.writeBigUInt64LE(BigInt(bytes.length));
    h.update(size);
    h.update(bytes);
  }
  return h.digest('hex');
};
// Waits until the page draws the revision of exactly this content (not one of an earlier save).
async function waitRevision(id, above, hash, timeoutMs = 60000) {
  const end = Date.now() + timeoutMs;
  for (;;) {
    const m = await model(id);
    if (m && m.revision > above && m.drawn_at && (!hash || m.content_hash === hash)) return m;
    if (Date.now() > end) throw new Error(`${id}: no revision above ${above} drawn`);
    // The page stamps drawn_at itself: polling slower only spares the two cores, it does not
    // change what is measured.
    await sleep(20);
  }
}
const percentile = (xs, p) => { const s = [...xs].sort((a, b) => a - b); return s[Math.min(s.length - 1, Math.ceil((p / 100) * s.length) - 1)]; };
const report = (o) => console.log(JSON.stringify(o));

// rdtfd's "converted <id> revision <n> ... in <ms> ms" lines (stderr, stamped in UTC to the ms):
// when a conversion ended and how long it took, by model and revision.
function conversions() {
  const out = new Map();
  const text = fs.readFileSync(path.join(root, 'rdtfd.log.err'), 'utf8');
  for (const m of text.matchAll(/^(\S+Z) converted (.+?) revision (\d+) \(.*\) in ([\d.]+) ms/gm)) {
    const end = Date.parse(m[1]);
    out.set(`${m[2]}#${m[3]}`, { start: end - Number(m[4]), end });
  }
  return out;
}
const median = (xs) => percentile(xs, 50);
// The stages of one save, each the time from the end of the previous one (ms), on one clock (the
// epoch, CLOCK_REALTIME in node, rdtfd, rdtf-view and chromium; rdtfd's log stamps are whole ms):
//   settle:   write -> rdtfd starts converting (inotify, the 50 ms settle, the queue)
//   convert:  rdtfd's conversion (and its check when on)
// (Converting while settling, rdtfd's default, the conversion starts within the settle period and
// ends with the commit after it: then `settle` is the wait before the conversion started and
// `convert` includes the rest of the settle period; their sum is still write -> committed.)
//   publish:  end of conversion -> DESCRIPTION stamped (utime)
//   bus:      -> the snapshot whole in rdtf-view (DESCRIPTION, INERTIA, MANIFEST, blobs fetched)
//   push:     -> the page's WebSocket handler has the model message
//   fetch:    -> the revision's files in the page (contents already held are not fetched)
//   parse:    -> GLTFLoader done
//   build:    -> links tinted, frames, centres of mass, inertia boxes and joints made
//   submit:   -> the first frame drawing it handed to WebGL (three.js's render())
//   raster:   -> that frame's pixels in the drawing buffer (a one-pixel readPixels returned)
const STAGES = ['settle', 'convert', 'publish', 'bus', 'push', 'fetch', 'parse', 'build', 'submit', 'raster'];
function stagesOf(t0, conversion, timing) {
  const marks = [t0, conversion?.start, conversion?.end, timing.published_at, timing.complete_at,
    timing.received_at, timing.fetched_at, timing.parsed_at, timing.built_at, timing.submitted_at, timing.drawn_at];
  if (marks.some((x) => typeof x !== 'number')) return null;
  return Object.fromEntries(STAGES.map((s, i) => [s, marks[i + 1] - marks[i]]));
}

async function latency(id, write, count, files) {
  let m = await waitRevision(id, 0);
  const ms = [];
  const runs = [];
  const rss_kib = [rss()];  // rdtf-view's, once the first revision is drawn and after each save's
  const frame = () => page.evaluate(() => window.rdtfView.state().frame);
  const frame0 = await frame();  // frames rendered meanwhile: states that moved a link, revisions
  for (let i = 0; i < count; ++i) {
    const t0 = now();
    write(i);
    m = await waitRevision(id, m.revision, contentHash(files));
    ms.push(m.drawn_at - t0);
    runs.push({ t0, revision: m.revision, timing: m.timing });
    await sleep(100);  // let the simulation's states of the new revision flow, as between real saves
    rss_kib.push(rss());
  }
  const frames_per_save = (await frame() - frame0) / count;
  // What the last frame drew (three.js's renderer.info): draw calls and triangles.
  const { draw_calls, triangles } = await page.evaluate(() => window.rdtfView.state().renderer);
  // SAVINGs the page heard for the drawn model (each held its motion frames, docs/view.md).
  const saves_heard = await page.evaluate(() => window.rdtfView.state().motion_hold.saves_heard);
  const log = conversions();
  const stages = runs.map((r) => stagesOf(r.t0, log.get(`${id}#${r.revision}`), r.timing || {})).filter(Boolean);
  const stage_median_ms = Object.fromEntries(STAGES.map((s) => [s, Math.round(10 * median(stages.map((x) => x[s]))) / 10]));
  const stage_p99_ms = Object.fromEntries(STAGES.map((s) => [s, Math.round(10 * percentile(stages.map((x) => x[s]), 99)) / 10]));
  return { p50: percentile(ms, 50), p99: percentile(ms, 99), max: Math.max(...ms), n: ms.length,
    load: os.loadavg().map((x) => Math.round(100 * x) / 100), broken_down: stages.length, stage_median_ms, stage_p99_ms,
    frames_per_save, saves_heard, draw_calls, triangles, rss_kib };
}

report({ bench: 'save_to_pixels_ms', validate, while_settling: !afterSettle, model: 'arm3 (3 links)', ...(await latency('arm3.gltf', (i) => writeArm('arm3.gltf', 1.1 + 0.001 * i), saves, [path.join(watch, 'arm3.gltf'), path.join(watch, 'arm3.bin')])) });

if (big) {
  // One link, a 1M-triangle grid (500,000 vertices) closed into a slab by nothing: an open
  // surface is fine for drawing (rdtfd warns MESH_OPEN).
  const n = 708;  // (n-1)^2 * 2 = 1,000,000 triangles
  const positions = new Float32Array(n * n * 3);
  for (let y = 0; y < n; ++y) for (let x = 0; x < n; ++x) {
    const k = (y * n + x) * 3;
    positions.set([x / n, 0.05 * Math.sin(x / 9) * Math.cos(y / 7), y / n], k);
  }
  const indices = new Uint32Array((n - 1) * (n - 1) * 6);
  let k = 0;
  for (let y = 0; y < n - 1; ++y) for (let x = 0; x < n - 1; ++x) {
    const a = y * n + x, b = a + 1, c = a + n, d = c + 1;
    indices.set([a, c, b, b, c, d], k);
    k += 6;
  }
  const bin = Buffer.concat([Buffer.from(positions.buffer), Buffer.from(indices.buffer)]);
  fs.writeFileSync(path.join(watch, 'big.bin'), bin);
  const writeBig = (i) => fs.writeFileSync(path.join(watch, 'big.gltf'), JSON.stringify({
    asset: { version: '2.0' }, scene: 0, scenes: [{ nodes: [0] }],
    nodes: [{ name: `plate${i}`, mesh: 0 }],
    meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
    buffers: [{ uri: 'big.bin', byteLength: bin.length }],
    bufferViews: [{ buffer: 0, byteOffset: 0, byteLength: positions.byteLength },
      { buffer: 0, byteOffset: positions.byteLength, byteLength: indices.byteLength }],
    accessors: [{ bufferView: 0, componentType: 5126, count: n * n, type: 'VEC3', min: [0, -0.05, 0], max: [(n - 1) / n, 0.05, (n - 1) / n] },
      { bufferView: 1, componentType: 5125, count: indices.length, type: 'SCALAR' }],
  }));
  writeBig(0);
  report({ bench: 'save_to_pixels_ms', validate, model: `big (1 link, ${indices.length / 3} triangles)`, ...(await latency('big.gltf', (i) => writeBig(i + 1), Math.max(5, Math.round(saves / 10)), [path.join(watch, 'big.gltf'), path.join(watch, 'big.bin')])) });
  await page.evaluate(() => { window.rdtfView.select('big.gltf'); window.rdtfView.renderEveryFrame(true); });
  const f0 = (await page.evaluate(() => window.rdtfView.state().frame));
  const t0 = now();
  await sleep(10000);
  const f1 = (await page.evaluate(() => window.rdtfView.state().frame));
  report({ bench: 'fps_swiftshader', model: 'big', fps: (f1 - f0) / ((now() - t0) / 1000) });
  await page.evaluate(() => window.rdtfView.renderEveryFrame(false));
  fs.rmSync(path.join(watch, 'big.gltf'));
}

if (robot) {
  // A published robot as users bring it (many links): how fast the page draws it, everything shown.
  const id = `${robot}.gltf`;
  const imported = spawnSync(path.join(build, 'clients/rdtf/rdtf'), ['import', path.join(repo, 'tests/data/robots', `${robot}.urdf`), '-o', path.join(watch, id)], { encoding: 'utf8' });
  if (imported.status !== 0) throw new Error(`rdtf import ${robot}: ${imported.stderr}`);
  const m = await waitRevision(id, 0);
  await page.evaluate((i) => { window.rdtfView.select(i); window.rdtfView.show({ frames: true, com: true, inertia: true }); window.rdtfView.renderEveryFrame(true); }, id);
  await sleep(1000);
  const f0 = (await page.evaluate(() => window.rdtfView.state().frame));
  const t0 = now();
  await sleep(10000);
  const f1 = (await page.evaluate(() => window.rdtfView.state().frame));
  const { draw_calls, triangles } = await page.evaluate(() => window.rdtfView.state().renderer);
  report({ bench: 'fps_swiftshader', model: `${robot} (${m.links.length} links, ${m.joints.length} joints)`, fps: (f1 - f0) / ((now() - t0) / 1000),
    draw_calls, triangles, load: os.loadavg().map((x) => Math.round(100 * x) / 100) });
  await page.evaluate(() => window.rdtfView.renderEveryFrame(false));
  fs.rmSync(path.join(watch, id));
}

const before = rss();
for (let i = 0; i < modelCount; ++i) writeArm(`arm3_${String(i).padStart(3, '0')}.gltf`, 1.0 + i * 1e-3);
const end = Date.now() + 300000;
for (;;) {
  const live = await page.evaluate(() => window.rdtfView.state().models.filter((m) => m.status === 'live').length);
  if (live >= modelCount + 1) break;
  if (Date.now() > end) throw new Error(`only ${live} models live`);
  await sleep(200);
}
const withModels = rss();
await sleep(5000);  // what stays once the pages' queues drained
report({ bench: 'rdtf_view_rss_kib', models: modelCount + 1, before_kib: before, with_models_kib: withModels, five_s_later_kib: rss() });
await browser.close();
process.exit(0);
