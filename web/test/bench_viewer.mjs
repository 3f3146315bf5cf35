// Frame time of the web viewer in headless Chromium (SwiftShader: software WebGL, no GPU),
// turning about the scene so that every frame draws a new view, and the time from a click to
// the lit PVS (ray cast against the scene, then the colours). Prints one JSON line.
// Usage: node bench_viewer.mjs SITE/index.html [SECONDS] [WIDTHxHEIGHT] [HASH]
// (HASH: more of the address's settings, e.g. cells=none)
import { launch, openSite } from './browser.mjs';
import { resolve } from 'node:path';

const [index, secondsArg, sizeArg, extraHash] = process.argv.slice(2);
if (!index) { console.error('usage: node bench_viewer.mjs SITE/index.html [SECONDS] [WIDTHxHEIGHT]'); process.exit(2); }
const seconds = Number(secondsArg || 10);
const [width, height] = (sizeArg || '1280x720').split('x').map(Number);
const browser = await launch();
try {
  const t0 = Date.now();
  const { page, errors } = await openSite(browser, resolve(index), (extraHash || '').includes('spin=') ? extraHash : 'spin=1' + (extraHash ? '&' + extraHash : ''), { width, height });
  const loadSeconds = (Date.now() - t0) / 1000;
  await page.waitForFunction(() => window.viewcells.frameTimes().length > 3, null, { timeout: 300000 });
  await page.waitForTimeout(seconds * 1000);
  const frames = await page.evaluate(() => window.viewcells.frameTimes());
  const clicks = await page.evaluate(() => {
    const out = [];
    for (const [x, y] of [[0, 0], [0.2, -0.2], [-0.3, -0.1], [0.1, 0.3], [-0.1, -0.4]]) {
      const t = performance.now();
      window.viewcells.pick(x, y);
      out.push(performance.now() - t);
    }
    return out;
  });
  const sorted = frames.slice(5).sort((a, b) => a - b);
  const q = (p) => sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
  console.log(JSON.stringify({
    site: index, settings: extraHash || '', viewport: `${width}x${height}`, seconds, frames: sorted.length,
    load_seconds: +loadSeconds.toFixed(2), frame_ms_median: +q(0.5).toFixed(1), frame_ms_p95: +q(0.95).toFixed(1),
    click_ms_median: +clicks.sort((a, b) => a - b)[2].toFixed(1), errors,
  }));
} finally {
  await browser.close();
}
