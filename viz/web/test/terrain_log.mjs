// Elevation maps added to a session log, for the browser test (and screenshots) of the terrain
// drawing: the log's robot walks on flat ground in stride-sim, and these maps are what a
// perception stack would publish of a made-up world around it, on STRIDE_TERRAIN as terrain_t
// (messages/terrain_t.lcm), encoded here by test/lcmlog.mjs (its fingerprint checked against
// lcm-gen's by lcmlog_test.mjs). The robot's path (|y| < 0.35 m) stays flat at z = 0, so its feet
// stand on the map; beside it:
//   a box step to the left: 8 cm for 0.2 < x < 0.6, then 16 cm to x = 1.0 (0.35 < y < 0.7);
//   a pit to the left behind: -10 cm (-0.7 < x < -0.4, 0.35 < y < 0.7);
//   a ramp to the right, rising 0.4 m per m from y = -0.4 outwards;
//   unknown cells (NaN) over -0.2 < x < 0.1, -0.75 < y < -0.55 (as if hidden from the sensor).
// Maps of 100 x 100 cells of 2 cm (stride-sim's default) centred on the robot's base, their origin
// on the 2 cm grid, at 10 Hz of the robot's clock: one after the first state at or past each
// 0.1 s, stamped with that state's stamp. The maps the log already holds on STRIDE_TERRAIN
// (stride-sim's, of its flat ground) are left out: the test's are the only ones.
// The controller planned blind (it never saw these maps), so its horizons' chosen footholds
// (horizon_t.foothold_source, issue 31) are all measured or blind: they are given every source in
// turn instead (foothold i of the k-th horizon: (i + k) mod 6), so that the browser test sees each
// source's colour drawn. Nothing else of a horizon changes.
//
//   node terrain_log.mjs IN OUT    writes IN with the maps added as OUT

import { readFileSync, writeFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import {
  decode, encode, horizonType, readLog, robotStateType, terrainType, writeLog,
} from './lcmlog.mjs';

export const MAP = { rows: 100, cols: 100, resolution: 0.02, period: 100000 /* us */ };
export const CHANNEL = 'STRIDE_TERRAIN';
export const HORIZON_CHANNEL = 'STRIDE_HORIZON';
export const SOURCES = 6; // horizon_t.foothold_source: 0 measured ... 5 unknown to the map

const inside = (v, lo, hi) => v > lo && v < hi;

/** The made-up world's height at (x, y) [m]; NaN where the map does not know it. */
export function worldHeight(x, y) {
  if (inside(x, -0.2, 0.1) && inside(y, -0.75, -0.55)) return NaN;
  if (inside(y, 0.35, 0.7)) {
    if (inside(x, 0.2, 0.6)) return 0.08;
    if (inside(x, 0.6, 1.0)) return 0.16;
    if (inside(x, -0.7, -0.4)) return -0.1;
  }
  if (y < -0.4) return 0.4 * (-0.4 - y);
  return 0;
}

/** A map centred on (cx, cy), stamped utime [us]: a terrain_t message as lcmlog.mjs encodes it. */
export function mapAround(utime, cx, cy) {
  const { rows, cols, resolution: res } = MAP;
  // The origin on the resolution's grid, as stride-sim's maps (terrain/elevation_map.hpp).
  const origin_x = Math.round((cx - 0.5 * res * (cols - 1)) / res) * res;
  const origin_y = Math.round((cy - 0.5 * res * (rows - 1)) / res) * res;
  const height = [];
  for (let r = 0; r < rows; ++r) {
    const row = [];
    for (let c = 0; c < cols; ++c) row.push(worldHeight(origin_x + c * res, origin_y + r * res));
    height.push(row);
  }
  return { utime: BigInt(utime), origin_x, origin_y, resolution: res, rows, cols, height };
}

/** The log's bytes with maps added after the states they follow (see above). */
export function addTerrain(bytes) {
  const out = [];
  let next = null; // the stamp [us] of the next map
  let maps = 0;
  let dropped = 0;
  let horizons = 0;
  for (const e of readLog(bytes)) {
    if (e.channel === CHANNEL) {
      dropped += 1;
      continue;
    }
    if (e.channel === HORIZON_CHANNEL) {
      const h = decode(horizonType, e.data);
      h.foothold_source = h.foothold_source.map((_, i) => (i + horizons) % SOURCES);
      horizons += 1;
      out.push({ ...e, data: encode(horizonType, h) });
      continue;
    }
    out.push(e);
    if (e.channel !== 'STRIDE_STATE') continue;
    const s = decode(robotStateType, e.data);
    const utime = Number(s.utime);
    if (next === null) next = utime;
    if (utime < next) continue;
    const data = encode(terrainType, mapAround(utime, s.q[0], s.q[1]));
    out.push({ channel: CHANNEL, data, timestamp: e.timestamp });
    maps += 1;
    while (next <= utime) next += MAP.period;
  }
  return { bytes: writeLog(out), maps, dropped };
}

if (process.argv[1] === fileURLToPath(import.meta.url)) {
  const [input, output] = process.argv.slice(2);
  if (!input || !output) {
    console.error('usage: terrain_log.mjs IN OUT');
    process.exit(2);
  }
  const { bytes, maps, dropped } = addTerrain(readFileSync(input));
  writeFileSync(output, bytes);
  console.log(`terrain_log: ${maps} maps of ${MAP.rows} x ${MAP.cols} cells added ` +
              `(${dropped} of the log left out): ${output}`);
}
