// Drives rdtf-view's page in Debian's headless chromium for the C++ browser tests
// (tests/clients/view_itest.cc): one JSON request per line on stdin, one JSON answer per line on
// stdout, in order.
//   {"open": URL}                       -> {"ok": true}            loads the page
//   {"eval": "JS expression"}           -> {"ok": true, "value": V}  awaited, JSON-serialised
//   {"screenshot": PATH}                -> {"ok": true}
//   {"quit": true}                      -> exits
// Any failure answers {"ok": false, "error": "..."}. Console errors of the page go to stderr.
// CHROMIUM (default /usr/bin/chromium) is started headless with SwiftShader's software WebGL.
import puppeteer from 'puppeteer-core';
import readline from 'node:readline';

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
    '--disable-dev-shm-usage', '--no-first-run', '--no-default-browser-check', '--window-size=1280,800'],
  defaultViewport: { width: 1280, height: 800 },
  // Chromium's start and the first load are the slow steps on a loaded machine (two cores shared
  // with a build): puppeteer's own 30 s gave up on them while the tests' waits still had time.
  timeout: 120000,
});
const page = await browser.newPage();
page.on('console', (m) => { if (m.type() === 'error' || m.type() === 'warn') process.stderr.write(`page ${m.type()}: ${m.text()}\n`); });
page.on('pageerror', (e) => process.stderr.write(`page error: ${e.message}\n`));

const answer = (value) => process.stdout.write(`${JSON.stringify(value)}\n`);
const lines = readline.createInterface({ input: process.stdin });
for await (const line of lines) {
  let request;
  try {
    request = JSON.parse(line);
    if (request.quit) break;
    if (request.open) {
      await page.goto(request.open, { waitUntil: 'load', timeout: 120000 });
      answer({ ok: true });
    } else if (request.eval !== undefined) {
      const value = await page.evaluate(`(async () => (${request.eval}))()`);
      answer({ ok: true, value: value === undefined ? null : value });
    } else if (request.screenshot) {
      await page.screenshot({ path: request.screenshot });
      answer({ ok: true });
    } else {
      answer({ ok: false, error: 'unknown request' });
    }
  } catch (e) {
    answer({ ok: false, error: String(e && e.message ? e.message : e) });
  }
}
await browser.close();
