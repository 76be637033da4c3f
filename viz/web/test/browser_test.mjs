// stride-viz's page in headless Chromium, on a real log (viz/web/README.md, "Test").
//
//   node browser_test.mjs STRIDE_VIZ LOG OUT_DIR
//
// Starts `STRIDE_VIZ --log LOG --port 0`, reads the port from its first line, opens the page and
// checks, against test/lcmlog.mjs's own reading of LOG (not stride-viz's):
//   - no console error and no page error, from the load to the end;
//   - the page loads with no network access but stride-viz: every request to another origin is
//     aborted and recorded, and none may be made (WebSockets too);
//   - window.stride.ready comes; the loaded URDF has as many movable joints as the model in the
//     log (robot_model_t) has actuated joints (nq - 7 with a floating base), and the page names
//     them in the model's wire order;
//   - at 10 %, 50 % and 90 % of the timeline, seek(t) shows the newest state frame with a stamp
//     at or before t (the frames of GET /api/log), a state of the log (same stamp), at most
//     MAX_AGE old, and the joint angles the URDF robot holds equal that state's q in the log
//     (index idx_q of robot_model_t) within 1e-6;
// and saves a screenshot (OUT_DIR/viewer.png, at 50 %) and the snapshots (OUT_DIR/viewer.json).
//
// Environment: STRIDE_VIZ_NODE_MODULES, the node_modules with playwright-core (the build's
// npm install; nothing is installed in the source tree); CHROMIUM, the browser (/usr/bin/chromium).

import { mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { startViz as launchViz } from './start_viz.mjs';
import { readSession, hashHex } from './lcmlog.mjs';

const TOLERANCE = 1e-6; // rad (or m for a prismatic joint)
const MAX_AGE = 0.03; // s: a state at most this much older than the seek time (log decimation)
const READY_TIMEOUT_MS = 60000;
const TOTAL_TIMEOUT_MS = 170000;

const [vizBin, logPath, outDir] = process.argv.slice(2);
if (!vizBin || !logPath || !outDir) {
  console.error('usage: browser_test.mjs STRIDE_VIZ LOG OUT_DIR');
  process.exit(2);
}
const modules = process.env.STRIDE_VIZ_NODE_MODULES;
if (!modules) {
  console.error('browser_test: set STRIDE_VIZ_NODE_MODULES to the node_modules that hold playwright-core');
  process.exit(2);
}
const chromiumPath = process.env.CHROMIUM || '/usr/bin/chromium';
const { chromium } = createRequire(path.join(path.resolve(modules), 'noop.js'))('playwright-core');

let passed = 0;
const failed = [];
function check(name, ok, detail = '') {
  if (ok) {
    passed += 1;
    console.log(`ok    ${name}`);
  } else {
    failed.push(name);
    console.log(`FAIL  ${name}${detail ? `: ${detail}` : ''}`);
  }
  return ok;
}

// ---- the log, read here ----
const session = readSession(readFileSync(logPath));
const model = session.model;
const logStates = session.states;
if (!model) throw new Error(`${logPath}: no robot_model_t on STRIDE_MODEL`);
if (logStates.length === 0) throw new Error(`${logPath}: no robot_state_t on STRIDE_STATE`);
const floating = model.joint_types[0] === 'free-flyer';
const actuated = model.joint_names
  .map((name, i) => ({ name, type: model.joint_types[i], idx: model.joint_idx_q[i] }))
  .filter((j) => j.type !== 'free-flyer');
console.log(`browser_test: ${logPath}: ${model.robot} (hash ${hashHex(model.model_hash)}, nq ${model.nq}), ` +
            `${logStates.length} states from ${logStates[0].t} to ${logStates.at(-1).t} s`);
check('log: states in time order', logStates.every((s, i) => i === 0 || s.t > logStates[i - 1].t));
check('log: every state of the model', logStates.every((s) => s.nq === model.nq && s.model_hash === model.model_hash));

/** The log's state with this stamp [s] (frames carry t = utime * 1e-6), or null. */
function logStateAt(t) {
  let lo = 0;
  let hi = logStates.length - 1;
  while (lo <= hi) {
    const mid = (lo + hi) >> 1;
    const d = logStates[mid].t - t;
    if (Math.abs(d) < 0.5e-6) return logStates[mid];
    if (d < 0) lo = mid + 1; else hi = mid - 1;
  }
  return null;
}

// ---- stride-viz ----
function startViz() {
  return launchViz(vizBin, ['--log', logPath, '--port', '0']);
}

async function main() {
  mkdirSync(outDir, { recursive: true });
  const viz = startViz();
  let browser = null;
  const overall = setTimeout(() => {
    console.log(`FAIL  the test took more than ${TOTAL_TIMEOUT_MS / 1000} s`);
    viz.child.kill('SIGKILL');
    process.exit(1);
  }, TOTAL_TIMEOUT_MS);
  try {
    const base = await viz.url;
    const origin = new URL(base).origin;
    console.log(`browser_test: stride-viz at ${base}`);

    const launchArgs = [];
    if (process.getuid && process.getuid() === 0) launchArgs.push('--no-sandbox'); // root: no sandbox
    browser = await chromium.launch({ executablePath: chromiumPath, headless: true, args: launchArgs });
    const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });

    // Offline: only stride-viz's origin is reachable; anything else is aborted and recorded.
    const requests = [];
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
    context.on('request', (r) => requests.push(r.url()));
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
    check('page: window.stride.ready', true);

    const snap0 = await page.evaluate(() => window.stride.snapshot());
    check('page: log mode', snap0.mode === 'log', `mode ${snap0.mode}`);
    check('page: frames received', snap0.frames_received > 0, `${snap0.frames_received}`);
    const expectedJoints = floating ? model.nq - 7 : model.nq;
    check(`URDF: movable joints = actuated joints of the model (${expectedJoints})`,
          snap0.urdf_joint_count === expectedJoints && actuated.length === expectedJoints,
          `URDF ${snap0.urdf_joint_count}, model ${actuated.length} (nq ${model.nq})`);
    check('page: joint names in the model\'s wire order',
          JSON.stringify(snap0.joint_names) === JSON.stringify(actuated.map((j) => j.name)),
          `page ${JSON.stringify(snap0.joint_names)}`);

    // The served frames, for the rule "newest state at or before t" (stride-viz decimates).
    const doc = await (await fetch(new URL('api/log', base))).json();
    const frameTimes = doc.frames.map((f) => f.t);
    const t0 = frameTimes.reduce((a, b) => Math.min(a, b), Infinity);
    const t1 = frameTimes.reduce((a, b) => Math.max(a, b), -Infinity);
    const duration = await page.evaluate(() => window.stride.duration());
    check('page: duration() spans the log\'s frames',
          Math.abs(duration - (t1 - t0)) < 1e-9, `${duration}`);
    const stateTimes = doc.frames.filter((f) => f.type === 'state').map((f) => f.t);

    const snapshots = [];
    for (const fraction of [0.1, 0.5, 0.9]) {
      const offset = fraction * duration;
      const target = t0 + offset;
      const label = `${Math.round(fraction * 100)} % (t ${target.toFixed(4)} s)`;
      await page.evaluate((o) => window.stride.seek(o), offset);
      // Two animation frames later: what stays drawn, not only what seek() returned.
      await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
      const snap = await page.evaluate(() => window.stride.snapshot());
      snapshots.push({ fraction, offset, target, ...snap });
      const expectedT = stateTimes.filter((t) => t <= target).reduce((a, b) => Math.max(a, b), -Infinity);
      check(`${label}: shows the newest state at or before t`, snap.t === expectedT,
            `shows ${snap.t}, newest ${expectedT}`);
      check(`${label}: the state is at most ${MAX_AGE} s old`, target - snap.t <= MAX_AGE + 1e-9,
            `${(target - snap.t).toFixed(4)} s`);
      const state = logStateAt(snap.t);
      if (!check(`${label}: a state of the log has that stamp`, state !== null, `${snap.t}`)) continue;
      const want = actuated.map((j) => state.q[j.idx]);
      const errs = want.map((w, i) => Math.abs(w - snap.joint_angles[i]));
      const worst = Math.max(...errs.map((e) => (Number.isFinite(e) ? e : Infinity)));
      check(`${label}: joint angles = the log's within ${TOLERANCE}`,
            snap.joint_angles.length === want.length && worst <= TOLERANCE,
            `largest error ${worst} (${actuated[errs.indexOf(worst)]?.name}); page ` +
            `${JSON.stringify(snap.joint_angles)}, log ${JSON.stringify(want)}`);
      if (fraction === 0.5) {
        await page.screenshot({ path: path.join(outDir, 'viewer.png') });
        console.log(`browser_test: screenshot ${path.join(outDir, 'viewer.png')}`);
      }
    }
    writeFileSync(path.join(outDir, 'viewer.json'), JSON.stringify({ base, snapshots, requests, sockets }, null, 1));

    check('offline: nothing requested from another origin', foreign.length === 0, foreign.join(', '));
    check('offline: every request to stride-viz',
          requests.length >= 4 && requests.every((u) => u.startsWith('data:') || new URL(u).origin === origin),
          `${requests.length} requests: ${requests.filter((u) => !u.startsWith(origin)).join(', ')}`);
    const host = new URL(base).host;
    check('offline: WebSockets only to stride-viz', sockets.every((u) => new URL(u).host === host),
          sockets.join(', '));
    check('page: no console error, no page error', errors.length === 0, `\n  ${errors.join('\n  ')}`);
    check('stride-viz still running', viz.child.exitCode === null && viz.child.signalCode === null,
          `exit ${viz.child.exitCode ?? viz.child.signalCode}; stderr:\n${viz.stderr()}`);
  } finally {
    clearTimeout(overall);
    if (browser) await browser.close();
    if (viz.child.exitCode === null) {
      const exited = new Promise((r) => viz.child.once('exit', r));
      viz.child.kill('SIGTERM');
      await Promise.race([exited, new Promise((r) => setTimeout(r, 5000))]);
      if (viz.child.exitCode === null && viz.child.signalCode === null) viz.child.kill('SIGKILL');
    }
  }
  console.log(`${passed} passed, ${failed.length} failed`);
  return failed.length === 0 ? 0 : 1;
}

main().then((code) => process.exit(code), (e) => {
  console.log(`FAIL  ${e.stack ?? e}`);
  console.log(`${passed} passed, ${failed.length + 1} failed`);
  process.exit(1);
});
