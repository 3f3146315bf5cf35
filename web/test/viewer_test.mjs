// The web viewer in a real browser: a generated office is baked, `viewcells view` writes the
// site, headless Chromium opens it, the test clicks the middle of the picture and checks that
// the cell and PVS the page highlights are what `viewcells query` says for the point the page
// chose; the screenshot (kept in WORK/viewer.png) must not be blank, and the page must log no
// errors. Usage: node viewer_test.mjs VIEWCELLS_BINARY WORK_DIR
import { execFileSync } from 'node:child_process';
import { mkdirSync, rmSync, readFileSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { launch, openSite } from './browser.mjs';

const [viewcells, workArg] = process.argv.slice(2);
if (!viewcells || !workArg) { console.error('usage: node viewer_test.mjs VIEWCELLS WORK_DIR'); process.exit(2); }
const work = resolve(workArg);
rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
const run = (...args) => execFileSync(viewcells, ['-q', ...args], { cwd: work, encoding: 'utf8' });
const fail = (why) => { console.error('FAIL: ' + why); process.exitCode = 1; };

run('generate', 'office', '--size', '1', '-o', 'office.obj');
run('bake', 'office.obj', '--cells', '24', '--samples', '60000', '--max-cells', '150', '--agvs-samples', '100000',
    '--merge-pvs', 'samples', '-o', 'office.pvs');
run('view', 'office.pvs', '--scene', 'office.obj', '-o', 'site', '--gltf', 'office-cells.glb');

// Inside the building, at eye height over the middle of the floor plan, looking down ahead.
const info = JSON.parse(readFileSync(join(work, 'site', 'data.js'), 'utf8').replace(/^window\.VIEWCELLS_DATA = /, '').replace(/;\s*$/, ''));
const [x0, y0, z0, x1, y1] = info.view_box;
const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2, eyeZ = z0 + 1.6;
const hash = `camera=${cx - 2},${cy},${eyeZ}&target=${cx + 1},${cy},${z0 + 0.2}`;

// What a screenshot shows: its distinct colours, its share of background, and the distinct
// cell colours in it (pixels within 3 of a cell's colour as the page draws it: 8-bit sRGB, the
// cells' cross-sections opaque and unlit), outside the panel (whose legend holds every colour
// of the scale).
async function screenshotStats(page, png) {
  return page.evaluate(async (data) => {
    const v = window.viewcells;
    const keys = [];
    for (let c = 0; c < v.cellCount; ++c) {
      const [r, g, b] = v.cellColour(c);
      keys.push((r << 16) | (g << 8) | b);
    }
    const img = new Image();
    img.src = 'data:image/png;base64,' + data;
    await img.decode();
    const cv = document.createElement('canvas');
    cv.width = img.width; cv.height = img.height;
    const g = cv.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, cv.width, cv.height).data;
    const colours = new Set(), shown = new Set(), near = new Map();
    let background = 0, green = 0;
    const hud = document.getElementById('hud').getBoundingClientRect();
    const ratio = cv.width / window.innerWidth;
    for (let i = 0; i < d.length; i += 4) {
      const key = (d[i] << 16) | (d[i + 1] << 8) | d[i + 2];
      colours.add(key);
      if (Math.abs(d[i] - 0x15) + Math.abs(d[i + 1] - 0x17) + Math.abs(d[i + 2] - 0x1c) < 6) ++background;
      if (d[i + 1] > d[i] + 40 && d[i + 1] > d[i + 2] + 40) ++green;
      const x = (i / 4) % cv.width / ratio, y = Math.floor(i / 4 / cv.width) / ratio;
      if (x >= hud.left && x <= hud.right && y >= hud.top && y <= hud.bottom) continue;
      let hit = near.get(key);
      if (hit === undefined) {
        hit = keys.find((k) => Math.abs((k >> 16) - d[i]) + Math.abs(((k >> 8) & 255) - d[i + 1]) +
                               Math.abs((k & 255) - d[i + 2]) <= 3);
        near.set(key, hit);
      }
      if (hit !== undefined) shown.add(hit);
    }
    return { colours: colours.size, background: background / (d.length / 4), green: green / (d.length / 4), shown: shown.size,
             distinct: new Set(keys).size, crossed: v.sectionCells.length };
  }, png.toString('base64'));
}

