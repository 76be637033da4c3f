// test/lcmlog.mjs on its own (node --test): the fingerprints of its member lists against the ones
// lcm-gen computed from messages/*.lcm (the generated C++ headers of the build, directory in
// STRIDE_LCM_GEN_DIR), a log written here byte by byte read back, the "state shown at t" rule,
// and the errors a damaged log or another type gives.

import assert from 'node:assert/strict';
import { existsSync, readFileSync } from 'node:fs';
import path from 'node:path';
import test from 'node:test';
import {
  decode, encode, fingerprint, hashHex, horizonType, readLog, readSession, robotModelType,
  robotStateType, stateAt, terrainType, writeLog,
} from './lcmlog.mjs';

const genDir = process.env.STRIDE_LCM_GEN_DIR;

test('fingerprints equal lcm-gen\'s', { skip: genDir ? false : 'STRIDE_LCM_GEN_DIR not set' }, () => {
  for (const type of [robotStateType, robotModelType, horizonType, terrainType]) {
    const header = path.join(genDir, 'stride', `${type.name}.hpp`);
    assert.ok(existsSync(header), `${header} (build the messages first)`);
    // lcm-gen writes the hash before its final rotation: `uint64_t hash = 0x...LL;`
    const m = readFileSync(header, 'utf8').match(/uint64_t hash = 0x([0-9a-f]+)LL;/);
    assert.ok(m, `no hash in ${header}`);
    const base = BigInt(`0x${m[1]}`);
    const rotated = ((base << 1n) | (base >> 63n)) & ((1n << 64n) - 1n);
    assert.equal(fingerprint(type).toString(16), rotated.toString(16), type.name);
  }
});

// ---- a log written here, the way the format describes it ----

class Writer {
  constructor() {
    this.parts = [];
  }
  bytes(n, fill) {
    const b = Buffer.alloc(n);
    fill(b);
    this.parts.push(b);
  }
  i8(x) { this.bytes(1, (b) => b.writeInt8(x)); }
  i32(x) { this.bytes(4, (b) => b.writeInt32BE(x)); }
  i64(x) { this.bytes(8, (b) => b.writeBigInt64BE(BigInt(x))); }
  u64(x) { this.bytes(8, (b) => b.writeBigUInt64BE(x)); }
  f64(x) { this.bytes(8, (b) => b.writeDoubleBE(x)); }
  str(s) {
    const b = Buffer.from(s, 'utf8');
    this.i32(b.length + 1);
    this.parts.push(b, Buffer.from([0]));
  }
  done() { return Buffer.concat(this.parts); }
}

function stateMessage({ utime, hash, q, v, contact }) {
  const w = new Writer();
  w.u64(fingerprint(robotStateType));
  w.i64(utime);
  w.i64(hash);
  w.i64(0x5e5510n);  // session
  w.i32(q.length);
  w.i32(v.length);
  q.forEach((x) => w.f64(x));
  v.forEach((x) => w.f64(x));
  w.i32(contact.length);
  contact.forEach((x) => w.i8(x));
  return w.done();
}

function modelMessage() {
  const w = new Writer();
  w.u64(fingerprint(robotModelType));
  w.str('two_link');
  w.i64(-5n); // a hash with the top bit set
  w.i32(9); w.i32(8); w.i32(2);
  w.i32(3);
  ['root_joint', 'hip', 'knee'].forEach((s) => w.str(s));
  ['free-flyer', 'revolute', 'prismatic'].forEach((s) => w.str(s));
  [0, 7, 8].forEach((x) => w.i32(x));
  [0, 6, 7].forEach((x) => w.i32(x));
  w.i32(1);
  w.str('foot');
  return w.done();
}

// Two knots of the two_link robot (nq 9, one contact): arrays of arrays, row by row; two chosen
// footholds (a fixed inner dimension: no count on the wire).
function horizonMessage(utime) {
  const w = new Writer();
  w.u64(fingerprint(horizonType));
  w.i64(utime);
  w.i64(-5n);
  w.i32(2); w.i32(9); w.i32(1); w.i32(3);
  [0, 0.02].forEach((x) => w.f64(x));
  [q(0), q(1)].forEach((row) => row.forEach((x) => w.f64(x)));
  [1, 0].forEach((x) => w.i32(x));
  [0, 1].forEach((x) => w.i8(x));
  [[1, 2, 30], [0, 0, 0.5]].forEach((row) => row.forEach((x) => w.f64(x)));
  w.i32(2);
  [0, 0].forEach((x) => w.i32(x));
  [0.25, 0.75].forEach((x) => w.f64(x));
  [[0.5, 0.125, 0], [0.75, 0.125, 0.05]].forEach((row) => row.forEach((x) => w.f64(x)));
  [1, 3].forEach((x) => w.i8(x));
  return w.done();
}

function event(number, timestamp, channel, data) {
  const w = new Writer();
  w.bytes(4, (b) => b.writeUInt32BE(0xeda1da01));
  w.i64(number);
  w.i64(timestamp);
  const ch = Buffer.from(channel);
  w.i32(ch.length);
  w.i32(data.length);
  w.parts.push(ch, data);
  return w.done();
}

const q = (x) => [x, 0, 0.3, 0, 0, 0, 1, 0.1 * x, -0.2 * x];
const states = [1000000, 1005000, 1010000].map((utime, i) => ({
  utime, hash: -5n, q: q(i), v: new Array(8).fill(0.5), contact: [i % 2],
}));
const log = Buffer.concat([
  event(0, 1000000, 'STRIDE_MODEL', modelMessage()),
  ...states.map((s, i) => event(i + 1, s.utime, 'STRIDE_STATE', stateMessage(s))),
  event(9, 1010000, 'OTHER', Buffer.from([1, 2, 3])),
  event(10, 1010000, 'STRIDE_HORIZON', horizonMessage(1010000)),
]);

