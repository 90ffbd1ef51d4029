// The web viewer end to end in a real browser: the real objmap_server (real detector, SQLite
// file) fed redkitchen keyframes by `objmap ingest`, its viewer opened in headless Chromium
// (puppeteer-core). Checks that the inventory table lists what the gRPC inventory answers, that
// the scene holds one pickable point set per inventory object, that clicking one shows its class
// and observations (and its keyframe crops), that a keyframe arriving updates the table, that a
// pose update's regeneration moves the page's objects to where gRPC has them, that IsFree on a
// drawn box agrees with `objmap free`, and that the screenshot is neither blank nor uniform. Exit 77 (ctest: skipped) with the reason when Chromium, puppeteer-core, the data or
// the model is missing.
//
// usage: node viewer_browser_test.mjs --server BIN --objmap BIN --dataset DIR --model FILE
//                                     --out DIR [--chromium PATH] [--keyframes N]
import { spawn, execFile } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import { createInterface } from 'node:readline';
import { join } from 'node:path';
import { promisify } from 'node:util';

const SKIP = 77;
const args = Object.fromEntries(process.argv.slice(2).reduce((pairs, arg, i, all) =>
  arg.startsWith('--') ? [...pairs, [arg.slice(2), all[i + 1]]] : pairs, []));
const keyframes = Number(args.keyframes || 10);
const chromium = args.chromium || '/usr/bin/chromium';

function skip(reason) {
  console.log(`SKIPPED: ${reason}`);
  process.exit(SKIP);
}
let failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures += 1;
}

if (!existsSync(chromium)) skip(`no Chromium at ${chromium} (Debian: apt-get install chromium; scripts/test.sh installs it)`);
for (const key of ['server', 'objmap', 'dataset', 'model', 'out']) if (!args[key]) skip(`--${key} not given`);
if (!existsSync(args.dataset)) skip(`no dataset at ${args.dataset} (../shared/data)`);
if (!existsSync(args.model)) skip(`no detector model at ${args.model} (scripts/fetch_model.sh)`);
let puppeteer;
try {
  puppeteer = (await import('puppeteer-core')).default;
} catch (error) {
  skip(`puppeteer-core is not installed (npm ci in tests/http_viewer/browser; scripts/test.sh does it): ${error.message}`);
}

const run = promisify(execFile);
async function objmap(...words) {
  try {
    const { stdout } = await run(args.objmap, words, { maxBuffer: 64 << 20 });
    return { code: 0, stdout };
  } catch (error) {
    return { code: error.code, stdout: error.stdout || '', stderr: error.stderr || '' };
  }
}

mkdirSync(args.out, { recursive: true });
const db = join(args.out, `viewer_${process.pid}.db`);
const server = spawn(args.server, ['--db', db, '--listen', '127.0.0.1:0', '--http', '127.0.0.1:0',
                                   '--model', args.model], { stdio: ['ignore', 'pipe', 'inherit'] });
let browser = null;
const stop = async () => {
  if (browser) await browser.close().catch(() => {});
  server.kill('SIGTERM');
};

