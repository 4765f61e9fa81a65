// The protocol of docs/protocol.md: a reader and writer of postcard as it lays it out, the
// snapshot decoder, and the WebSocket frames' tags. No DOM: a test or another page may import
// it alone. Decoded messages have the shape serde gives the Rust types in JSON (externally
// tagged enums).

const VERSION = 1;
const SNAPSHOT_VERSION = 2;  // …/poses: quantized, delta-coded against the latest keyframe
const ANGLE_STEPS = 65536;
const ORIENTATIONS = ['Portrait', 'PortraitUpsideDown', 'LandscapeLeft', 'LandscapeRight',
  'FaceUp', 'FaceDown'];
const utf8 = new TextDecoder('utf-8', { fatal: true });
const utf8enc = new TextEncoder();

class DecodeError extends Error {}

// A body id as a map key: `3v0`.
const idKey = id => id.index + 'v' + id.generation;

class Reader {
  constructor(bytes) {
    this.b = bytes;
    this.dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    this.i = 0;
  }
  need(n) {
    if (this.i + n > this.b.length) throw new DecodeError('truncated: the payload ended in the middle of a field');
  }
  u8() { this.need(1); return this.b[this.i++]; }
  varint(maxBytes) {
    let v = 0, mul = 1;
    for (let k = 0; k < maxBytes; k++) {
      const byte = this.u8();
      v += (byte & 0x7f) * mul;
      if ((byte & 0x80) === 0) {
        if (maxBytes === 5 && v > 0xffffffff) throw new DecodeError('a varint is longer than its type allows');
        return v;
      }
      mul *= 128;
    }
    throw new DecodeError('a varint is longer than its type allows');
  }
  u32() { return this.varint(5); }
  // zigzag: n >= 0 as 2n, n < 0 as -2n - 1 (exact within +-2^53)
  signed() { const v = this.varint(10); return v % 2 === 0 ? v / 2 : -(v + 1) / 2; }
  u16le() { this.need(2); const v = this.dv.getUint16(this.i, true); this.i += 2; return v; }
  u64() { return this.varint(10); }
  bool() {
    const b = this.u8();
    if (b > 1) throw new DecodeError('a bool byte is neither 0 nor 1');
    return b === 1;
  }
  f32() { this.need(4); const v = this.dv.getFloat32(this.i, true); this.i += 4; return v; }
  f64() { this.need(8); const v = this.dv.getFloat64(this.i, true); this.i += 8; return v; }
  string() {
    const n = this.u32();
    this.need(n);
    let s;
    try { s = utf8.decode(this.b.subarray(this.i, this.i + n)); } catch (e) {
      throw new DecodeError('a string is not valid UTF-8');
    }
    this.i += n;
    return s;
  }
  option(f) {
    const t = this.u8();
    if (t > 1) throw new DecodeError('an option tag is neither 0 nor 1');
    return t === 1 ? f(this) : null;
  }
  seq(f) {
    const n = this.u32();
    if (n > this.b.length - this.i) throw new DecodeError('truncated: a sequence is longer than the payload');
    const out = new Array(n);
    for (let k = 0; k < n; k++) out[k] = f(this);
    return out;
  }
  variant(count, name) {
    const v = this.u32();
    if (v >= count) throw new DecodeError('unknown variant in ' + name);
    return v;
  }
}

