// The files of a revision (its RDTF glTF, buffers, images), fetched once per content: a file
// whose SHA-256 an earlier revision already brought (a save that changed the glTF's JSON but not
// its 18 MB buffer) is not fetched again. Each distinct content is held in the page: the glTF's
// text as a string, a buffer's bytes as an ArrayBuffer, an image as a Blob. A revision with one
// buffer goes to GLTFLoader as a GLB made in memory (glbOf), so that drawing it reads nothing
// back through a URL: reading a Blob, or fetching its object URL, is a round trip to the browser
// process, several ms of a save's latency each. Images and further buffers get object URLs made
// for one load and revoked after it (loadRevisionFiles). Contents no drawn or loading revision
// uses are dropped by retain().
const held = new Map();  // sha256 -> promise of its content (string | ArrayBuffer | Blob)

function fetchOnce(file) {
  let promise = held.get(file.sha256);
  if (promise) return promise;
  if (typeof file.text === 'string') {
    promise = Promise.resolve(file.text);  // The glTF's text came in the model message.
  } else {
    promise = fetch(file.url).then((response) => {
      if (!response.ok) throw new Error(`${file.path}: HTTP ${response.status}`);
      if (file.role === 'rdtf') return response.text();
      if (file.role === 'image') return response.blob();  // Decoded by the browser from a URL.
      return response.arrayBuffer();
    });
    promise.catch(() => { if (held.get(file.sha256) === promise) held.delete(file.sha256); });
  }
  held.set(file.sha256, promise);
  return promise;
}

// The decoded path of a URL (relative ones resolved against `base`), to match a glTF's URI to a
// manifest file whatever each percent-encodes.
function pathKey(url, base) {
  try { return decodeURIComponent(new URL(url, base).pathname); } catch { return null; }
}

// Fetches a revision's glTF and every file it refers to; returns its JSON and `bin`: the bytes of
// its buffer when it has exactly one and that is a manifest file (its URI is then dropped: the
// buffer is the GLB's BIN chunk, glbOf). Every other buffer or image URI that names a manifest
// file is replaced by an object URL of that content, listed in `urls`: the caller revokes them
// once GLTFLoader is done. URIs that name no manifest file (a data: URI) are left as they are.
// (The same content may be held as another type, when one file serves as two roles.)
export async function loadRevisionFiles(info) {
  const files = info.files || [];
  const gltf = files.find((f) => f.role === 'rdtf');
  if (!gltf) throw new Error('the manifest lists no RDTF glTF');
  const wanted = files.filter((f) => f.role === 'rdtf' || f.role === 'buffer' || f.role === 'image');
  const contents = new Map(await Promise.all(wanted.map(async (f) => [f, await fetchOnce(f)])));
  const text = contents.get(gltf);
  const json = JSON.parse(typeof text === 'string' ? text : await new Blob([text]).text());
  const base = new URL(gltf.url, location.href).href;
  const byPath = new Map(wanted.map((f) => [pathKey(f.url, location.href), contents.get(f)]));
  const named = (item) => (typeof item.uri === 'string' && !item.uri.startsWith('data:') ? byPath.get(pathKey(item.uri, base)) : undefined);
  const urls = [];
  const urlOf = (content) => {
    urls.push(URL.createObjectURL(content instanceof Blob ? content : new Blob([content])));
    return urls[urls.length - 1];
  };
  for (const image of json.images || []) {
    const content = named(image);
    if (content !== undefined) image.uri = urlOf(content);
  }
  let bin = null;
  const buffers = json.buffers || [];
  for (const [i, buffer] of buffers.entries()) {
    const content = named(buffer);
    if (content === undefined) continue;
    if (buffers.length === 1 && i === 0) {
      bin = content instanceof ArrayBuffer ? content : await new Blob([content]).arrayBuffer();
      delete buffer.uri;
    } else {
      buffer.uri = urlOf(content);
    }
  }
  return { json, bin, urls, resourcePath: base.slice(0, base.lastIndexOf('/') + 1) };
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
  for (const sha of [...held.keys()]) if (!keep.has(sha)) held.delete(sha);
}

export function heldCount() { return held.size; }
