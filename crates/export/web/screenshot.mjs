// Full-page screenshot of a report opened from disk in headless Debian Chromium.
//   node screenshot.mjs OUT/index.html SHOT.png [WIDTHxHEIGHT]
// Used to make the README's picture of the report; the checks live in browser-test.mjs.
import { chromium } from 'playwright-core';
import { pathToFileURL } from 'node:url';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';

const [page_path, shot, size = '1280x900'] = process.argv.slice(2);
if (!page_path || !shot) {
  console.error('usage: node screenshot.mjs INDEX.html SHOT.png [WIDTHxHEIGHT]');
  process.exit(2);
}
const [width, height] = size.split('x').map(Number);
const profile = mkdtempSync(join(tmpdir(), 'surfcap-shot-'));
try {
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    headless: true,
    viewport: { width, height },
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
  const page = await context.newPage();
  await page.goto(pathToFileURL(resolve(page_path)).href);
  await page.waitForTimeout(1500);
  await page.screenshot({ path: shot, fullPage: false });
  await context.close();
} finally {
  rmSync(profile, { recursive: true, force: true });
}
