// The paper's snapshot figures as frames of stride-viz's page: each log played by `stride-viz
// --log LOG --port 0 --all-frames`, opened in headless Chromium (playwright-core, as
// viz/web/test/browser_test.mjs), and a screenshot of the 3D view taken at each chosen time with
// the camera placed by the page's hook (window.stride.camera). tools/paper/snapshots.py writes the
// spec, runs this and composes the frames into one figure.
//
//   node snapshots.mjs SPEC.json
//
// SPEC: {
//   "viz": stride-viz, "chromium": the browser (default $CHROMIUM or /usr/bin/chromium),
//   "node_modules": the build's node_modules with playwright-core (build/viz/web/npm/node_modules),
//   "out_dir": where the frames (row<r>_<i>.png) and manifest.json go,
//   "rows": [{"label", "log"}], one log per row,
//   "times": [s], motion time of each frame: seconds from the log's first frame,
//   "tile": [width, height] of a frame [CSS px], "scale": device pixels per CSS px (default 1),
//   "camera": {"direction": [x, y, z] from the target to the camera, "height": metres of the
//     world the frame spans vertically at the target, "target": [x, y, z] fixed, or "base" to
//     look at the robot's base (x, y) at height "target_z"}
// }
//
// Fails (exit 1, one line per failure) on: a console error or page error; a request to anything
// but stride-viz (aborted and recorded; WebSockets too); stride-viz warnings or refused messages
// (another model hash, a malformed message); a time at which the page does not show the log's
// state stamped there (within 1 µs). manifest.json holds, per frame, the page's snapshot()
// (stamp, joint angles read back from the drawn robot, base, planned forces) and the camera, for
// the caller's checks.

import { mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { startViz as launchViz } from '../../viz/web/test/start_viz.mjs';

const READY_TIMEOUT_MS = 60000;
const TOTAL_TIMEOUT_MS = 240000;
// A time is sought this far past its stamp: the state stamped there is shown whatever the
// rounding of (first stamp + time) in floating point. Far below a knot (20 ms or more).
const SEEK_PAST = 1e-4;
const STAMP_TOLERANCE = 1e-6; // s: the frames' stamps are rounded to 1 µs

const specPath = process.argv[2];
if (!specPath || process.argv.length !== 3) {
  console.error('usage: snapshots.mjs SPEC.json');
  process.exit(2);
}
const spec = JSON.parse(readFileSync(specPath, 'utf8'));
const chromiumPath = spec.chromium || process.env.CHROMIUM || '/usr/bin/chromium';
const { chromium } = createRequire(path.join(path.resolve(spec.node_modules), 'noop.js'))('playwright-core');
const [tileWidth, tileHeight] = spec.tile;
const scale = spec.scale ?? 1;

const failures = [];
function fail(what) {
  failures.push(what);
  console.error(`snapshots: FAIL ${what}`);
}

function startViz(log) {
  return launchViz(spec.viz, ['--log', log, '--port', '0', '--all-frames']);
}

async function stopViz(viz) {
  if (viz.child.exitCode !== null || viz.child.signalCode !== null) return;
  const exited = new Promise((r) => viz.child.once('exit', r));
  viz.child.kill('SIGTERM');
  await Promise.race([exited, new Promise((r) => setTimeout(r, 5000))]);
  if (viz.child.exitCode === null && viz.child.signalCode === null) viz.child.kill('SIGKILL');
}

const add = (a, b) => a.map((x, i) => x + b[i]);
const times = (a, s) => a.map((x) => x * s);
function unit(a) {
  const n = Math.hypot(...a);
  if (!(n > 0)) throw new Error('camera.direction must not be zero');
  return times(a, 1 / n);
}

/** What stride-viz says it refused or warned about: none may be, or the figure is not the log's. */
function sourceProblems(info) {
  const problems = [...(info.warnings ?? [])];
  for (const [channel, count] of Object.entries(info.messages?.channels ?? {})) {
    for (const [reason, n] of Object.entries(count.rejected ?? {})) {
      problems.push(`${n} message(s) on ${channel} refused: ${reason}`);
    }
  }
  return problems;
}

async function renderRow(browser, row, r) {
  const viz = startViz(row.log);
  let context = null;
  try {
    const base = await viz.url;
    const origin = new URL(base).origin;
    const host = new URL(base).host;
    const info = await (await fetch(new URL('api/info', base))).json();
    for (const p of sourceProblems(info)) fail(`${row.log}: stride-viz: ${p}`);
    const doc = await (await fetch(new URL('api/log', base))).json();
    const stateTimes = doc.frames.filter((f) => f.type === 'state').map((f) => f.t);
    if (stateTimes.length === 0) throw new Error(`${row.log}: no state frame`);
    const t0 = Math.min(...doc.frames.map((f) => f.t));

    // The 3D view a little larger than a frame: the frame is cut from its centre.
    context = await browser.newContext({
      viewport: { width: tileWidth + 270, height: tileHeight + 60 }, deviceScaleFactor: scale,
    });
    const foreign = [];
    await context.route('**/*', (route) => {
      const url = route.request().url();
      if (url.startsWith('data:') || url.startsWith('blob:') || new URL(url).origin === origin) {
        route.continue();
      } else {
        foreign.push(url);
        route.abort();
      }
    });
    const page = await context.newPage();
    const sockets = [];
    page.on('websocket', (ws) => sockets.push(ws.url()));
    const errors = [];
    page.on('console', (msg) => {
      if (msg.type() === 'error') errors.push(`console: ${msg.text()}`);
    });
    page.on('pageerror', (e) => errors.push(`page error: ${e.message}`));
    await page.goto(base);
    await page.waitForFunction(() => window.stride && window.stride.ready === true, null,
                               { timeout: READY_TIMEOUT_MS });
    // The figure shows the robot only: the legend (its scale goes in the figure's caption) and
    // the message box off. An inline style: nothing is fetched.
    await page.addStyleTag({ content: '#legend, #message { display: none !important; }' });
    const view = await page.locator('#view canvas').boundingBox();
    if (view.width < tileWidth || view.height < tileHeight) {
      throw new Error(`the 3D view (${view.width} x ${view.height}) is smaller than a frame`);
    }
    const clip = {
      x: view.x + Math.round((view.width - tileWidth) / 2),
      y: view.y + Math.round((view.height - tileHeight) / 2),
      width: tileWidth,
      height: tileHeight,
    };
    const cam = spec.camera;
    const dir = unit(cam.direction);
    const frames = [];
    for (let i = 0; i < spec.times.length; ++i) {
      const t = spec.times[i];
      const want = t0 + t;
      const shown = await page.evaluate((o) => window.stride.seek(o), t + SEEK_PAST);
      const stamp = stateTimes.filter((s) => s <= want + SEEK_PAST).reduce((a, b) => Math.max(a, b), -Infinity);
      if (shown.t === null || Math.abs(shown.t - want) > STAMP_TOLERANCE || shown.t !== stamp) {
        fail(`${row.log}: at ${t} s the page shows the state of ${shown.t === null ? 'none' : (shown.t - t0).toFixed(6)} s, not one stamped there`);
      }
      // The camera: the view spans `height` metres vertically at the target over the frame's
      // height (the frame is part of the view: the view's own height spans more).
      const camera0 = await page.evaluate(() => window.stride.camera());
      const tan = Math.tan((camera0.fov * Math.PI) / 360);
      const distance = (cam.height * view.height) / (2 * tileHeight * tan);
      const target = cam.target === 'base'
        ? [shown.base[0], shown.base[1], cam.target_z]
        : cam.target;
      const camera = await page.evaluate((v) => window.stride.camera(v),
                                         { target, position: add(target, times(dir, distance)) });
      // Two animation frames: what stays drawn, not only what was set.
      await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
      const snap = await page.evaluate(() => window.stride.snapshot());
      const png = path.join(spec.out_dir, `row${r}_${String(i).padStart(2, '0')}.png`);
      await page.screenshot({ path: png, clip });
      frames.push({ time: t, png, snapshot: snap, camera });
    }
    for (const u of foreign) fail(`${row.log}: the page asked for ${u} (only stride-viz may be asked)`);
    for (const u of sockets) if (new URL(u).host !== host) fail(`${row.log}: a WebSocket to ${u}`);
    for (const e of errors) fail(`${row.log}: ${e}`);
    if (viz.child.exitCode !== null || viz.child.signalCode !== null) {
      fail(`${row.log}: stride-viz stopped early; stderr:\n${viz.stderr()}`);
    }
    return { label: row.label, log: row.log, t0, info, frames };
  } finally {
    if (context) await context.close();
    await stopViz(viz);
  }
}

async function main() {
  mkdirSync(spec.out_dir, { recursive: true });
  const overall = setTimeout(() => {
    console.error(`snapshots: FAIL more than ${TOTAL_TIMEOUT_MS / 1000} s`);
    process.exit(1);
  }, TOTAL_TIMEOUT_MS);
  const args = [];
  if (process.getuid && process.getuid() === 0) args.push('--no-sandbox'); // root: no sandbox
  const browser = await chromium.launch({ executablePath: chromiumPath, headless: true, args });
  const rows = [];
  try {
    for (let r = 0; r < spec.rows.length; ++r) rows.push(await renderRow(browser, spec.rows[r], r));
  } finally {
    clearTimeout(overall);
    await browser.close();
  }
  writeFileSync(path.join(spec.out_dir, 'manifest.json'), JSON.stringify({ rows }, null, 1));
  return failures.length === 0 ? 0 : 1;
}

main().then((code) => process.exit(code), (e) => {
  console.error(`snapshots: FAIL ${e.stack ?? e}`);
  process.exit(1);
});