try {
  // "objmap_server viewer at URL", then "objmap_server listening on ADDR (...)".
  const { url, address } = await new Promise((resolve, reject) => {
    let url = null;
    const lines = createInterface({ input: server.stdout });
    lines.on('line', (line) => {
      const viewer = line.match(/viewer at (http:\/\/\S+)/);
      if (viewer) url = viewer[1];
      const listening = line.match(/listening on (\S+)/);
      if (listening) resolve({ url, address: listening[1] });
    });
    server.on('exit', (code) => reject(new Error(`objmap_server exited with ${code} before serving`)));
    setTimeout(() => reject(new Error('objmap_server did not start within 120 s')), 120000);
  });
  check(url && url.startsWith('http://127.0.0.1:'), `viewer on loopback: ${url}`);

  // --resume skips the keyframes the server holds; --max-keyframes counts the ones sent.
  const ingest = async (count) => {
    const result = await objmap('ingest', args.dataset, '--server', address, '--max-keyframes',
                                String(count), '--resume');
    if (result.code !== 0) throw new Error(`objmap ingest failed: ${result.stderr}`);
  };
  const grpcInventory = async () => JSON.parse((await objmap('inventory', '--server', address, '--json')).stdout);
  const asCounts = (entries) => Object.fromEntries(entries.map((e) => [e.class, e.count]));
  await ingest(keyframes);
  let inventory = await grpcInventory();
  check(inventory.inventory.length > 0, `gRPC inventory after ${keyframes} keyframes: ${JSON.stringify(asCounts(inventory.inventory))}`);

  browser = await puppeteer.launch({
    executablePath: chromium, headless: true,
    args: ['--no-sandbox', '--disable-dev-shm-usage', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--window-size=1280,900'],
  });
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 900 });
  const consoleErrors = [];
  page.on('pageerror', (error) => consoleErrors.push(error.message));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.objmapViewer && (window.objmapViewer.ready || window.objmapViewer.error),
                             { timeout: 120000 });
  const error = await page.evaluate(() => window.objmapViewer.error);
  check(!error, `the page loaded the map${error ? ': ' + error : ''}`);

  const table = () => page.evaluate(() => [...document.querySelectorAll('#inventory tbody tr')]
      .map((row) => [row.dataset.class, Number(row.dataset.count)]));
  const sameCounts = (rows, entries) => JSON.stringify(Object.fromEntries(rows.sort())) ===
      JSON.stringify(Object.fromEntries(Object.entries(asCounts(entries)).sort()));
  await page.waitForFunction((v) => window.objmapViewer.version >= v, { timeout: 30000 }, inventory.map_version);
  let rows = await table();
  check(sameCounts(rows, inventory.inventory),
        `the table lists the gRPC inventory: ${JSON.stringify(rows)}`);

  const inventoryIds = inventory.inventory.flatMap((e) => e.object_ids).sort((a, b) => a - b);
  const pickable = (await page.evaluate(() => window.objmapViewer.pickableIds())).sort((a, b) => a - b);
  check(JSON.stringify(pickable) === JSON.stringify(inventoryIds),
        `one pickable point set per inventory object: ${pickable} vs ${inventoryIds}`);

  // Click an object where it is visible; the panel names it as the gRPC objects query does.
  const objects = JSON.parse((await objmap('objects', '--server', address, '--json')).stdout);
  const objectList = Array.isArray(objects) ? objects : objects.objects;
  let clicked = null;
  for (const id of inventoryIds) {
    const point = await page.evaluate((i) => window.objmapViewer.screenPointOf(i), id);
    if (!point) continue;
    await page.mouse.click(point.x, point.y);
    clicked = id;
    break;
  }
  check(clicked !== null, `an inventory object is visible and clickable (#${clicked})`);
  if (clicked !== null) {
    await page.waitForFunction((id) => document.getElementById('object').dataset.objectId === String(id) &&
                               !document.getElementById('object').hidden, { timeout: 10000 }, clicked);
    const panel = await page.evaluate(() => ({
      title: document.getElementById('object-title').textContent,
      facts: document.getElementById('object-facts').textContent,
      crops: document.querySelectorAll('#object-sightings img').length,
    }));
    const expected = objectList.find((o) => o.id === clicked);
    check(expected && panel.title === `${expected.class} #${clicked}`,
          `clicking shows the class: "${panel.title}" (gRPC: ${expected && expected.class})`);
    check(expected && panel.facts.includes(`${expected.observations} observations`),
          `and the observations: "${panel.facts}" (gRPC: ${expected && expected.observations})`);
    await page.waitForFunction(() => [...document.querySelectorAll('#object-sightings img')]
        .some((img) => img.complete && img.naturalWidth > 0), { timeout: 20000 }).catch(() => {});
    const loadedCrops = await page.evaluate(() => [...document.querySelectorAll('#object-sightings img')]
        .filter((img) => img.complete && img.naturalWidth > 0).length);
    check(panel.crops > 0 && loadedCrops > 0, `its keyframe crops load (${loadedCrops} of ${panel.crops})`);

    // IsFree on a box around the clicked object's centroid agrees with `objmap free`.
    const c = expected.centroid;
    const lo = c.map((v) => (v - 0.03).toFixed(3)), hi = c.map((v) => (v + 0.03).toFixed(3));
    await page.evaluate((min, max) => {
      document.getElementById('box-min').value = min;
      document.getElementById('box-max').value = max;
    }, lo.join(','), hi.join(','));
    await page.click('#ask-free');
    await page.waitForFunction(() => document.getElementById('free-answer').dataset.free !== undefined,
                               { timeout: 20000 });
    const pageFree = await page.evaluate(() => document.getElementById('free-answer').dataset.free);
    const cliFree = await objmap('free', ...lo, ...hi, '--server', address);
    check(pageFree === String(cliFree.code === 0),
          `IsFree from the page (${pageFree}) agrees with objmap free (exit ${cliFree.code})`);
  }

  // One more keyframe: the change feed brings the page to the new version and inventory.
  const before = await page.evaluate(() => ({ version: window.objmapViewer.version, updates: window.objmapViewer.updates,
                                              keyframes: window.objmapViewer.keyframes }));
  await ingest(1);
  inventory = await grpcInventory();
  check(inventory.map_version > before.version, `a keyframe arrived: version ${before.version} -> ${inventory.map_version}`);
  await page.waitForFunction((v) => window.objmapViewer.version >= v, { timeout: 60000 }, inventory.map_version)
      .catch(() => {});
  const after = await page.evaluate(() => ({ version: window.objmapViewer.version, updates: window.objmapViewer.updates,
                                             keyframes: window.objmapViewer.keyframes,
                                             status: document.getElementById('status').textContent }));
  check(after.version >= inventory.map_version && after.updates > before.updates &&
        after.keyframes === before.keyframes + 1,
        `the page followed it: version ${after.version}, "${after.status}"`);
  rows = await table();
  const tableVersion = await page.evaluate(() => Number(document.getElementById('inventory').dataset.version));
  check(tableVersion >= inventory.map_version && sameCounts(rows, inventory.inventory),
        `the table was redrawn at version ${tableVersion} and lists the new gRPC inventory: ${JSON.stringify(rows)}`);

  // A pose-graph correction (every keyframe 0.5 m along x, through objmap update-poses): the
  // regeneration reaches the page through the feed, its objects and structure move with it.
  const posesFile = join(args.out, `poses_${process.pid}.txt`);
  const exported = await objmap('keyframes', '--server', address, '--out', posesFile);
  check(exported.code === 0, `objmap keyframes wrote the poses ${exported.stderr || ''}`);
  const shifted = readFileSync(posesFile, 'utf8').split('\n').map((line) => {
    const fields = line.split('#')[0].trim().split(/\s+/);
    if (fields.length < 8) return line;
    fields[1] = String(Number(fields[1]) + 0.5);
    return fields.join(' ');
  }).join('\n');
  writeFileSync(posesFile, shifted);
  const beforeUpdate = await page.evaluate(() => ({ loads: window.objmapViewer.structureLoads,
      centroids: Object.fromEntries(window.objmapViewer.map.objects.map((o) => [o.id, o.centroid])) }));
  const updated = await objmap('update-poses', posesFile, '--wait', '--server', address);
  check(updated.code === 0, `objmap update-poses --wait ${updated.stderr || ''}`);
  inventory = await grpcInventory();
  await page.waitForFunction((v) => window.objmapViewer.version >= v, { timeout: 60000 }, inventory.map_version)
      .catch(() => {});
  await page.waitForFunction((n) => window.objmapViewer.structureLoads > n, { timeout: 20000 },
                             beforeUpdate.loads).catch(() => {});
  const movedObjects = JSON.parse((await objmap('objects', '--server', address, '--json')).stdout);
  const pageObjects = await page.evaluate(() => Object.fromEntries(window.objmapViewer.map.objects
      .map((o) => [o.id, o.centroid])));
  const mismatched = movedObjects.filter((o) => !pageObjects[o.id] ||
      Math.hypot(...o.centroid.map((v, k) => v - pageObjects[o.id][k])) > 1e-3);
  check(movedObjects.length > 0 && mismatched.length === 0,
        `after the regeneration the page's objects are where gRPC says (${mismatched.length} of ${movedObjects.length} differ)`);
  // Every object the page showed before moved by the correction's 0.5 m (kept ids).
  const shifts = movedObjects.filter((o) => beforeUpdate.centroids[o.id])
      .map((o) => Math.hypot(...o.centroid.map((v, k) => v - beforeUpdate.centroids[o.id][k])));
  check(shifts.length > 0 && shifts.every((d) => Math.abs(d - 0.5) < 0.05),
        `and they moved by the correction: ${shifts.map((d) => d.toFixed(3)).join(' ')} m`);
  const structureLoads = await page.evaluate(() => window.objmapViewer.structureLoads);
  check(structureLoads > beforeUpdate.loads, `the page reloaded the moved structure (${structureLoads} loads)`);

  // The screenshot: neither blank nor one colour (measured by the browser itself on the PNG).
  const png = await page.screenshot({ type: 'png' });
  writeFileSync(join(args.out, 'viewer.png'), png);
  const stats = await page.evaluate(async (data) => {
    const image = new Image();
    image.src = 'data:image/png;base64,' + data;
    await image.decode();
    const canvas = document.createElement('canvas');
    canvas.width = image.width;
    canvas.height = image.height;
    const context = canvas.getContext('2d');
    context.drawImage(image, 0, 0);
    // The 3D view only: the left part, without the panel.
    const width = image.width - 380;
    const pixels = context.getImageData(0, 0, width, image.height).data;
    const colours = new Set();
    let sum = 0, squares = 0;
    for (let i = 0; i < pixels.length; i += 4 * 7) {
      const grey = (pixels[i] + pixels[i + 1] + pixels[i + 2]) / 3;
      sum += grey;
      squares += grey * grey;
      colours.add((pixels[i] >> 3) << 10 | (pixels[i + 1] >> 3) << 5 | pixels[i + 2] >> 3);
    }
    const n = pixels.length / (4 * 7);
    return { colours: colours.size, stddev: Math.sqrt(squares / n - (sum / n) ** 2) };
  }, png.toString('base64'));
  check(stats.colours > 50 && stats.stddev > 8,
        `the 3D view is neither blank nor uniform: ${stats.colours} colours, grey stddev ${stats.stddev.toFixed(1)} (${join(args.out, 'viewer.png')})`);
  check(consoleErrors.length === 0, `no script errors in the page ${consoleErrors.join('; ')}`);
} catch (error) {
  console.log(`FAIL ${error.stack || error}`);
  failures += 1;
} finally {
  await stop();
}
console.log(failures === 0 ? 'viewer browser test: passed' : `viewer browser test: ${failures} failed`);
process.exit(failures === 0 ? 0 : 1);
