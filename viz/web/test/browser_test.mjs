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
//   - when the log holds elevation maps (terrain_t on STRIDE_TERRAIN; browser_test.sh adds them):
//     GET /api/log's terrain frames are at most 2 per second of log time and none is missed, each
//     is a map of the log with its numbers (origin, resolution, counts; heights within 0.5 mm,
//     null where the log's are NaN); at each seek the page draws the newest terrain frame at or
//     before t (the first before them all) as a mesh of one vertex per known cell of that map,
//     the triangles of its squares with at most one unknown corner, spanning the known cells'
//     x, y and heights (window.stride.snapshot().terrain);
//   - the footholds the controller's gait generator chose (horizon_t.foothold*, issue 31): every
//     plan frame of GET /api/log made from a horizon of the log carries that horizon's footholds
//     (position within 1e-6, contact, time, source), the log has some (the robot trots), and at
//     each seek the page draws one ring per foothold of the horizon shown (plan_t), at its place
//     (3 mm above it) and in its source's colour (window.stride.snapshot().chosen_footholds),
//     each of the 6 sources at some seek (terrain_log.mjs gives them every source in turn);
// and saves screenshots (OUT_DIR/viewer.png at 50 %; OUT_DIR/viewer-terrain.png, the map from
// above, when there is one) and the snapshots (OUT_DIR/viewer.json).
//
// Environment: STRIDE_VIZ_NODE_MODULES, the node_modules with playwright-core (the build's
// npm install; nothing is installed in the source tree); CHROMIUM, the browser (/usr/bin/chromium).

import { mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';
import { startViz as launchViz } from './start_viz.mjs';
import { readSession, hashHex } from './lcmlog.mjs';

const TOLERANCE = 1e-6; // rad (or m for a prismatic joint)
const TERRAIN_RATE = 2; // terrain frames per second of log time, at most (viz/README.md)
const HEIGHT_STEP = 1e-3; // m: the terrain frames' rounding of heights
const MAX_AGE = 0.03; // s: a state at most this much older than the seek time (log decimation)
const RING_LIFT = 0.003; // m: the chosen footholds' rings above the foothold (overlays.js)
// The rings' colours by horizon_t.foothold_source: measured and blind grey, the map's nominal
// green, moved yellow, unreachable and unknown red.
const SOURCE_COLORS = { 0: 0x6b7480, 1: 0x6b7480, 2: 0x2fa84f, 3: 0xf2c12e, 4: 0xd62828, 5: 0xd62828 };
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
const logMaps = session.terrains;
if (logMaps.length > 0) {
  console.log(`browser_test: ${logMaps.length} maps (${logMaps[0].rows} x ${logMaps[0].cols}) ` +
              `from ${logMaps[0].t} to ${logMaps.at(-1).t} s`);
}

/** The log's map with this stamp [s], or null. */
function logMapAt(t) {
  return logMaps.find((m) => Math.abs(m.t - t) < 0.5e-6) ?? null;
}

/** What the page must draw of a map: its known cells, the triangles of the squares of four
 *  neighbouring cells with at most one unknown, their x, y, z bounds. */
function expectedMesh(m) {
  const known = (r, c) => Number.isFinite(m.height[r][c]);
  let vertices = 0;
  let triangles = 0;
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let r = 0; r < m.rows; ++r) {
    for (let c = 0; c < m.cols; ++c) {
      if (!known(r, c)) continue;
      vertices += 1;
      const p = [m.origin_x + c * m.resolution, m.origin_y + r * m.resolution, m.height[r][c]];
      p.forEach((x, i) => { lo[i] = Math.min(lo[i], x); hi[i] = Math.max(hi[i], x); });
    }
  }
  for (let r = 0; r + 1 < m.rows; ++r) {
    for (let c = 0; c + 1 < m.cols; ++c) {
      const corners = [[r, c], [r, c + 1], [r + 1, c], [r + 1, c + 1]];
      const missing = corners.filter(([a, b]) => !known(a, b)).length;
      triangles += missing === 0 ? 2 : missing === 1 ? 1 : 0;
    }
  }
  return { vertices, triangles, lo, hi };
}

const logHorizons = session.horizons;
const logFootholds = logHorizons.reduce((n, h) => n + h.nfootholds, 0);
console.log(`browser_test: ${logHorizons.length} horizons, ${logFootholds} chosen footholds`);