const vector = r => ({ x: r.f32(), y: r.f32() });
const bodyRef = r => ({ index: r.u32(), generation: r.u32() });
const colour = r => ({ r: r.u8(), g: r.u8(), b: r.u8() });
function shapeSpec(r, inCompound) {
  switch (r.variant(6, 'ShapeSpec')) {
    case 0: return { Rect: { width: r.f32(), height: r.f32() } };
    case 1: return { Circle: { radius: r.f32() } };
    case 2: return { Capsule: { length: r.f32(), radius: r.f32() } };
    case 3: return { Polygon: { vertices: r.seq(vector) } };
    case 4: return { Segment: {
      a: vector(r), b: vector(r), radius: r.f32(), prev: r.option(vector), next: r.option(vector),
      one_sided: r.bool(),
    } };
    default:
      if (inCompound) throw new DecodeError("a compound's part is itself a compound");
      return { Compound: { parts: r.seq(partShape) } };
  }
}
// One shape of a body of several, placed in the body's frame.
const partShape = r => ({ shape: shapeSpec(r, true), offset: vector(r), angle: r.f32() });
// Joints (docs/protocol.md, "Build"): their ends, kinds and descriptions.
const optF32 = r => r.option(q => q.f32());
const limitSpec = r => ({ lower: r.f32(), upper: r.f32() });
const motorSpec = r => ({ speed: r.f32(), max: r.f32() });
const springSpec = r => ({ hertz: r.f32(), damping_ratio: r.f32() });
function jointEnd(r) {
  switch (r.variant(3, 'JointEnd')) {
    case 0: return 'World';
    case 1: return { New: r.u32() };
    default: return { Live: bodyRef(r) };
  }
}
function jointKind(r) {
  switch (r.variant(6, 'JointKindSpec')) {
    case 0: return { Revolute: { reference_angle: optF32(r), limit: r.option(limitSpec),
      motor: r.option(motorSpec), spring: r.option(springSpec) } };
    case 1: return { Prismatic: { axis: vector(r), reference_angle: optF32(r),
      limit: r.option(limitSpec), motor: r.option(motorSpec), spring: r.option(springSpec) } };
    case 2: return { Distance: { length: optF32(r), spring: r.option(springSpec),
      limit: r.option(limitSpec) } };
    case 3: return { Weld: { reference_angle: optF32(r), linear_hertz: r.f32(),
      linear_damping_ratio: r.f32(), angular_hertz: r.f32(), angular_damping_ratio: r.f32() } };
    case 4: return { Wheel: { axis: vector(r), spring: r.option(springSpec),
      limit: r.option(limitSpec), motor: r.option(motorSpec) } };
    default: return { Motor: { angular_offset: r.f32(), max_force: r.f32(), max_torque: r.f32(),
      correction_factor: r.f32() } };
  }
}
const jointSpec = r => ({
  a: jointEnd(r), b: jointEnd(r), anchor_a: vector(r), anchor_b: vector(r), kind: jointKind(r),
  collide_connected: r.bool(), break_force: optF32(r), break_torque: optF32(r),
});
const jointInfo = r => ({ id: bodyRef(r), joint: jointSpec(r) });
const brokenJoint = r => ({ id: bodyRef(r), force: r.f32(), torque: r.f32() });
// An id in a list sorted by slot: 2 (index - next) + (generation != 0), then the generation.
function listId(r, at) {
  const head = r.varint(6);
  const generation = head % 2 === 1 ? r.u32() : 0;
  const index = at.next + Math.floor(head / 2);
  if (index > 0xffffffff) throw new DecodeError('a body index beyond u32');
  at.next = index + 1;
  return { index, generation };
}
// A snapshot as the wire carries it (docs/protocol.md, "Snapshot", encoding version 2).
function snapshotFrame(r) {
  const frame = r.u64(), time = r.f64(), gravity = vector(r), reference = r.u64(), grid = r.u8();
  if (grid > 24) throw new DecodeError('the grid is finer than 2^-24 m');
  const key = reference === 0;
  const n = r.u32();
  if (n * (key ? 5 : 4) > r.b.length - r.i) throw new DecodeError('truncated: a sequence is longer than the payload');
  const poses = [], at = { next: 0 };
  let px = 0, py = 0;
  for (let k = 0; k < n; k++) {
    const id = listId(r, at), dx = r.signed(), dy = r.signed();
    if (key) { px += dx; py += dy; poses.push({ id, x: px, y: py, angle: r.u16le() }); }
    else poses.push({ id, x: dx, y: dy, angle: r.signed() });
  }
  const gone = [];
  if (!key) {
    const m = r.u32();
    if (m > r.b.length - r.i) throw new DecodeError('truncated: a sequence is longer than the payload');
    const g = { next: 0 };
    for (let k = 0; k < m; k++) gone.push(listId(r, g));
  }
  return { frame, time, gravity, reference, grid, poses, gone };
}
const shapeHit = r => ({ id: bodyRef(r), shape: r.u32() });
const shapePair = r => ({ a: shapeHit(r), b: shapeHit(r) });
const hitInfo = r => ({ pair: shapePair(r), point: vector(r), normal: vector(r), approach_speed: r.f32() });
const bodyInfo = r => ({
  id: bodyRef(r), name: r.string(), shape: shapeSpec(r), is_static: r.bool(),
  colour: colour(r), position: vector(r), angle: r.f32(), velocity: vector(r),
  angular_velocity: r.f32(), mass: r.f32(), friction: r.f32(), restitution: r.f32(),
});
const spawnBody = r => ({
  name: r.option(q => q.string()), shape: shapeSpec(r), position: vector(r), angle: r.f32(),
  velocity: vector(r), angular_velocity: r.f32(), density: r.f32(), friction: r.f32(),
  restitution: r.f32(), colour: colour(r),
});

