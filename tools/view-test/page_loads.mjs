// Loads rdtf-view's page once in Debian's headless chromium and checks that it came up whole: every
// module it imports served (no failed request, no HTTP error), no script error, and the test hook
// answering with a WebGL renderer. For the packaging test (tests/packaging/deb_test.sh), which
// serves the page from the installed tree. Prints what went wrong and exits 1, else prints the
// modules loaded and exits 0.
// Usage: node page_loads.mjs URL
import puppeteer from 'puppeteer-core';

const url = process.argv[2];
const problems = [];
const modules = [];
const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium', headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-dev-shm-usage', '--window-size=1280,800'],
});
try {
  const page = await browser.newPage();
  page.on('pageerror', (e) => problems.push(`script error: ${e.message}`));
  page.on('console', (m) => { if (m.type() === 'error' && !/favicon\.ico/.test(m.location()?.url ?? '')) problems.push(`console error: ${m.text()} ${m.location()?.url ?? ''}`); });
  page.on('requestfailed', (r) => problems.push(`request failed: ${r.url()} (${r.failure()?.errorText})`));
  page.on('response', (r) => {
    if (r.status() >= 400 && !r.url().endsWith('/favicon.ico')) problems.push(`HTTP ${r.status()}: ${r.url()}`);
    else if (r.url().endsWith('.js')) modules.push(new URL(r.url()).pathname);
  });
  await page.goto(url, { waitUntil: 'load' });
  const renderer = await page.waitForFunction(() => window.rdtfView && window.rdtfView.state().renderer.name, { timeout: 30000 })
    .then((h) => h.jsonValue()).catch((e) => { problems.push(`no test hook: ${e.message}`); return null; });
  if (renderer) console.log(`renderer: ${renderer}`);
} finally {
  await browser.close();
}
console.log(`modules: ${modules.join(' ')}`);
if (problems.length) {
  console.error(problems.join('\n'));
  process.exit(1);
}