/** The log's horizon with this stamp [s], or null. */
function logHorizonAt(t) {
  return logHorizons.find((h) => Math.abs(h.t0 - t) < 0.5e-6) ?? null;
}

/** The chosen footholds of a log's horizon: [{p, contact, dt, source}]. */
function footholdsOf(h) {
  return h.foothold.slice(0, h.nfootholds).map((p, i) => ({
    p, contact: h.foothold_contact[i], dt: h.foothold_time[i], source: h.foothold_source[i],
  }));
}

/** The page draws the chosen footholds of the plan it shows (plan_t): one ring per foothold of
 *  the log's horizon of that stamp, at its place and in its source's colour. Returns how many. */
const coloursDrawn = new Set(); // the sources whose colour a seek drew

function checkChosen(label, snap) {
  const drawn = snap.chosen_footholds ?? [];
  const h = snap.plan_t === null ? null : logHorizonAt(snap.plan_t);
  if (!check(`${label}: the plan shown is a horizon of the log`, h !== null, `plan_t ${snap.plan_t}`)) {
    return 0;
  }
  const want = footholdsOf(h);
  if (!check(`${label}: ${want.length} chosen footholds drawn (the horizon's)`, drawn.length === want.length,
             `page ${drawn.length}`)) {
    return drawn.length;
  }
  const wrong = [];
  want.forEach((f, i) => {
    const d = drawn[i];
    const off = Math.max(Math.abs(d.position[0] - f.p[0]), Math.abs(d.position[1] - f.p[1]),
                         Math.abs(d.position[2] - RING_LIFT - f.p[2]));
    if (!(off <= 1e-6) || d.contact !== f.contact || d.source !== f.source ||
        d.color !== SOURCE_COLORS[f.source]) {
      wrong.push(`${i}: page ${JSON.stringify(d)}, log ${JSON.stringify(f)}`);
    } else {
      coloursDrawn.add(f.source);
    }
  });
  check(`${label}: each at its foothold, in its source's colour`, wrong.length === 0, wrong.slice(0, 3).join('; '));
  return drawn.length;
}

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

/** The page draws the map it must at `target`: the newest terrain frame at or before it (the
 *  first before them all), as the mesh expectedMesh() says of the log's map of that stamp. */
