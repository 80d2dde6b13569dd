// Runs the Khronos glTF validator on one file and prints its report as JSON on stdout.
// External resources are read relative to the file's own folder, as a viewer would.
// Usage: node validate.mjs MODEL.gltf|MODEL.glb
// Exit code: 0 when the report has no errors, 3 when it has errors, 1 when the file cannot be read.
import fs from 'node:fs/promises';
import path from 'node:path';
import validator from 'gltf-validator';

const file = process.argv[2];
if (!file) {
  console.error('usage: node validate.mjs MODEL');
  process.exit(1);
}
let bytes;
try {
  bytes = new Uint8Array(await fs.readFile(file));
} catch (e) {
  console.error(`${file}: ${e.message}`);
  process.exit(1);
}
const folder = path.dirname(file);
const report = await validator.validateBytes(bytes, {
  uri: path.basename(file),
  maxIssues: 0,
  externalResourceFunction: (uri) =>
    fs.readFile(path.resolve(folder, decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
});
process.stdout.write(JSON.stringify(report, null, 2) + '\n');
// Not process.exit(): on a pipe, stdout is written asynchronously, and exiting at once cut a report
// longer than the pipe's 64 KiB off mid-JSON. Node exits with this code once stdout is flushed.
process.exitCode = report.issues.numErrors > 0 ? 3 : 0;