const MESSAGES = {
  Snapshot: snapshotFrame,
  Event: r => {
    const frame = r.u64();
    let kind;
    switch (r.variant(10, 'EventKind')) {
      case 0: kind = { Added: { bodies: r.seq(bodyInfo) } }; break;
      case 1: kind = { Removed: { ids: r.seq(bodyRef) } }; break;
      case 2: kind = { Reset: { scene: r.string(), gravity: vector(r), bodies: r.seq(bodyInfo) } }; break;
      case 3: kind = { Rejected: { key: r.string(), reason: r.string() } }; break;
      case 4: kind = { Contacts: { begin: r.seq(shapePair), end: r.seq(shapePair), dropped: r.u32() } }; break;
      case 5: kind = { Hits: { hits: r.seq(hitInfo), dropped: r.u32() } }; break;
      case 6: kind = { Sensors: { begin: r.seq(shapePair), end: r.seq(shapePair), dropped: r.u32() } }; break;
      case 7: kind = { Built: { bodies: r.seq(bodyInfo), joints: r.seq(jointInfo) } }; break;
      case 8: kind = { JointsRemoved: { ids: r.seq(bodyRef) } }; break;
      default: kind = { JointsBroken: { joints: r.seq(brokenJoint) } };
    }
    return { frame, kind };
  },
  Stats: r => ({
    frame: r.u64(), bodies: r.u32(), awake: r.u32(), contacts: r.u32(), step_us_median: r.u32(),
    step_us_max: r.u32(), lateness_us_max: r.u32(), commands_applied: r.u64(),
    commands_rejected: r.u64(), steps_dropped: r.u64(), commands_received: r.u64(),
    commands_dropped: r.u64(),
  }),
  SceneState: r => ({ world: r.string(), scene: r.string(), frame: r.u64(), time: r.f64(), gravity: vector(r), bodies: r.seq(bodyInfo) }),
  SceneWithJoints: r => ({ scene: MESSAGES.SceneState(r), joints: r.seq(jointInfo) }),
  RemoveJoints: r => ({ ids: r.seq(bodyRef) }),
  SetGravity: r => ({ x: r.f32(), y: r.f32() }),
  Tilt: r => (r.variant(2, 'Tilt') === 0
    ? { Orientation: ORIENTATIONS[r.variant(6, 'Tilt')] }
    : { Accelerometer: { x: r.f32(), y: r.f32(), z: r.f32() } }),
  Spawn: r => ({ bodies: r.seq(spawnBody) }),
  Remove: r => ({ ids: r.seq(bodyRef) }),
  Reset: () => null,
  Drag: r => {
    const v = r.variant(3, 'Drag'), hand = r.u64();
    if (v === 0) return { Grab: { hand, id: bodyRef(r), point: vector(r) } };
    if (v === 1) return { Move: { hand, target: vector(r) } };
    return { Release: { hand } };
  },
};

