// An LCM log reader and writer and a decoder (and encoder) of Stride's robot_state_t,
// robot_model_t, horizon_t and terrain_t in plain JavaScript, written for the browser tests from
// the formats alone (no LCM code, nothing of stride-viz): what the page shows is checked against
// what this reads from the log.
//
// Log file (lcm-logger): a sequence of events, each
//   uint32 sync word 0xEDA1DA01, int64 event number, int64 timestamp [µs],
//   int32 channel length, int32 data length, channel (bytes, no NUL), data,
// all big-endian. A message (data) is an 8-byte type fingerprint followed by the fields in
// declaration order, big-endian: integers, floats and doubles as they are, a string as int32
// length (with its NUL) + bytes + NUL, an array of a member's count as that many elements.
//
// The types below are messages/robot_state_t.lcm, robot_model_t.lcm, horizon_t.lcm and
// terrain_t.lcm written out as member lists; the fingerprint computed from a list (LCM's hash of member names, primitive
// type names and dimensions) must equal the one in each message, so a change of the .lcm files
// that this file does not follow fails loudly instead of decoding garbage.

const SYNC = 0xeda1da01;

/** robot_state_t (messages/robot_state_t.lcm). */
export const robotStateType = {
  name: 'robot_state_t',
  members: [
    ['utime', 'int64_t'],
    ['model_hash', 'int64_t'],
    ['session', 'int64_t'],
    ['nq', 'int32_t'],
    ['nv', 'int32_t'],
    ['q', 'double', ['nq']],
    ['v', 'double', ['nv']],
    ['ncontacts', 'int32_t'],
    ['contact', 'int8_t', ['ncontacts']],
  ],
};

/** robot_model_t (messages/robot_model_t.lcm). */
export const robotModelType = {
  name: 'robot_model_t',
  members: [
    ['robot', 'string'],
    ['model_hash', 'int64_t'],
    ['nq', 'int32_t'],
    ['nv', 'int32_t'],
    ['nu', 'int32_t'],
    ['njoints', 'int32_t'],
    ['joint_names', 'string', ['njoints']],
    ['joint_types', 'string', ['njoints']],
    ['joint_idx_q', 'int32_t', ['njoints']],
    ['joint_idx_v', 'int32_t', ['njoints']],
    ['ncontacts', 'int32_t'],
    ['contact_frames', 'string', ['ncontacts']],
  ],
};

/** horizon_t (messages/horizon_t.lcm). */
export const horizonType = {
  name: 'horizon_t',
  members: [
    ['utime', 'int64_t'],
    ['model_hash', 'int64_t'],
    ['knots', 'int32_t'],
    ['nq', 'int32_t'],
    ['ncontacts', 'int32_t'],
    ['nf', 'int32_t'],
    ['t', 'double', ['knots']],
    ['q', 'double', ['knots', 'nq']],
    ['contact_mask', 'int32_t', ['knots']],
    ['impulse', 'int8_t', ['knots']],
    ['force', 'double', ['knots', 'nf']],
    ['nfootholds', 'int32_t'],
    ['foothold_contact', 'int32_t', ['nfootholds']],
    ['foothold_time', 'double', ['nfootholds']],
    ['foothold', 'double', ['nfootholds', 3]],
    ['foothold_source', 'int8_t', ['nfootholds']],
  ],
};

/** terrain_t (messages/terrain_t.lcm): an elevation map, NaN heights unknown. */
export const terrainType = {
  name: 'terrain_t',
  members: [
    ['utime', 'int64_t'],
    ['origin_x', 'double'],
    ['origin_y', 'double'],
    ['resolution', 'double'],
    ['rows', 'int32_t'],
    ['cols', 'int32_t'],
    ['height', 'float', ['rows', 'cols']],
  ],
};

const MASK64 = (1n << 64n) - 1n;

// One step of LCM's type hash: v = ((v << 8) ^ (v >> 55)) + c on a signed 64-bit integer (the
// shift right is arithmetic), c a signed char.
function hashByte(v, c) {
  const signedV = BigInt.asIntN(64, v);
  const signedC = BigInt.asIntN(8, BigInt(c));
  return BigInt.asIntN(64, ((signedV << 8n) ^ (signedV >> 55n)) + signedC);
}

function hashString(v, s) {
  const bytes = new TextEncoder().encode(s);
  v = hashByte(v, bytes.length);
  for (const b of bytes) v = hashByte(v, b);
  return v;
}