function checkTerrain(label, drawn, frames, target) {
  const before = frames.filter((f) => f.t <= target);
  const want = before.length > 0 ? before.at(-1) : frames[0];
  if (!check(`${label}: draws the terrain frame at or before t`,
             drawn !== null && drawn !== undefined && drawn.visible && drawn.t === want.t,
             `draws ${JSON.stringify(drawn && { t: drawn.t, visible: drawn.visible })}, frame ${want.t}`)) {
    return;
  }
  const m = logMapAt(drawn.t);
  if (!check(`${label}: a map of the log has that stamp`, m !== null, `${drawn.t}`)) return;
  const e = expectedMesh(m);
  check(`${label}: terrain mesh of ${e.vertices} vertices (known cells), ${e.triangles} triangles`,
        drawn.rows === m.rows && drawn.cols === m.cols && drawn.vertices === e.vertices &&
        drawn.triangles === e.triangles,
        `page ${drawn.rows} x ${drawn.cols}, ${drawn.vertices} vertices, ${drawn.triangles} triangles`);
  const [lo, hi] = drawn.bounds ?? [[NaN, NaN, NaN], [NaN, NaN, NaN]];
  const tol = [1e-5, 1e-5, HEIGHT_STEP / 2 + 1e-6]; // float32 positions; heights rounded to 1 mm
  const off = [0, 1, 2].map((i) => Math.max(Math.abs(lo[i] - e.lo[i]) / tol[i], Math.abs(hi[i] - e.hi[i]) / tol[i]));
  check(`${label}: terrain mesh spans the map's known cells (z ${e.lo[2].toFixed(3)} to ${e.hi[2].toFixed(3)} m)`,
        off.every((x) => x <= 1),
        `page ${JSON.stringify(drawn.bounds)}, log ${JSON.stringify([e.lo, e.hi])}`);
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
    const terrainFrames = doc.frames.filter((f) => f.type === 'terrain');
    if (logMaps.length > 0) {
      const gaps = terrainFrames.slice(1).map((f, i) => f.t - terrainFrames[i].t);
      check(`api/log: terrain frames at most ${TERRAIN_RATE} per second of log time`,
            terrainFrames.length > 0 && gaps.every((g) => g >= 1 / TERRAIN_RATE - 1e-6),
            `${terrainFrames.length} frames, gaps ${JSON.stringify(gaps)}`);
      const span = logMaps.at(-1).t - logMaps[0].t;
      check('api/log: no terrain frame missed', terrainFrames.length >= Math.floor(span * TERRAIN_RATE),
            `${terrainFrames.length} frames over ${span.toFixed(3)} s of maps`);
      let worst = 0;
      const wrong = [];
      for (const f of terrainFrames) {
        const m = logMapAt(f.t);
        if (!m || f.rows !== m.rows || f.cols !== m.cols || Math.abs(f.origin_x - m.origin_x) > 1e-6 ||
            Math.abs(f.origin_y - m.origin_y) > 1e-6 || Math.abs(f.resolution - m.resolution) > 1e-6 ||
            f.heights.length !== m.rows * m.cols) {
          wrong.push(`t ${f.t}: ${m ? 'origin, resolution or counts' : 'no map of the log'}`);
          continue;
        }
        f.heights.forEach((h, i) => {
          const want = m.height[Math.floor(i / m.cols)][i % m.cols];
          if (Number.isNaN(want) !== (h === null)) wrong.push(`t ${f.t}: cell ${i} ${h} for ${want}`);
          else if (h !== null) worst = Math.max(worst, Math.abs(h - want));
        });
      }
      check('api/log: each terrain frame is a map of the log, with its numbers',
            wrong.length === 0 && worst <= HEIGHT_STEP / 2 + 1e-7,
            `${wrong.slice(0, 5).join('; ')}; largest height error ${worst}`);
    }

    // Every plan frame made from a horizon carries its chosen footholds, and the log has some.
    check('log: the horizons carry chosen footholds (the robot trots)', logFootholds > 0,
          `${logHorizons.length} horizons, none with a foothold`);
    const planFrames = doc.frames.filter((f) => f.type === 'plan');
    let fromHorizons = 0;
    const wrongPlans = [];
    for (const f of planFrames) {
      const h = logHorizonAt(f.t);
      if (!h) continue;
      fromHorizons += 1;
      const want = footholdsOf(h);
      const got = f.chosen_footholds ?? [];
      const same = got.length === want.length && want.every((w, i) =>
        [0, 1, 2].every((k) => Math.abs(got[i][k] - w.p[k]) <= 1e-6) && got[i][3] === w.contact &&
        Math.abs(got[i][4] - w.dt) <= 1e-6 && got[i][5] === w.source);
      if (!same) wrongPlans.push(`t ${f.t}: ${JSON.stringify(got)} for ${JSON.stringify(want)}`);
    }
    check('api/log: each plan frame of a horizon carries its chosen footholds',
          fromHorizons > 0 && wrongPlans.length === 0,
          `${fromHorizons} plan frames of horizons; ${wrongPlans.slice(0, 2).join('; ')}`);

    let chosenDrawn = 0;
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
      if (logMaps.length > 0) checkTerrain(label, snap.terrain, terrainFrames, target);
      chosenDrawn += checkChosen(label, snap);
      if (fraction === 0.5) {
        await page.screenshot({ path: path.join(outDir, 'viewer.png') });
        console.log(`browser_test: screenshot ${path.join(outDir, 'viewer.png')}`);
      }
    }
    check('page: chosen footholds drawn at some seek', chosenDrawn > 0, `${chosenDrawn} rings`);
    // browser_test.sh gives the footholds every source in turn (terrain_log.mjs): all 6 drawn.
    check('page: chosen footholds of every source drawn in its colour', coloursDrawn.size === 6,
          `sources ${JSON.stringify([...coloursDrawn].sort())}`);
    if (logMaps.length > 0) {
      // The whole map from above and behind, at the middle of the log.
      const snap = await page.evaluate((o) => window.stride.seek(o), 0.5 * duration);
      const [lo, hi] = snap.terrain.bounds;
      const c = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, 0];
      await page.evaluate((v) => window.stride.camera(v),
                          { target: c, position: [c[0] - 1.2, c[1] - 2.0, c[2] + 1.9] });
      await page.screenshot({ path: path.join(outDir, 'viewer-terrain.png') });
      console.log(`browser_test: screenshot ${path.join(outDir, 'viewer-terrain.png')}`);
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