// The WebSocket frame tags (docs/protocol.md, "WebSocket gateway").
const TAGS = { 1: ['poses', 'Snapshot'], 2: ['events', 'Event'], 3: ['stats', 'Stats'],
  4: ['scene', 'SceneState'], 5: ['gravity', 'SetGravity'], 6: ['tilt', 'Tilt'],
  7: ['spawn', 'Spawn'], 8: ['remove', 'Remove'], 9: ['reset', 'Reset'], 11: ['drag', 'Drag'],
  13: ['remove_joints', 'RemoveJoints'], 14: ['scene', 'SceneWithJoints'] };
const TAG_OF = {};
for (const t in TAGS) TAG_OF[TAGS[t][1]] = +t;

// A payload: the version byte, the message, nothing after it.
function decodeMessage(type, bytes) {
  const f = MESSAGES[type];
  if (!f) throw new DecodeError('no message ' + type);
  if (bytes.length === 0) throw new DecodeError('empty payload');
  const version = type === 'Snapshot' ? SNAPSHOT_VERSION : VERSION;
  if (bytes[0] !== version) throw new DecodeError('unsupported protocol version ' + bytes[0] + ' (this page reads ' + version + ')');
  const r = new Reader(bytes.subarray(1));
  const m = f(r);
  if (r.i !== r.b.length) throw new DecodeError((r.b.length - r.i) + ' unexpected byte(s) after the end of a ' + type);
  return m;
}

// A WebSocket frame: a tag byte, then a payload.
function decodeFrame(bytes) {
  if (bytes.length === 0) throw new DecodeError('empty frame');
  const t = TAGS[bytes[0]];
  if (!t) throw new DecodeError('unknown tag ' + bytes[0]);
  return { tag: bytes[0], key: t[0], type: t[1], message: decodeMessage(t[1], bytes.subarray(1)) };
}

class Writer {
  constructor() { this.b = []; }
  u8(v) { this.b.push(v & 0xff); }
  u32(v) { do { let byte = v % 128; v = Math.floor(v / 128); if (v > 0) byte |= 0x80; this.b.push(byte); } while (v > 0); }
  f32(v) { const a = new Uint8Array(4); new DataView(a.buffer).setFloat32(0, v, true); this.b.push(...a); }
  string(s) { const u = utf8enc.encode(s); this.u32(u.length); this.b.push(...u); }
  vector(v) { this.f32(v.x); this.f32(v.y); }
  bytes() { return new Uint8Array(this.b); }
}

function writeShape(w, s) {
  if (s.Rect) { w.u32(0); w.f32(s.Rect.width); w.f32(s.Rect.height); }
  else if (s.Circle) { w.u32(1); w.f32(s.Circle.radius); }
  else if (s.Capsule) { w.u32(2); w.f32(s.Capsule.length); w.f32(s.Capsule.radius); }
  else { w.u32(3); w.u32(s.Polygon.vertices.length); s.Polygon.vertices.forEach(v => w.vector(v)); }
}