/**
 * The fingerprint of a type of primitive members (no nested struct): the hash of every member's
 * name, type name and dimensions (mode 0 constant, 1 variable; the size as text), from the seed
 * 0x12345678, rotated left by one bit. Returned as an unsigned 64-bit BigInt.
 */
export function fingerprint(type) {
  let v = 0x12345678n;
  for (const [name, primitive, dims = []] of type.members) {
    v = hashString(v, name);
    v = hashString(v, primitive);
    v = hashByte(v, dims.length);
    for (const d of dims) {
      const variable = typeof d === 'string' && !/^[0-9]+$/.test(d);
      v = hashByte(v, variable ? 1 : 0);
      v = hashString(v, String(d));
    }
  }
  const u = BigInt.asUintN(64, v);
  return ((u << 1n) | (u >> 63n)) & MASK64;
}

/** The events of a log file (a Buffer or Uint8Array): {eventNumber, timestamp, channel, data}. */
export function readLog(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const events = [];
  let pos = 0;
  while (pos < bytes.byteLength) {
    if (bytes.byteLength - pos < 28) throw new Error(`lcmlog: truncated event header at byte ${pos}`);
    const sync = view.getUint32(pos);
    if (sync !== SYNC) {
      throw new Error(`lcmlog: bad sync word 0x${sync.toString(16)} at byte ${pos}`);
    }
    const eventNumber = view.getBigInt64(pos + 4);
    const timestamp = view.getBigInt64(pos + 12);
    const channelLength = view.getInt32(pos + 20);
    const dataLength = view.getInt32(pos + 24);
    pos += 28;
    if (channelLength < 0 || dataLength < 0 || pos + channelLength + dataLength > bytes.byteLength) {
      throw new Error(`lcmlog: truncated event ${eventNumber} at byte ${pos - 28}`);
    }
    const channel = new TextDecoder().decode(bytes.subarray(pos, pos + channelLength));
    pos += channelLength;
    const data = bytes.subarray(pos, pos + dataLength);
    pos += dataLength;
    events.push({ eventNumber, timestamp, channel, data });
  }
  return events;
}

/** Decodes one message of `type` (its fingerprint checked); int64 fields come as BigInt. */
export function decode(type, data) {
  const view = new DataView(data.buffer, data.byteOffset, data.byteLength);
  let pos = 0;
  const need = (n) => {
    if (pos + n > data.byteLength) throw new Error(`lcmlog: ${type.name} truncated at byte ${pos}`);
  };
  need(8);
  const got = view.getBigUint64(0);
  const want = fingerprint(type);
  if (got !== want) {
    throw new Error(`lcmlog: not a ${type.name}: fingerprint ${got.toString(16)}, ` +
                    `expected ${want.toString(16)} (messages/${type.name}.lcm changed?)`);
  }
  pos = 8;
  const readOne = (primitive) => {
    switch (primitive) {
      case 'int8_t': need(1); return view.getInt8(pos++);
      case 'int32_t': { need(4); const x = view.getInt32(pos); pos += 4; return x; }
      case 'int64_t': { need(8); const x = view.getBigInt64(pos); pos += 8; return x; }
      case 'float': { need(4); const x = view.getFloat32(pos); pos += 4; return x; }
      case 'double': { need(8); const x = view.getFloat64(pos); pos += 8; return x; }
      case 'string': {
        need(4);
        const n = view.getInt32(pos); // bytes with the terminating NUL
        pos += 4;
        if (n < 1) throw new Error(`lcmlog: ${type.name}: bad string length ${n}`);
        need(n);
        const s = new TextDecoder().decode(data.subarray(pos, pos + n - 1));
        pos += n;
        return s;
      }
      default: throw new Error(`lcmlog: type ${primitive} not supported`);
    }
  };
  const out = {};
  for (const [name, primitive, dims = []] of type.members) {
    const read = (level) => {
      if (level === dims.length) return readOne(primitive);
      const d = dims[level];
      const n = typeof d === 'number' ? d : Number(out[d]);
      if (!(n >= 0)) throw new Error(`lcmlog: ${type.name}.${name}: bad count ${n}`);
      const arr = new Array(n);
      for (let i = 0; i < n; ++i) arr[i] = read(level + 1);
      return arr;
    };
    out[name] = read(0);
  }
  if (pos !== data.byteLength) {
    throw new Error(`lcmlog: ${type.name}: ${data.byteLength - pos} bytes left after the last field`);
  }
  return out;
}

/**
 * Encodes `message` (an object with every member of `type`; arrays sized by their count members,
 * int64 as BigInt or Number) into the bytes of an LCM message, fingerprint first. Numbers and
 * strings only, as decode() reads them.
 */
