// Headless Chromium (Debian's /usr/bin/chromium) driven by playwright-core, for the viewer's
// test and its frame-time benchmark. WebGL runs on SwiftShader: these machines have no GPU.
import { chromium } from 'playwright-core';

export const CHROMIUM = process.env.VIEWCELLS_CHROMIUM || '/usr/bin/chromium';

export async function launch() {
  return chromium.launch({
    executablePath: CHROMIUM,
    headless: true,
    args: ['--no-sandbox', '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--no-first-run', '--disable-quic', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--allow-file-access-from-files'],
  });
}

/// Opens a site written by `viewcells view` and waits until the viewer has drawn.
export async function openSite(browser, indexHtml, hash, viewport = { width: 960, height: 640 }) {
  const page = await browser.newPage({ viewport });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto('file://' + indexHtml + (hash ? '#' + hash : ''));
  await page.waitForFunction(() => window.viewcells && window.viewcells.ready, null, { timeout: 120000 });
  // Drawn at least once (the viewer draws on demand).
  await page.waitForFunction(() => window.viewcells.drawn > 0, null, { timeout: 120000 });
  return { page, errors };
}
