// What the paper's snapshot figures showed, checked against the logs they were drawn from, read
// here by viz/web/test/lcmlog.mjs (not by stride-viz):
//
//   node snapshots_check.mjs SHOWN.json [--locked SUMMARY.json] [--hash HEX] [--forces]
//
// SHOWN.json is what tools/paper/snapshots.py writes beside a figure (the page's snapshot() at
// each frame). For every frame: the page showed the log's state stamped at the frame's time (the
// log's first stamp + time, within 1 µs), its joints named in the log's robot_model_t wire
// order, and the angles read back from the drawn robot equal that state's q within 1e-6.
// --locked: the joints of SUMMARY.json's "locked_joints" (stride-paper-astronaut) show the
// angles they are locked at, within 1e-6. --hash: every message of the log carries this model
// hash. --forces: the page showed the log's horizon stamped at the frame's time, and its planned
// forces equal the horizon's knot 0 within 1e-6.
// Prints one line per check; exits 1 when one fails.

import { readFileSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const { readSession, hashHex } = await import(path.join(here, '../../viz/web/test/lcmlog.mjs'));

const TOLERANCE = 1e-6;
const args = process.argv.slice(2);
const shownPath = args[0];
const option = (name) => {
  const i = args.indexOf(name);
  return i >= 0 ? args[i + 1] : null;
};
if (!shownPath) {
  console.error('usage: snapshots_check.mjs SHOWN.json [--locked SUMMARY.json] [--hash HEX] [--forces]');
  process.exit(2);
}
const shown = JSON.parse(readFileSync(shownPath, 'utf8'));
const locked = option('--locked') ? JSON.parse(readFileSync(option('--locked'), 'utf8')).locked_joints : null;
const hash = option('--hash');
const forces = args.includes('--forces');

let passed = 0;
let failed = 0;
function check(name, ok, detail = '') {
  if (ok) {
    passed += 1;
    console.log(`ok    ${name}`);
  } else {
    failed += 1;
    console.log(`FAIL  ${name}${detail ? `: ${detail}` : ''}`);
  }
}

const near = (a, b) => Math.abs(a - b) <= TOLERANCE;
const figure = path.basename(shownPath);

for (const row of shown.rows) {
  const session = readSession(readFileSync(row.log));
  const { model, states, horizons } = session;
  const name = `${figure} ${row.label || path.basename(row.log)}`;
  if (!model || states.length === 0) {
    check(`${name}: the log has a robot model and states`, false);
    continue;
  }
  const actuated = model.joint_names
    .map((n, i) => ({ name: n, type: model.joint_types[i], idx: model.joint_idx_q[i] }))
    .filter((j) => j.type !== 'free-flyer');
  if (hash !== null) {
    const all = [model, ...states, ...horizons].every((m) => hashHex(m.model_hash) === hash);
    check(`${name}: every message carries the model hash ${hash}`, all,
          `robot_model_t's ${hashHex(model.model_hash)}`);
  }
  const t0 = states[0].t;
  check(`${name}: the figure has frames`, row.frames.length > 0);
  if (forces) {
    // Not a figure of zeros: the soles carry the robot's weight.
    const largest = Math.max(0, ...row.frames.flatMap((f) => f.snapshot.planned_forces.map((x) => Math.hypot(...x))));
    check(`${name}: planned forces drawn (largest ${largest.toFixed(0)} N)`, largest > 100);
  }
  for (const frame of row.frames) {
    const snap = frame.snapshot;
    const label = `${name} at ${frame.time.toFixed(3)} s`;
    const state = states.find((s) => Math.abs(s.t - snap.t) < 0.5e-6);
    check(`${label}: shows the log's state stamped there`,
          state !== undefined && Math.abs(snap.t - t0 - frame.time) <= TOLERANCE,
          `shows ${snap.t}, wanted ${t0 + frame.time}`);
    if (!state) continue;
    check(`${label}: joints in the model's wire order`,
          JSON.stringify(snap.joint_names) === JSON.stringify(actuated.map((j) => j.name)),
          JSON.stringify(snap.joint_names));
    const errs = actuated.map((j, i) => Math.abs(state.q[j.idx] - snap.joint_angles[i]));
    const worst = Math.max(...errs.map((e) => (Number.isFinite(e) ? e : Infinity)));
    check(`${label}: joint angles = the log's within ${TOLERANCE}`,
          snap.joint_angles.length === actuated.length && worst <= TOLERANCE,
          `largest error ${worst} (${actuated[errs.indexOf(worst)]?.name})`);
    if (locked) {
      const bad = Object.entries(locked).filter(([joint, angle]) => {
        const i = snap.joint_names.indexOf(joint);
        return i < 0 || !near(snap.joint_angles[i], angle);
      });
      check(`${label}: the ${Object.keys(locked).length} locked joints at their locked angles`,
            Object.keys(locked).length > 0 && bad.length === 0,
            bad.map(([j, a]) => `${j}: page ${snap.joint_angles[snap.joint_names.indexOf(j)]}, locked ${a}`).join(', '));
    }
    if (forces) {
      const h = horizons.find((x) => Math.abs(x.t0 - snap.t) < 0.5e-6);
      check(`${label}: shows the log's plan stamped there`, h !== undefined && snap.plan_t === snap.t,
            `plan ${snap.plan_t}`);
      if (h) {
        const want = [];
        for (let c = 0; c < h.ncontacts; ++c) want.push(h.force[0].slice(3 * c, 3 * c + 3));
        const same = snap.planned_forces.length === want.length &&
          want.every((f, c) => f.every((x, i) => near(x, snap.planned_forces[c][i])));
        check(`${label}: planned forces = the log's`, same,
              `page ${JSON.stringify(snap.planned_forces)}, log ${JSON.stringify(want)}`);
      }
    }
  }
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 ? 0 : 1);
