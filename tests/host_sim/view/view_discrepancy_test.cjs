// A discrepancy report's page in a real browser (Debian's chromium, headless, puppeteer-core):
// the exported file (view_checks.py discrepancy writes it) shows the verdict, the effect, the
// error tables and one chart per output, without console errors. Screenshot into OUT.
//
// node view_discrepancy_test.cjs PAGE.html OUT CHROMIUM   (NODE_PATH: the view's node_modules)
'use strict';
const fs = require('node:fs');
const path = require('node:path');
const { checks, launchChromium, newPage } = require('./browser_support.cjs');

const [file, outDir, chromium] = process.argv.slice(2);
if (!chromium) {
  console.error('usage: node view_discrepancy_test.cjs PAGE.html OUT CHROMIUM');
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const { expect, finish } = checks();

(async () => {
  const browser = await launchChromium(chromium);
  try {
    const page = await newPage(browser);
    const { errors } = page;
    await page.goto(`file://${path.resolve(file)}`, { waitUntil: 'load' });
    await page.waitForFunction(() => window.scopekinView !== undefined, { timeout: 120000 });
    const state = await page.evaluate(() => window.scopekinView.state());
    expect(state.kind === 'discrepancy' && state.verdict === 'single', `the page shows the report (${state.kind}, verdict ${state.verdict})`);
    expect(state.charts === 2, `one chart per output component (${state.charts})`);
    const effect = await page.$eval('#effects', (t) => t.textContent);
    expect(/ei_scale/.test(effect) && /0\.85/.test(effect) && /93 %/.test(effect), `the effect with its value and share (${effect.replace(/\s+/g, ' ')})`);
    const errorsTable = await page.$eval('#errors', (t) => t.textContent);
    expect(/88 %/.test(errorsTable), 'the handle force\'s held-out error 0.8 -> 0.1 reads 88 % less');
    await page.screenshot({ path: path.join(outDir, 'discrepancy.png') });
    expect(errors.length === 0, `no console errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
  } finally {
    await browser.close();
  }
  finish();
})().catch((e) => {
  console.error(`FAIL ${e.stack || e}`);
  process.exit(1);
});
