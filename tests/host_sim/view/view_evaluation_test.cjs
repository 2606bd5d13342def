// An evaluation's page in a real browser (Debian's chromium, headless, puppeteer-core): the
// exported file shows the scorecard and the cases' table; a case's link shows its replay (the same
// page, #case=NAME) with the canvas drawn; the back link returns to the scorecard; no console
// errors. Screenshots into OUT.
//
// node view_evaluation_test.cjs SCOPEKIN EVALUATION_DIR OUT CHROMIUM   (NODE_PATH: node_modules)
'use strict';
const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');
const { checks, launchChromium, newPage, drawnShare } = require('./browser_support.cjs');

const [scopekin, evaluationDir, outDir, chromium] = process.argv.slice(2);
if (!chromium) {
  console.error('usage: node view_evaluation_test.cjs SCOPEKIN EVALUATION_DIR OUT CHROMIUM');
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const { expect, finish } = checks();

(async () => {
  const exported = path.join(outDir, 'evaluation.html');
  const exp = spawnSync(scopekin, ['view', evaluationDir, '--export', exported], { encoding: 'utf8' });
  expect(exp.status === 0, `scopekin view --export of the evaluation exits 0 (${exp.status}) ${exp.stderr.trim().split('\n').pop()}`);
  const scorecard = JSON.parse(fs.readFileSync(path.join(evaluationDir, 'scorecard.json'), 'utf8'));
  const browser = await launchChromium(chromium);
  try {
    const page = await newPage(browser);
    const { errors } = page;
    await page.goto(`file://${path.resolve(exported)}`, { waitUntil: 'load' });
    await page.waitForFunction(() => window.scopekinView !== undefined, { timeout: 120000 });
    const state = await page.evaluate(() => window.scopekinView.state());
    expect(state.kind === 'evaluation', `the page shows the scorecard (${state.kind})`);
    const rows = await page.$$eval('#cases tr.viewable a', (links) => links.map((a) => a.textContent));
    expect(rows.length === scorecard.cases.length, `every case is listed with a link (${rows.length} of ${scorecard.cases.length})`);
    const overall = await page.$$eval('#overall th', (th) => th.map((x) => x.textContent));
    expect(overall.length === scorecard.overall.estimators.length + 1, `the overall table has a column per estimator (${overall.slice(1).join(', ')})`);
    await page.screenshot({ path: path.join(outDir, 'evaluation.png') });

    // A link changes the address's #case=NAME; the page loads again and shows that case.
    await page.click('#cases tr.viewable a');
    await page.waitForFunction(() => window.scopekinView !== undefined && window.scopekinView.state().kind === 'run', { timeout: 120000 });
    const shown = await page.evaluate(() => ({ state: window.scopekinView.state(), hash: location.hash, title: document.getElementById('title').textContent }));
    expect(shown.state.kind === 'run' && shown.title === rows[0], `the link shows case ${rows[0]}'s replay (${shown.hash}, ${shown.state.frames} frames, ${shown.state.alarms.length} alarms)`);
    const drawn = await drawnShare(page);
    expect(drawn > 0.01, `the case's canvas is drawn (${(100 * drawn).toFixed(1)} % of its pixels)`);
    await page.screenshot({ path: path.join(outDir, 'evaluation-case.png') });
    await page.click('#banner a');
    const back = await page.waitForFunction(() => window.scopekinView !== undefined && window.scopekinView.state().kind === 'evaluation', { timeout: 120000 })
      .then(() => true, () => false);
    expect(back, 'the back link returns to the scorecard');
    expect(errors.length === 0, `no console errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
  } finally {
    await browser.close();
  }
  finish();
})().catch((e) => {
  console.error(`FAIL ${e.stack || e}`);
  process.exit(1);
});
