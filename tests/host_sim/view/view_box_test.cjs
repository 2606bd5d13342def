// The box's own page in a real browser (Debian's chromium, headless, puppeteer-core), from
// `scopekin run RECORDING --view` (the recording through the firmware at --pace) or `scopekin
// display BOX_LOG` (the box's CAN frames at --pace): while it goes, the page receives the box's
// outputs (messages and the cursor's time advance), shows only what the box knows (no truth
// series, no true tip, no scope shape), without console errors; SIGTERM ends the command with 0.
// Screenshot OUT/NAME.png.
//
// node view_box_test.cjs OUT CHROMIUM NAME COMMAND [ARGS...]   (NODE_PATH: node_modules)
'use strict';
const { spawn } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');
const { checks, launchChromium, newPage } = require('./browser_support.cjs');

const [outDir, chromium, shotName, command, ...commandArgs] = process.argv.slice(2);
if (!command) {
  console.error('usage: node view_box_test.cjs OUT CHROMIUM NAME COMMAND [ARGS...]');
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const { expect, finish } = checks();
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

(async () => {
  // Paced as the box lived it (--pace 1): the recording's seconds to watch it.
  const run = spawn(command, commandArgs, { stdio: ['ignore', 'pipe', 'inherit'] });
  let out = '';
  run.stdout.on('data', (d) => { out += d; });
  const exited = new Promise((r) => run.on('exit', (code) => r(code)));
  for (let waited = 0; !/view at (http\S+)/.test(out) && waited < 60000; waited += 100) await sleep(100);
  const url = out.match(/view at (http:\/\/127\.0\.0\.1:\d+\/)/)[1];
  const browser = await launchChromium(chromium);
  try {
    const page = await newPage(browser);
    const { errors } = page;
    await page.goto(url, { waitUntil: 'load', timeout: 120000 });
    await page.waitForFunction(() => window.scopekinView !== undefined && window.scopekinView.messagesReceived >= 3, { timeout: 120000 });
    const a = await page.evaluate(() => window.scopekinView.state());
    await sleep(1500);
    const b = await page.evaluate(() => window.scopekinView.state());
    expect(b.messages > a.messages && b.time_s > a.time_s, `the box's outputs keep arriving (${a.messages} -> ${b.messages} messages, ${a.time_s.toFixed(2)} -> ${b.time_s.toFixed(2)} s)`);
    const knows = await page.evaluate(() => {
      const v = window.scopekinView;
      const s = v.data.series;
      return {
        boxOnly: v.data.box_only === true,
        truth: s.true_tip_path_mm.some((x) => x !== null) || s.true_max_force_N.some((x) => x !== null),
        boxTip: s.box_tip_path_mm.some((x) => x !== null),
        trueTipShown: v.scene.trueTip.visible,
        scope: v.data.frames.length,
      };
    });
    expect(knows.boxOnly && knows.boxTip, 'the page is the box\'s, with the box\'s tip');
    expect(!knows.truth && !knows.trueTipShown && knows.scope === 0, `no truth on it (truth series ${knows.truth}, true tip shown ${knows.trueTipShown}, shapes ${knows.scope})`);
    await page.screenshot({ path: path.join(outDir, `${shotName}.png`) });
    for (let waited = 0; !/stays at/.test(out) && waited < 120000; waited += 200) await sleep(200);
    expect(/stays at/.test(out), 'it says when the recording has gone through');
    expect(errors.length === 0, `no console errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
  } finally {
    await browser.close();
    run.kill('SIGTERM');
  }
  const code = await exited;
  expect(code === 0, `it ends with 0 on SIGTERM (${code})`);
  finish();
})().catch((e) => {
  console.error(`FAIL ${e.stack || e}`);
  process.exit(1);
});
