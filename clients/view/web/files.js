// The files of a revision (its RDTF glTF, buffers, images), fetched once per content: a file
// whose SHA-256 an earlier revision already brought (a save that changed the glTF's JSON but not
// its 18 MB buffer) is not fetched again. Each distinct content is held in the page: the glTF's
// text as a string, a buffer's bytes as an ArrayBuffer, an image as a Blob with an object URL.
// A revision with one buffer goes to GLTFLoader as a GLB made in memory (glbOf), so that drawing
// it reads nothing back through a URL: reading a Blob, or fetching its object URL, is a round trip
// to the browser process, several ms of a save's latency each. Contents no drawn or loading
// revision uses are dropped by retain().
const held = new Map();  // sha256 -> {promise (-> string | ArrayBuffer | Blob), url}

function fetchOnce(file) {
  let entry = held.get(file.sha256);
  if (entry) return entry;
  if (typeof file.text === 'string') {
    // The glTF's text came in the model message: nothing to fetch.
    entry = { url: null, promise: Promise.resolve(file.text) };
  } else {
    entry = { url: null };
    entry.promise = fetch(file.url).then(async (response) => {
      if (!response.ok) throw new Error(`${file.path}: HTTP ${response.status}`);
      if (file.role === 'rdtf') return response.text();
      if (file.role === 'image') {
        const blob = await response.blob();  // Decoded by the browser from its object URL.
        entry.url = URL.createObjectURL(blob);
        return blob;
      }
      return response.arrayBuffer();
    });
    entry.promise.catch(() => { if (held.get(file.sha256) === entry) held.delete(file.sha256); });
  }
  held.set(file.sha256, entry);
  return entry;
}

// The decoded path of a URL (relative ones resolved against `base`), to match a glTF's URI to a
// manifest file whatever each percent-encodes.
function pathKey(url, base) {
  try { return decodeURIComponent(new URL(url, base).pathname); } catch { return null; }
}

// Fetches a revision's glTF and every file it refers to; returns its JSON, with each image URI
// that names a manifest file replaced by that content's object URL, and `bin`: the bytes of its
// buffer when it has exactly one and it is a manifest file (its URI is then dropped: the buffer is
// the GLB's BIN chunk, glbOf). Other buffers get an object URL. URIs that name no manifest file (a
// data: URI) are left as they are.
export async function loadRevisionFiles(info) {
  const files = info.files || [];
  const gltf = files.find((f) => f.role === 'rdtf');
  if (!gltf) throw new Error('the manifest lists no RDTF glTF');
  const entries = new Map(files.filter((f) => f.role === 'rdtf' || f.role === 'buffer' || f.role === 'image')
    .map((f) => [f, fetchOnce(f)]));
  const contents = new Map(await Promise.all([...entries].map(async ([f, e]) => [f, await e.promise])));
  const json = JSON.parse(contents.get(gltf));
  const base = new URL(gltf.url, location.href).href;
  const byPath = new Map([...entries].map(([f, e]) => [pathKey(f.url, location.href), { entry: e, content: contents.get(f) }]));
  const named = (item) => (typeof item.uri === 'string' && !item.uri.startsWith('data:') ? byPath.get(pathKey(item.uri, base)) : undefined);
  for (const image of json.images || []) {
    const found = named(image);
    if (found && found.entry.url) image.uri = found.entry.url;
  }
  let bin = null;
  const buffers = json.buffers || [];
  buffers.forEach((buffer, i) => {
    const found = named(buffer);
    if (!found || !(found.content instanceof ArrayBuffer)) return;
    if (buffers.length === 1 && i === 0) {
      bin = found.content;
      delete buffer.uri;
      return;
    }
    if (!found.entry.url) found.entry.url = URL.createObjectURL(new Blob([found.content]));
    buffer.uri = found.entry.url;
  });
  return { json, bin, resourcePath: base.slice(0, base.lastIndexOf('/') + 1) };
}

// A GLB of `json` with `bin` as its BIN chunk (glTF 2.0, "Binary glTF Layout"): chunks padded to
// four bytes, the JSON with spaces, the BIN with zeros.
export function glbOf(json, bin) {
  const text = new TextEncoder().encode(JSON.stringify(json));
  const jsonLength = (text.length + 3) & ~3;
  const binLength = (bin.byteLength + 3) & ~3;
  const total = 12 + 8 + jsonLength + 8 + binLength;
  const out = new ArrayBuffer(total);
  const view = new DataView(out);
  const bytes = new Uint8Array(out);
  view.setUint32(0, 0x46546c67, true);  // "glTF"
  view.setUint32(4, 2, true);
  view.setUint32(8, total, true);
  view.setUint32(12, jsonLength, true);
  view.setUint32(16, 0x4e4f534a, true);  // "JSON"
  bytes.set(text, 20);
  bytes.fill(0x20, 20 + text.length, 20 + jsonLength);
  view.setUint32(20 + jsonLength, binLength, true);
  view.setUint32(24 + jsonLength, 0x004e4942, true);  // "BIN"
  bytes.set(new Uint8Array(bin), 28 + jsonLength);
  return out;
}

// Drops every held content whose hash is not in `keep`.
export function retain(keep) {
  for (const [sha, entry] of held) {
    if (keep.has(sha)) continue;
    if (entry.url) URL.revokeObjectURL(entry.url);
    held.delete(sha);
  }
}

export function heldCount() { return held.size; }