const browser = await launch();
try {
  // First sight, before any click: the cutaway at mid-height shows the cells' cross-sections in
  // their colours. At least a quarter of the cells' colours must show; with the cut off (the
  // view as it was: the roof, translucent cells behind it) far fewer do.
  const cellCount = info.cells.count;
  for (const [name, h] of [['default', ''], ['no-cut', 'cut=off']]) {
    const { page, errors } = await openSite(browser, join(work, 'site', 'index.html'), h);
    await page.waitForTimeout(300);
    const shotPath = join(work, `viewer-${name}.png`);
    const png = await page.screenshot({ path: shotPath });
    const seen = await screenshotStats(page, png);
    console.log(`${name} view (${shotPath}): ${seen.shown} cell colours shown of ${seen.distinct} distinct among ` +
                `${cellCount} cells (the cut crosses ${seen.crossed})`);
    if (name === 'default') {
      if (!(await page.evaluate(() => window.viewcells.cut !== null))) fail('the cutaway is not on by default');
      if (seen.shown < Math.ceil(cellCount / 4)) fail(`the first view shows ${seen.shown} cell colours, fewer than a quarter of ${cellCount} cells`);
    } else if (seen.shown >= Math.ceil(cellCount / 4)) {
      fail(`without the cut the check should fail (the roof hides the cells), yet ${seen.shown} colours show: it cannot tell`);
    }
    if (errors.length) fail(`the ${name} view logged errors: ` + errors.join('; '));
    await page.close();
  }

  // The play space (the office's floors, found as bake finds them) is drawn in green: without the
  // cells (#cells=none: neither they nor their cross-sections), the first view has clearly more
  // green pixels than with #play=0 too.
  const greens = [];
  for (const h of ['cells=none', 'cells=none&play=0']) {
    const { page, errors } = await openSite(browser, join(work, 'site', 'index.html'), h);
    await page.waitForTimeout(300);
    const play = await page.evaluate(() => window.viewcells.playSpace);
    const png = await page.screenshot({ path: join(work, `viewer-${h.replace(/[=&]/g, '-')}.png`) });
    greens.push((await screenshotStats(page, png)).green);
    if (!(play.triangles > 0)) fail(`no play space drawn: ${play.rule}`);
    if (play.visible !== !h.includes('play=0')) fail(`play space visible ${play.visible} with '${h}'`);
    if (errors.length) fail('the page logged errors: ' + errors.join('; '));
    await page.close();
  }
  console.log(`play space: ${(100 * greens[0]).toFixed(1)}% green pixels drawn, ${(100 * greens[1]).toFixed(1)}% without it`);
  if (!(greens[0] > greens[1] + 0.02)) fail('the play space does not show as green floors');

  const { page, errors } = await openSite(browser, join(work, 'site', 'index.html'), hash);
  const box = await page.locator('canvas').boundingBox();
  await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
  await page.waitForFunction(() => window.viewcells.selected !== null, null, { timeout: 60000 });
  const selected = await page.evaluate(() => window.viewcells.selected);
  console.log(`clicked: point (${selected.point.join(', ')}), cell ${selected.cell}, PVS of ${selected.pvs.length} objects`);
  if (selected.cell < 0) fail('the click chose no cell');
  // What the toolkit says for that point.
  const query = JSON.parse(run('query', 'office.pvs', ...selected.point.map(String), '--json'));
  if (query.cell !== selected.cell) fail(`page shows cell ${selected.cell}, query says ${query.cell}`);
  const expected = query.pvs.map((o) => o.id);
  if (JSON.stringify(expected) !== JSON.stringify(selected.pvs))
    fail(`page highlights ${JSON.stringify(selected.pvs)}, query says ${JSON.stringify(expected)}`);
  // The highlight is on the objects: their colours in the page's buffers.
  const lit = await page.evaluate(() => {
    const s = window.viewcells.selected;
    return { cellText: document.getElementById('selection').textContent };
  });
  if (!lit.cellText.includes(`cell ${selected.cell} of`) || !lit.cellText.includes(`sees ${selected.pvs.length} of`))
    fail('the panel does not say the chosen cell and its PVS size: ' + lit.cellText);
  // Drawing only the PVS draws exactly its objects' triangles.
  run('info', 'office.obj', '--json', 'info.json');
  const sceneInfo = JSON.parse(readFileSync(join(work, 'info.json'), 'utf8'));
  const pvsTriangles = selected.pvs.reduce((sum, o) => sum + sceneInfo.object_list[o].triangles, 0);
  await page.selectOption('#draw', 'pvs');
  const drawnPvs = await page.evaluate(() => window.viewcells.sceneTrianglesDrawn);
  await page.selectOption('#draw', 'all');
  const drawnAll = await page.evaluate(() => window.viewcells.sceneTrianglesDrawn);
  if (drawnPvs !== pvsTriangles) fail(`drawing the PVS draws ${drawnPvs} triangles, its objects have ${pvsTriangles}`);
  if (drawnAll !== sceneInfo.triangles) fail(`the page draws ${drawnAll} triangles, the scene has ${sceneInfo.triangles}`);
  console.log(`draw only the PVS: ${drawnPvs} of ${drawnAll} triangles`);
  // Half resolution draws half the pixels each way.
  const fullWidth = await page.evaluate(() => document.querySelector('canvas').width);
  await page.selectOption('#scale', '0.5');
  const halfWidth = await page.evaluate(() => document.querySelector('canvas').width);
  if (Math.abs(halfWidth - fullWidth / 2) > 1) fail(`half resolution: canvas ${halfWidth} wide, full ${fullWidth}`);
  await page.selectOption('#scale', '1');
  await page.waitForTimeout(300);
  const shot = join(work, 'viewer.png');
  await page.screenshot({ path: shot });
  // Not blank: many colours, and most pixels differ from the background.
  const stats = await screenshotStats(page, readFileSync(shot));
  console.log(`screenshot ${shot}: ${stats.colours} colours, ${(100 * stats.background).toFixed(1)}% background`);
  if (stats.colours < 50) fail(`the screenshot has only ${stats.colours} colours`);
  if (stats.background > 0.9) fail('the screenshot is mostly background');
  // Escape clears the choice; the camera's own cell can be followed.
  await page.keyboard.press('Escape');
  if ((await page.evaluate(() => window.viewcells.selected)) !== null) fail('Escape did not clear the choice');
  await page.keyboard.press('f');
  await page.waitForFunction(() => window.viewcells.selected !== null, null, { timeout: 60000 });
  const followed = await page.evaluate(() => window.viewcells.selected);
  const cameraCell = JSON.parse(run('query', 'office.pvs', ...followed.point.map(String), '--json')).cell;
  if (followed.cell !== cameraCell) fail(`following the camera shows cell ${followed.cell}, query says ${cameraCell}`);
  if (errors.length) fail('the page logged errors: ' + errors.join('; '));
} finally {
  await browser.close();
}
if (!process.exitCode) console.log('PASS');