// Encode a command (the messages a page sends) as a payload: version byte + postcard.
function encodeMessage(type, m) {
  const w = new Writer();
  w.u8(VERSION);
  switch (type) {
    case 'SetGravity': w.vector(m); break;
    case 'Tilt':
      if (m.Orientation !== undefined) { w.u32(0); w.u32(ORIENTATIONS.indexOf(m.Orientation)); }
      else { w.u32(1); w.f32(m.Accelerometer.x); w.f32(m.Accelerometer.y); w.f32(m.Accelerometer.z); }
      break;
    case 'Spawn':
      w.u32(m.bodies.length);
      for (const b of m.bodies) {
        if (b.name === null || b.name === undefined) w.u8(0); else { w.u8(1); w.string(b.name); }
        writeShape(w, b.shape); w.vector(b.position); w.f32(b.angle); w.vector(b.velocity);
        w.f32(b.angular_velocity); w.f32(b.density); w.f32(b.friction); w.f32(b.restitution);
        w.u8(b.colour.r); w.u8(b.colour.g); w.u8(b.colour.b);
      }
      break;
    case 'Remove': w.u32(m.ids.length); m.ids.forEach(id => { w.u32(id.index); w.u32(id.generation); }); break;
    case 'Reset': break;
    case 'RemoveJoints': w.u32(m.ids.length); m.ids.forEach(id => { w.u32(id.index); w.u32(id.generation); }); break;
    case 'Drag':
      if (m.Grab) { w.u32(0); w.u32(m.Grab.hand); w.u32(m.Grab.id.index); w.u32(m.Grab.id.generation); w.vector(m.Grab.point); }
      else if (m.Move) { w.u32(1); w.u32(m.Move.hand); w.vector(m.Move.target); }
      else { w.u32(2); w.u32(m.Release.hand); }
      break;
    default: throw new Error('not a command: ' + type);
  }
  return w.bytes();
}

function encodeFrame(type, m) {
  const p = encodeMessage(type, m);
  const f = new Uint8Array(p.length + 1);
  f[0] = TAG_OF[type];
  f.set(p, 1);
  return f;
}

// The snapshot decoder: keeps the latest keyframe and the poses last given out. A delta is
// applied only against the keyframe it names (lost keyframe: skipped until the next one), so
// a lost sample never leaves a wrong pose. Gives out {frame, time, gravity, keyframe, poses}
// with poses in metres and radians: every dynamic body for a keyframe, the changed ones for a
// delta.
class SnapshotDecoder {
  constructor() { this.skipped = 0; this.reset(); }
  reset() { this.key = null; this.changed = new Map(); this.last = 0; }
  apply(f) {
    const step = Math.pow(2, -f.grid), out = [];
    const pose = (id, q) => {
      const a = q[2] >= ANGLE_STEPS / 2 ? q[2] - ANGLE_STEPS : q[2];
      return { id, x: Math.fround(q[0] * step), y: Math.fround(q[1] * step), angle: Math.fround(a * (2 * Math.PI / ANGLE_STEPS)) };
    };
    if (f.reference === 0) {
      const poses = new Map();
      for (const p of f.poses) { const q = [p.x, p.y, p.angle]; poses.set(idKey(p.id), q); out.push(pose(p.id, q)); }
      this.key = { frame: f.frame, grid: f.grid, poses };
      this.changed = new Map();
    } else {
      const k = this.key;
      if (!k || k.frame !== f.frame - f.reference || k.grid !== f.grid || f.frame <= this.last) { this.skipped++; return null; }
      const now = new Map();
      for (const p of f.poses) {
        const key = idKey(p.id), kq = k.poses.get(key), base = kq || [0, 0, 0];
        const q = [base[0] + p.x, base[1] + p.y, (((base[2] + p.angle) % ANGLE_STEPS) + ANGLE_STEPS) % ANGLE_STEPS];
        now.set(key, { id: p.id, q });
        const was = this.changed.has(key) ? this.changed.get(key).q : kq;
        if (!was || was[0] !== q[0] || was[1] !== q[1] || was[2] !== q[2]) out.push(pose(p.id, q));
      }
      const gone = new Set(f.gone.map(idKey));
      for (const [key, c] of this.changed) {
        if (!now.has(key) && !gone.has(key) && k.poses.has(key)) out.push(pose(c.id, k.poses.get(key)));
      }
      this.changed = now;
    }
    this.last = f.frame;
    return { frame: f.frame, time: f.time, gravity: f.gravity, keyframe: f.reference === 0, poses: out };
  }
}

export {
  VERSION, SNAPSHOT_VERSION, ANGLE_STEPS, ORIENTATIONS, DecodeError, TAGS, TAG_OF, idKey,
  decodeMessage, decodeFrame, encodeMessage, encodeFrame, SnapshotDecoder,
};
