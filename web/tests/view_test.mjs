// Opens a source's page in headless Chromium (Debian's, through playwright-core),
// waits for a drawn frame, checks the page's box count, saves screenshots of the
// 2D and 3D views.
//   node view_test.mjs URL EXPECTED_BOXES OUT_2D.png OUT_3D.png
// Exit 0 when the page showed EXPECTED_BOXES boxes; prints what it saw as JSON.
import { chromium } from 'playwright-core';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const [url, expectedText, shot2d, shot3d] = process.argv.slice(2);
if (!url || expectedText === undefined || !shot2d || !shot3d) {
  console.error('usage: node view_test.mjs URL EXPECTED_BOXES OUT_2D.png OUT_3D.png');
  process.exit(2);
}
const expected = Number(expectedText);
const profile = mkdtempSync(join(tmpdir(), 'cornerpose-chromium-'));
// A fresh profile (--user-data-dir, which playwright takes as this argument).
const browser = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  headless: true,
  viewport: { width: 1400, height: 1100 },
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run',
    // WebGL in software (SwiftShader) for the 3D view.
    '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
let status = 1;
try {
  const page = browser.pages()[0] || await browser.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  // Every request goes to the server under test: no CDN, nothing else.
  const origin = new URL(url).origin;
  const foreign = [];
  page.on('request', (r) => { if (!r.url().startsWith(origin) && !r.url().startsWith('data:')) foreign.push(r.url()); });
  await page.goto(url);
  await page.waitForFunction(() => Number(document.getElementById('box-count').dataset.frameId) > 0,
    null, { timeout: 60000 });
  // Let the 3D view fetch and draw the frame's cloud.
  await page.waitForTimeout(2000);
  const seen = await page.evaluate(() => ({
    boxes: Number(document.getElementById('box-count').textContent),
    frame_id: Number(document.getElementById('box-count').dataset.frameId),
    rows: document.querySelectorAll('#box-table tbody tr').length,
    state: document.getElementById('source-state').textContent,
  }));
  await page.locator('.views').screenshot({ path: shot2d });
  // The 3D view turned by the mouse, as an operator would.
  const view = page.locator('#cloud-view canvas');
  const box = await view.boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 + 120, box.y + box.height / 2 + 40, { steps: 10 });
  await page.mouse.up();
  await view.screenshot({ path: shot3d });
  console.log(JSON.stringify({ ...seen, expected, errors, foreign }));
  status = seen.boxes === expected && seen.rows === expected && errors.length === 0 && foreign.length === 0 ? 0 : 1;
} finally {
  await browser.close();
  rmSync(profile, { recursive: true, force: true });
}
process.exit(status);