test('a log written here reads back', () => {
  const events = readLog(log);
  assert.deepEqual(events.map((e) => e.channel), ['STRIDE_MODEL', 'STRIDE_STATE', 'STRIDE_STATE', 'STRIDE_STATE', 'OTHER', 'STRIDE_HORIZON']);
  assert.equal(events[4].eventNumber, 9n);
  assert.equal(events[4].timestamp, 1010000n);
  const { states: got, model } = readSession(log);
  assert.equal(model.robot, 'two_link');
  assert.equal(hashHex(model.model_hash), 'fffffffffffffffb');
  assert.deepEqual(model.joint_names, ['root_joint', 'hip', 'knee']);
  assert.deepEqual(model.joint_types, ['free-flyer', 'revolute', 'prismatic']);
  assert.deepEqual(model.joint_idx_q, [0, 7, 8]);
  assert.deepEqual(model.contact_frames, ['foot']);
  assert.equal(got.length, 3);
  got.forEach((s, i) => {
    assert.equal(s.t, states[i].utime * 1e-6);
    assert.deepEqual(s.q, q(i));
    assert.deepEqual(s.contact, [i % 2]);
    assert.equal(s.nv, 8);
  });
});

test('a horizon reads back, its arrays of arrays row by row', () => {
  const { horizons } = readSession(log);
  assert.equal(horizons.length, 1);
  const h = horizons[0];
  assert.equal(h.t0, 1.01);
  assert.equal(h.knots, 2);
  assert.deepEqual(h.t, [0, 0.02]);
  assert.deepEqual(h.q, [q(0), q(1)]);
  assert.deepEqual(h.contact_mask, [1, 0]);
  assert.deepEqual(h.impulse, [0, 1]);
  assert.deepEqual(h.force, [[1, 2, 30], [0, 0, 0.5]]);
  assert.equal(h.nfootholds, 2);
  assert.deepEqual(h.foothold_contact, [0, 0]);
  assert.deepEqual(h.foothold_time, [0.25, 0.75]);
  assert.deepEqual(h.foothold, [[0.5, 0.125, 0], [0.75, 0.125, 0.05]]);
  assert.deepEqual(h.foothold_source, [1, 3]);
});

// A 2 x 3 map, one cell unknown, written by encode() and checked byte by byte where the format
// fixes the bytes (counts, a float's bits).
const terrain = {
  utime: 1005000n, origin_x: -0.5, origin_y: 0.25, resolution: 0.02, rows: 2, cols: 3,
  height: [[0, 0.05, NaN], [0.25, -1.5, 0]],
};

test('a terrain_t encodes as the format says and reads back, NaN cells too', () => {
  const bytes = encode(terrainType, terrain);
  assert.equal(bytes.length, 8 + 8 + 3 * 8 + 2 * 4 + 6 * 4);
  assert.equal(bytes.readBigUInt64BE(0), fingerprint(terrainType));
  assert.equal(bytes.readInt32BE(40), 2);
  assert.equal(bytes.readInt32BE(44), 3);
  assert.equal(bytes.readFloatBE(48 + 4), Math.fround(0.05));
  const m = decode(terrainType, bytes);
  assert.equal(m.utime, 1005000n);
  assert.equal(m.rows, 2);
  assert.deepEqual(m.height[1], [0.25, -1.5, 0]);
  assert.equal(m.height[0][1], Math.fround(0.05));
  assert.ok(Number.isNaN(m.height[0][2]));
  assert.throws(() => encode(terrainType, { ...terrain, rows: 3 }), /count says 3/);
});

test('writeLog writes what readLog reads, terrain maps in the session', () => {
  const written = writeLog([
    ...readLog(log).map((e) => ({ channel: e.channel, data: e.data, timestamp: e.timestamp })),
    { channel: 'STRIDE_TERRAIN', data: encode(terrainType, terrain), timestamp: 1010000 },
  ]);
  const events = readLog(written);
  assert.equal(events.length, 7);
  assert.deepEqual(events.map((e) => e.eventNumber), [0n, 1n, 2n, 3n, 4n, 5n, 6n]);
  assert.equal(events[6].timestamp, 1010000n);
  assert.deepEqual(Buffer.from(events[1].data), Buffer.from(readLog(log)[1].data));
  const { terrains, states: s } = readSession(written);
  assert.equal(s.length, 3);
  assert.equal(terrains.length, 1);
  assert.equal(terrains[0].t, 1.005);
  assert.equal(terrains[0].cols, 3);
});

test('the state shown at t: the newest at or before t, the first before them all', () => {
  const { states: s } = readSession(log);
  assert.equal(stateAt(s, 0), s[0]);
  assert.equal(stateAt(s, 1.0), s[0]);
  assert.equal(stateAt(s, 1.0049), s[0]);
  assert.equal(stateAt(s, 1.005), s[1]);
  assert.equal(stateAt(s, 1.0099), s[1]);
  assert.equal(stateAt(s, 5), s[2]);
  assert.equal(stateAt([], 1), null);
});

test('a damaged log or another type is an error, not garbage', () => {
  assert.throws(() => readLog(log.subarray(0, log.length - 1)), /truncated/);
  const bad = Buffer.from(log);
  bad.writeUInt32BE(0x12345678, 0);
  assert.throws(() => readLog(bad), /bad sync word/);
  const model = readLog(log)[0].data;
  assert.throws(() => decode(robotStateType, model), /not a robot_state_t/);
  const longer = Buffer.concat([stateMessage(states[0]), Buffer.from([0])]);
  assert.throws(() => decode(robotStateType, longer), /left after the last field/);
});
