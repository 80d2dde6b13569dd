// The files of a revision (its RDTF glTF, buffers, images), fetched once per content: a file
// whose SHA-256 an earlier revision already brought (a save that changed the glTF's JSON but not
// its 18 MB buffer) is not fetched again. Each distinct content is held as one in-memory Blob with
// an object URL, which GLTFLoader reads without a request; contents no drawn or loading revision
// uses are dropped by retain().
const held = new Map();  // sha256 -> {url, promise}

function fetchOnce(file) {
  let entry = held.get(file.sha256);
  if (!entry && typeof file.text === 'string') {
    // The glTF's text came in the model message: nothing to fetch.
    const blob = new Blob([file.text], { type: 'model/gltf+json' });
    entry = { url: URL.createObjectURL(blob), promise: Promise.resolve(blob) };
    held.set(file.sha256, entry);
  }
  if (!entry) {
    entry = { url: null };
    entry.promise = fetch(file.url).then(async (response) => {
      if (!response.ok) throw new Error(`${file.path}: HTTP ${response.status}`);
      const blob = await response.blob();
      entry.url = URL.createObjectURL(blob);
      return blob;
    });
    entry.promise.catch(() => { if (held.get(file.sha256) === entry) held.delete(file.sha256); });
    held.set(file.sha256, entry);
  }
  return entry;
}

// The decoded path of a URL (relative ones resolved against `base`), to match a glTF's URI to a
// manifest file whatever each percent-encodes.
function pathKey(url, base) {
  try { return decodeURIComponent(new URL(url, base).pathname); } catch { return null; }
}

// Fetches a revision's glTF and every file it refers to; returns its JSON with each buffer and
// image URI that names a manifest file replaced by that content's object URL. URIs that name no
// manifest file (a data: URI) are left as they are.
export async function loadRevisionFiles(info) {
  const files = info.files || [];
  const gltf = files.find((f) => f.role === 'rdtf');
  if (!gltf) throw new Error('the manifest lists no RDTF glTF');
  const entries = new Map(files.filter((f) => f.role === 'rdtf' || f.role === 'buffer' || f.role === 'image')
    .map((f) => [f, fetchOnce(f)]));
  await Promise.all([...entries.values()].map((e) => e.promise));
  const json = JSON.parse(await (await entries.get(gltf).promise).text());
  const base = new URL(gltf.url, location.href).href;
  const byPath = new Map([...entries].map(([f, e]) => [pathKey(f.url, location.href), e.url]));
  for (const list of [json.buffers || [], json.images || []]) {
    for (const item of list) {
      if (typeof item.uri !== 'string' || item.uri.startsWith('data:')) continue;
      const url = byPath.get(pathKey(item.uri, base));
      if (url) item.uri = url;
    }
  }
  return { json, resourcePath: base.slice(0, base.lastIndexOf('/') + 1) };
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
