// `scopekin simulate --view` in a real browser (Debian's chromium, headless, puppeteer-core): the
// page receives the run while it is simulated (messages, frames and time advance), without
// console errors; once the run ends, a reload shows its replay; SIGTERM ends simulate with the
// run's exit status. Prints the rate at which messages arrived (a figure, not a check: wall-clock
// rates are not asserted in tests). Screenshots into OUT.
//
// node view_live_test.cjs SCOPEKIN SCENARIO RUN_DIR OUT CHROMIUM   (NODE_PATH: the view's node_modules)
'use strict';
const { spawn } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');
const { checks, launchChromium, newPage } = require('./browser_support.cjs');

const [scopekin, scenario, runDir, outDir, chromium] = process.argv.slice(2);
if (!chromium) {
  console.error('usage: node view_live_test.cjs SCOPEKIN SCENARIO RUN_DIR OUT CHROMIUM');
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const { expect, finish } = checks();
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

(async () => {
  const sim = spawn(scopekin, ['simulate', scenario, '--out', runDir, '--view', '--no-browser', '--port', '0', '--quiet'],
    { stdio: ['ignore', 'pipe', 'inherit'] });
  let out = '';
  sim.stdout.on('data', (d) => { out += d; });
  const exited = new Promise((r) => sim.on('exit', (code) => r(code)));
  const waitFor = async (pattern, ms) => {
    for (let waited = 0; waited < ms; waited += 100) {
      const m = out.match(pattern);
      if (m) return m;
      if (sim.exitCode !== null) break;
      await sleep(100);
    }
    throw new Error(`simulate did not print ${pattern} in ${ms / 1000} s: ${out}`);
  };
  const url = (await waitFor(/live view at (http:\/\/127\.0\.0\.1:\d+\/)/, 60000))[1];
  const browser = await launchChromium(chromium);
  try {
    const page = await newPage(browser);
    const { errors } = page;
    await page.goto(url, { waitUntil: 'load', timeout: 120000 });
    await page.waitForFunction(() => window.scopekinView !== undefined && window.scopekinView.messagesReceived >= 3, { timeout: 120000 });
    const a = await page.evaluate(() => window.scopekinView.state());
    const wallA = Date.now();
    await sleep(1500);
    const b = await page.evaluate(() => window.scopekinView.state());
    const seconds = (Date.now() - wallA) / 1000;
    expect(a.live && b.live, 'the page is the live page');
    expect(b.messages > a.messages, `messages keep arriving (${a.messages} -> ${b.messages})`);
    expect(b.frames > a.frames, `frames keep arriving (${a.frames} -> ${b.frames})`);
    expect(b.time_s > a.time_s, `the cursor follows the run (${a.time_s.toFixed(2)} -> ${b.time_s.toFixed(2)} s simulated)`);
    console.log(`     figure: ${((b.messages - a.messages) / seconds).toFixed(1)} messages and ${((b.frames - a.frames) / seconds).toFixed(1)} frames per wall second, ` +
      `${((b.time_s - a.time_s) / seconds).toFixed(1)} simulated s per wall s, ${((b.frames_drawn - a.frames_drawn) / seconds).toFixed(1)} canvas draws per s`);
    await page.screenshot({ path: path.join(outDir, 'live-running.png') });
    // The charts, redrawn as the run grows, are drawn by the CPU (web/src/chart.js): on a software
    // GPU their redraws held the page at 7 frames per second.
    const charts = await page.evaluate(() => [...document.querySelectorAll('#timeline canvas')]
      .map((c) => c.getContext('2d').getContextAttributes().willReadFrequently));
    expect(charts.length === 3 && charts.every((v) => v === true), `the live charts' canvases are drawn by the CPU (willReadFrequently: ${JSON.stringify(charts)})`);

    await waitFor(/replay is at/, 600000);
    await sleep(500);
    const ended = await page.evaluate(() => ({ banner: document.getElementById('banner').textContent, state: window.scopekinView.state() }));
    expect(/complete/.test(ended.banner), `the live page says the run is complete ("${ended.banner}")`);
    await page.screenshot({ path: path.join(outDir, 'live-ended.png') });
    await page.reload({ waitUntil: 'load' });
    await page.waitForFunction(() => window.scopekinView !== undefined, { timeout: 120000 });
    const replay = await page.evaluate(() => window.scopekinView.state());
    expect(!replay.live && replay.frames > 0, `a reload shows the replay (${replay.frames} frames, ${replay.alarms.length} alarms)`);
    expect(errors.length === 0, `no console errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
  } finally {
    await browser.close();
    sim.kill('SIGTERM');
  }
  const code = await exited;
  expect(code === 0, `simulate ends with the run's exit status 0 on SIGTERM (${code})`);
  finish();
})().catch((e) => {
  console.error(`FAIL ${e.stack || e}`);
  process.exit(1);
});
