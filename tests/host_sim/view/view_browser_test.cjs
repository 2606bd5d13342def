// `scopekin view` in a real browser (Debian's chromium, headless, driven by puppeteer-core):
// the served page and the exported file load without console errors, the 3D canvas is drawn,
// scrubbing to an alarm changes the scene and highlights that alarm. Screenshots are written
// into OUT as test artifacts.
//
// node view_browser_test.cjs SCOPEKIN RUN_DIR OUT CHROMIUM     (NODE_PATH: the view's node_modules)
// Exit status 0 passed, 1 a check failed (each failure printed), 2 bad usage.
'use strict';
const { spawn, spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');
const { checks, launchChromium, newPage, drawnShare } = require('./browser_support.cjs');

const [scopekin, runDir, outDir, chromium] = process.argv.slice(2);
if (!scopekin || !runDir || !outDir || !chromium) {
  console.error('usage: node view_browser_test.cjs SCOPEKIN RUN_DIR OUT CHROMIUM');
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const { expect, finish } = checks();

/// Starts `scopekin view RUN --no-browser --port 0` and resolves with its URL and process.
function serve() {
  return new Promise((resolve, reject) => {
    const child = spawn(scopekin, ['view', runDir, '--no-browser', '--port', '0'], { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    const timer = setTimeout(() => reject(new Error(`no address printed in 60 s: ${out}`)), 60000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/at (http:\/\/127\.0\.0\.1:\d+\/)/);
      if (m) { clearTimeout(timer); resolve({ url: m[1], child }); }
    });
    child.stderr.on('data', (d) => process.stderr.write(d));
    child.on('exit', (code) => { clearTimeout(timer); reject(new Error(`scopekin view exited ${code}: ${out}`)); });
  });
}

/// A digest of the 3D canvas (it changes when the scene does).
async function sceneDigest(page) {
  return page.evaluate(() => {
    const data = document.querySelector('#scene canvas').toDataURL('image/png');
    let h = 0;
    for (let k = 0; k < data.length; k++) h = (h * 31 + data.charCodeAt(k)) | 0;
    return `${data.length}:${h}`;
  });
}

async function waitFrames(page, n) {
  await page.evaluate((count) => new Promise((done) => {
    let left = count;
    const step = () => (--left <= 0 ? done() : requestAnimationFrame(step));
    requestAnimationFrame(step);
  }), n);
}

/// Loads `url`, checks it, scrubs to the first alarm; `name` prefixes the screenshots.
async function checkPage(browser, url, name) {
  const page = await newPage(browser);
  const { errors } = page;
  await page.goto(url, { waitUntil: 'load', timeout: 120000 });
  await page.waitForFunction(() => window.scopekinView !== undefined, { timeout: 120000 });
  await waitFrames(page, 3);
  const state = await page.evaluate(() => window.scopekinView.state());
  expect(state.frames > 1, `${name}: the page holds the run's shapes (${state.frames} frames)`);
  const share = await drawnShare(page);
  expect(share > 0.01, `${name}: the canvas is drawn (${(100 * share).toFixed(1)} % of its pixels are not the background)`);
  await page.screenshot({ path: path.join(outDir, `${name}-start.png`) });

  expect(state.alarms.length > 0, `${name}: the run has alarms (${state.alarms.length})`);
  if (state.alarms.length > 0) {
    const before = await sceneDigest(page);
    const alarm = state.alarms[0];
    // Through the page's own control: the next-alarm button from the start.
    await page.click('#next-alarm');
    await waitFrames(page, 3);
    const after = await page.evaluate(() => window.scopekinView.state());
    expect(Math.abs(after.time_s - alarm.start_s) < 1e-6, `${name}: "next alarm" moves the cursor to the first alarm (${after.time_s.toFixed(3)} s, raised at ${alarm.start_s.toFixed(3)} s)`);
    expect(after.active_alarms.includes(0), `${name}: that alarm is highlighted in the list (${JSON.stringify(after.active_alarms)})`);
    const highlighted = await page.$$eval('#alarms li.active', (li) => li.map((x) => x.dataset.index));
    expect(highlighted.includes('0'), `${name}: its list item carries the highlight`);
    expect(after.frame_index !== state.frame_index, `${name}: the scene shows another frame (${state.frame_index} -> ${after.frame_index})`);
    const digest = await sceneDigest(page);
    expect(digest !== before, `${name}: the canvas changed`);
    await page.screenshot({ path: path.join(outDir, `${name}-alarm.png`) });
  }
  // Playing advances the time.
  const t0 = await page.evaluate(() => window.scopekinView.time_s);
  await page.click('#play');
  await new Promise((r) => setTimeout(r, 600));
  await page.click('#play');
  const t1 = await page.evaluate(() => window.scopekinView.time_s);
  expect(t1 > t0, `${name}: play advances the time (${t0.toFixed(2)} -> ${t1.toFixed(2)} s)`);
  expect(errors.length === 0, `${name}: no console errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
  await page.close();
}

(async () => {
  const exported = path.join(outDir, 'view.html');
  const exp = spawnSync(scopekin, ['view', runDir, '--export', exported], { encoding: 'utf8' });
  expect(exp.status === 0 && fs.existsSync(exported), `scopekin view --export wrote ${exported} (exit ${exp.status}) ${exp.stderr.trim()}`);
  const server = await serve();
  const browser = await launchChromium(chromium);
  try {
    await checkPage(browser, server.url, 'served');
    await checkPage(browser, `file://${path.resolve(exported)}`, 'exported');
  } finally {
    await browser.close();
    server.child.kill('SIGTERM');
  }
  const code = await new Promise((r) => (server.child.exitCode !== null ? r(server.child.exitCode) : server.child.on('exit', (c) => r(c))));
  expect(code === 0, `scopekin view ends with exit status 0 on SIGTERM (${code})`);
  finish();
})().catch((e) => {
  console.error(`FAIL ${e.stack || e}`);
  process.exit(1);
});