export function encode(type, message) {
  const parts = [];
  const put = (n, write) => {
    const b = Buffer.alloc(n);
    write(b);
    parts.push(b);
  };
  put(8, (b) => b.writeBigUInt64BE(fingerprint(type)));
  const writeOne = (primitive, x, name) => {
    switch (primitive) {
      case 'int8_t': put(1, (b) => b.writeInt8(x)); break;
      case 'int32_t': put(4, (b) => b.writeInt32BE(x)); break;
      case 'int64_t': put(8, (b) => b.writeBigInt64BE(BigInt(x))); break;
      case 'float': put(4, (b) => b.writeFloatBE(x)); break;
      case 'double': put(8, (b) => b.writeDoubleBE(x)); break;
      case 'string': {
        const s = Buffer.from(x, 'utf8');
        put(4, (b) => b.writeInt32BE(s.length + 1));
        parts.push(s, Buffer.from([0]));
        break;
      }
      default: throw new Error(`lcmlog: ${type.name}.${name}: type ${primitive} not supported`);
    }
  };
  for (const [name, primitive, dims = []] of type.members) {
    const write = (x, level) => {
      if (level === dims.length) {
        writeOne(primitive, x, name);
        return;
      }
      const d = dims[level];
      const n = typeof d === 'number' ? d : Number(message[d]);
      if (!Array.isArray(x) || x.length !== n) {
        throw new Error(`lcmlog: ${type.name}.${name}: ${Array.isArray(x) ? x.length : 'no array'} elements, its count says ${n}`);
      }
      for (const y of x) write(y, level + 1);
    };
    write(message[name], 0);
  }
  return Buffer.concat(parts);
}

/**
 * The bytes of a log file holding `events` ({channel, data, timestamp}) in that order, numbered
 * from 0 (lcm-logger's event numbers).
 */
export function writeLog(events) {
  const parts = [];
  events.forEach((e, i) => {
    const channel = Buffer.from(e.channel, 'utf8');
    const head = Buffer.alloc(28);
    head.writeUInt32BE(SYNC, 0);
    head.writeBigInt64BE(BigInt(i), 4);
    head.writeBigInt64BE(BigInt(e.timestamp), 12);
    head.writeInt32BE(channel.length, 20);
    head.writeInt32BE(e.data.length, 24);
    parts.push(head, channel, Buffer.from(e.data.buffer, e.data.byteOffset, e.data.byteLength));
  });
  return Buffer.concat(parts);
}

/** A model hash as the 16 hex digits Stride prints (stride-mpc --print-model). */
export function hashHex(h) {
  return BigInt.asUintN(64, h).toString(16).padStart(16, '0');
}

/**
 * The robot states of a log on `channel`, in log order, each with t = utime * 1e-6 [s] (the
 * robot's clock, as stride-viz's frames), the first robot model on `modelChannel` (null when the
 * log has none), the horizons on `horizonChannel` and the elevation maps on `terrainChannel` (t
 * likewise).
 */
export function readSession(bytes, {
  channel = 'STRIDE_STATE', modelChannel = 'STRIDE_MODEL', horizonChannel = 'STRIDE_HORIZON',
  terrainChannel = 'STRIDE_TERRAIN',
} = {}) {
  const states = [];
  const horizons = [];
  const terrains = [];
  let model = null;
  for (const e of readLog(bytes)) {
    if (e.channel === channel) {
      const s = decode(robotStateType, e.data);
      s.t = Number(s.utime) * 1e-6;
      states.push(s);
    } else if (e.channel === horizonChannel) {
      const h = decode(horizonType, e.data);
      h.t0 = Number(h.utime) * 1e-6; // h.t is the knots' times after it
      horizons.push(h);
    } else if (e.channel === terrainChannel) {
      const m = decode(terrainType, e.data);
      m.t = Number(m.utime) * 1e-6;
      terrains.push(m);
    } else if (e.channel === modelChannel && model === null) {
      model = decode(robotModelType, e.data);
    }
  }
  return { states, model, horizons, terrains };
}

/**
 * The state shown at time t: the newest state whose stamp is at or before t (the first state
 * when t is before every stamp). `states` sorted by t (a log's order; checked by the caller).
 */
export function stateAt(states, t) {
  let lo = 0;
  let hi = states.length - 1;
  if (hi < 0) return null;
  if (t < states[0].t) return states[0];
  while (lo < hi) { // invariant: states[lo].t <= t
    const mid = (lo + hi + 1) >> 1;
    if (states[mid].t <= t) lo = mid; else hi = mid - 1;
  }
  return states[lo];
}
