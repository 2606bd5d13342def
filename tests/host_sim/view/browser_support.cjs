// What the view's browser tests share: the checks' tally and Debian's chromium, headless.
'use strict';
const puppeteer = require('puppeteer-core');

/// expect(condition, message) prints "ok" or "FAIL" and counts failures; finish() exits with them.
function checks() {
  let failures = 0;
  return {
    expect(condition, message) {
      console.log(`${condition ? 'ok  ' : 'FAIL'} ${message}`);
      if (!condition) failures += 1;
    },
    finish() {
      console.log(failures === 0 ? 'all checks passed' : `${failures} check(s) failed`);
      process.exit(failures === 0 ? 0 : 1);
    },
  };
}

/// Headless chromium; WebGL in software (SwiftShader: the machines have no GPU); no sandbox (root).
function launchChromium(executablePath) {
  return puppeteer.launch({
    executablePath,
    headless: true,
    args: ['--no-sandbox', '--disable-dev-shm-usage', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
}

/// A page of 1280 x 900 with generous timeouts (the tests share a loaded 2-core machine) and the
/// console errors and uncaught exceptions collected into page.errors.
async function newPage(browser) {
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 900 });
  page.setDefaultTimeout(120000);
  page.setDefaultNavigationTimeout(120000);
  page.errors = [];
  page.on('console', (m) => { if (m.type() === 'error') page.errors.push(m.text()); });
  page.on('pageerror', (e) => page.errors.push(String(e)));
  return page;
}

/// The share of the 3D canvas's pixels that are not the background (0x101418).
async function drawnShare(page) {
  return page.evaluate(() => {
    const src = document.querySelector('#scene canvas');
    const c = document.createElement('canvas');
    c.width = src.width; c.height = src.height;
    const ctx = c.getContext('2d');
    ctx.drawImage(src, 0, 0);
    const px = ctx.getImageData(0, 0, c.width, c.height).data;
    let drawn = 0;
    for (let k = 0; k < px.length; k += 4)
      if (Math.abs(px[k] - 0x10) + Math.abs(px[k + 1] - 0x14) + Math.abs(px[k + 2] - 0x18) > 12) drawn += 1;
    return drawn / (px.length / 4);
  });
}

module.exports = { checks, launchChromium, newPage, drawnShare };
