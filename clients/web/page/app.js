// tiltbox-web's page: decodes the documented protocol (docs/protocol.md) from the gateway's
// WebSocket, rebuilds the world the way a late joiner does, draws it at the display's frame
// rate between buffered snapshots, and sends tilts, spawns and resets back.
'use strict';
(function () {

// ---------------------------------------------------------------------------------------
// The protocol: a reader and writer of postcard as docs/protocol.md lays it out. Decoded
// messages have the shape serde gives the Rust types in JSON (externally tagged enums).

const VERSION = 1;
const SNAPSHOT_VERSION = 2;  // …/poses: quantized, delta-coded against the latest keyframe
const ANGLE_STEPS = 65536;
const ORIENTATIONS = ['Portrait', 'PortraitUpsideDown', 'LandscapeLeft', 'LandscapeRight',
  'FaceUp', 'FaceDown'];
const utf8 = new TextDecoder('utf-8', { fatal: true });
const utf8enc = new TextEncoder();

class DecodeError extends Error {}

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
function shapeSpec(r) {
  switch (r.variant(5, 'ShapeSpec')) {
    case 0: return { Rect: { width: r.f32(), height: r.f32() } };
    case 1: return { Circle: { radius: r.f32() } };
    case 2: return { Capsule: { length: r.f32(), radius: r.f32() } };
    case 3: return { Polygon: { vertices: r.seq(vector) } };
    default: return { Segment: {
      a: vector(r), b: vector(r), radius: r.f32(), prev: r.option(vector), next: r.option(vector),
      one_sided: r.bool(),
    } };
  }
}
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
    switch (r.variant(7, 'EventKind')) {
      case 0: kind = { Added: { bodies: r.seq(bodyInfo) } }; break;
      case 1: kind = { Removed: { ids: r.seq(bodyRef) } }; break;
      case 2: kind = { Reset: { scene: r.string(), gravity: vector(r), bodies: r.seq(bodyInfo) } }; break;
      case 3: kind = { Rejected: { key: r.string(), reason: r.string() } }; break;
      case 4: kind = { Contacts: { begin: r.seq(shapePair), end: r.seq(shapePair), dropped: r.u32() } }; break;
      case 5: kind = { Hits: { hits: r.seq(hitInfo), dropped: r.u32() } }; break;
      default: kind = { Sensors: { begin: r.seq(shapePair), end: r.seq(shapePair), dropped: r.u32() } };
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
  7: ['spawn', 'Spawn'], 8: ['remove', 'Remove'], 9: ['reset', 'Reset'], 11: ['drag', 'Drag'] };
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
const snapshots = new SnapshotDecoder();

// ---------------------------------------------------------------------------------------
// The world as the page knows it: the scene reply, then snapshots and events (the late join
// of docs/protocol.md), and a short history of full pose sets for interpolation.

const idKey = id => id.index + 'v' + id.generation;

const state = {
  world: '', scene: '', joined: false, frame: 0, time: 0, gravity: { x: 0, y: 0 },
  bodies: new Map(),   // id -> { info, x, y, angle }
  early: new Map(),    // poses of bodies whose Added event has not arrived yet
  buffer: [],          // frames received before the scene reply
  history: [],         // { t, poses: Map id -> [x, y, angle] }, oldest first
  offsets: [],         // arrival (ms) - simulated time (ms), recent snapshots
  stats: null, alive: false, snapTimes: [],
};

const metrics = {
  fps: 0, framesDrawn: 0, framesIn: 0, bytesIn: 0, rtt: null, errors: [], rejected: [],
  tilts: 0, spawns: 0, drags: 0, tiltToSnapshot: [], tiltToVisible: [], connected: false,
};
let pendingTilt = null;  // { sentAt, g0, seenAt, t }

function resetWorld() {
  state.bodies.clear(); state.early.clear(); state.history = []; state.offsets = [];
}

function addBody(info) {
  const k = idKey(info.id);
  const b = { info, x: info.position.x, y: info.position.y, angle: info.angle };
  const early = state.early.get(k);
  if (early) { b.x = early.x; b.y = early.y; b.angle = early.angle; state.early.delete(k); }
  state.bodies.set(k, b);
}

function applyScene(s) {
  resetWorld();
  state.scene = s.scene; state.frame = s.frame; state.time = s.time; state.gravity = s.gravity;
  s.bodies.forEach(addBody);
  state.joined = true;
  const buffered = state.buffer; state.buffer = [];
  for (const item of buffered) {
    if (item.message.frame > s.frame) apply(item);
  }
  record(performance.now());
}

function applySnapshot(s, now) {
  if (s.frame <= state.frame) return;
  state.frame = s.frame; state.time = s.time; state.gravity = s.gravity;
  const listed = s.keyframe ? new Set() : null;
  for (const p of s.poses) {
    const k = idKey(p.id);
    const b = state.bodies.get(k);
    if (b) { b.x = p.x; b.y = p.y; b.angle = p.angle; } else state.early.set(k, p);
    if (listed) listed.add(k);
  }
  if (listed) {
    for (const [k, b] of state.bodies) if (!b.info.is_static && !listed.has(k)) state.bodies.delete(k);
  }
  // the simulated clock against ours: the quickest arrival of the last two seconds
  state.offsets.push(now - s.time * 1000);
  if (state.offsets.length > 120) state.offsets.shift();
  state.snapTimes.push(now);
  while (state.snapTimes.length && state.snapTimes[0] < now - 1000) state.snapTimes.shift();
  if (pendingTilt && !pendingTilt.seenAt &&
      Math.hypot(s.gravity.x - pendingTilt.g0.x, s.gravity.y - pendingTilt.g0.y) > 0.01) {
    pendingTilt.seenAt = now; pendingTilt.t = s.time;
    metrics.tiltToSnapshot.push(now - pendingTilt.sentAt);
  }
  record(now);
}

function applyEvent(e) {
  const k = e.kind;
  if (k.Added) k.Added.bodies.forEach(addBody);
  else if (k.Removed) k.Removed.ids.forEach(id => state.bodies.delete(idKey(id)));
  else if (k.Reset) {
    resetWorld();
    state.scene = k.Reset.scene; state.gravity = k.Reset.gravity;
    k.Reset.bodies.forEach(addBody);
    record(performance.now());
  } else if (k.Rejected) {
    metrics.rejected.push(k.Rejected);
    note('refused by the daemon: ' + k.Rejected.reason);
  }
}

function apply(item) {
  if (item.type === 'Snapshot') applySnapshot(item.message, item.at);
  else if (item.type === 'Event') applyEvent(item.message);
}

// Keep the full set of dynamic poses after each snapshot, for interpolation.
function record(now) {
  const poses = new Map();
  for (const [k, b] of state.bodies) if (!b.info.is_static) poses.set(k, [b.x, b.y, b.angle]);
  state.history.push({ t: state.time, poses });
  if (state.history.length > 40) state.history.shift();
}

// ---------------------------------------------------------------------------------------
// The connection.

let ws = null, hello = null, reconnectTimer = null;
const params = new URLSearchParams(location.hash.slice(1));

function connect(world) {
  if (ws) { ws.onclose = null; ws.close(); }
  state.joined = false; state.buffer = []; state.frame = 0; state.alive = false; resetWorld();
  snapshots.reset();
  const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
  const q = world ? '?world=' + encodeURIComponent(world) : '';
  const sock = new WebSocket(proto + '//' + location.host + '/ws' + q);
  sock.binaryType = 'arraybuffer';
  sock.onopen = () => { metrics.connected = true; };
  sock.onmessage = ev => {
    if (typeof ev.data === 'string') return onText(JSON.parse(ev.data));
    const bytes = new Uint8Array(ev.data);
    metrics.framesIn++; metrics.bytesIn += bytes.length;
    let f;
    try { f = decodeFrame(bytes); } catch (e) { metrics.errors.push(String(e.message)); return; }
    const item = { type: f.type, message: f.message, at: performance.now() };
    if (f.type === 'Snapshot') {
      item.message = snapshots.apply(f.message);
      if (!item.message) return;  // a delta without its keyframe: wait for the next one
    }
    if (f.type === 'SceneState') { state.world = f.message.world; applyScene(f.message); }
    else if (f.type === 'Stats') state.stats = f.message;
    else if (!state.joined) state.buffer.push(item);
    else apply(item);
  };
  sock.onclose = () => {
    metrics.connected = false;
    clearTimeout(reconnectTimer);
    reconnectTimer = setTimeout(() => connect(state.world || world), 1000);
  };
  ws = sock;
}

function onText(m) {
  if (m.type === 'hello') {
    hello = m; state.world = m.world;
    fillWorlds(m.worlds);
    document.getElementById('reset').style.display = m.allow.includes('reset') ? '' : 'none';
  } else if (m.type === 'worlds') fillWorlds(m.worlds);
  else if (m.type === 'server') { state.alive = m.alive; if (!m.alive) note('no daemon serves this world'); else note(''); }
  else if (m.type === 'pong') metrics.rtt = performance.now() - m.t;
  else if (m.type === 'error') { metrics.errors.push(m.reason); note('refused: ' + m.reason); }
}

function send(type, m) {
  if (!ws || ws.readyState !== 1) return false;
  if (hello && !hello.allow.includes(TAGS[TAG_OF[type]][0])) { note(TAGS[TAG_OF[type]][0] + ' is not allowed by this gateway'); return false; }
  ws.send(encodeFrame(type, m));
  return true;
}

setInterval(() => {
  if (ws && ws.readyState === 1) ws.send(JSON.stringify({ type: 'ping', t: performance.now() }));
}, 1000);

let noteTimer = null;
function note(s) {
  const el = document.getElementById('note');
  el.textContent = s;
  clearTimeout(noteTimer);
  if (s) noteTimer = setTimeout(() => { el.textContent = ''; }, 4000);
}

function fillWorlds(list) {
  const sel = document.getElementById('worlds');
  const names = new Set(list); if (state.world) names.add(state.world);
  sel.innerHTML = '';
  for (const w of [...names].sort()) {
    const o = document.createElement('option'); o.value = w; o.textContent = w;
    if (w === state.world) o.selected = true;
    sel.appendChild(o);
  }
  sel.disabled = hello && !hello.pick;
}

// ---------------------------------------------------------------------------------------
// Drawing. The walls (the static bodies; every body when there are none) are fitted into the
// canvas with one scale on both axes, 94 % of the tighter side, centred.

const canvas = document.getElementById('world');
const ctx = canvas.getContext('2d');
const FIT = 0.94;

function shapeExtent(b, x, y, a) {
  const s = b.info.shape, c = Math.cos(a), sn = Math.sin(a);
  const pts = [];
  if (s.Rect) { const w = s.Rect.width / 2, h = s.Rect.height / 2; pts.push([-w, -h], [w, -h], [w, h], [-w, h]); }
  else if (s.Polygon) s.Polygon.vertices.forEach(v => pts.push([v.x, v.y]));
  else if (s.Segment) {
    const g = s.Segment, r = g.radius;
    pts.push([g.a.x - r, g.a.y - r], [g.a.x + r, g.a.y + r], [g.b.x - r, g.b.y - r], [g.b.x + r, g.b.y + r]);
  } else {
    const r = s.Circle ? s.Circle.radius : s.Capsule.radius;
    const h = s.Capsule ? s.Capsule.length / 2 - r : 0;
    return [x - Math.abs(c * h) - r, y - Math.abs(sn * h) - r, x + Math.abs(c * h) + r, y + Math.abs(sn * h) + r];
  }
  let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
  for (const [px, py] of pts) {
    const wx = x + c * px - sn * py, wy = y + sn * px + c * py;
    x0 = Math.min(x0, wx); y0 = Math.min(y0, wy); x1 = Math.max(x1, wx); y1 = Math.max(y1, wy);
  }
  return [x0, y0, x1, y1];
}

function view() {
  const W = canvas.clientWidth, H = canvas.clientHeight;
  let box = null;
  const grow = e => { box = box ? [Math.min(box[0], e[0]), Math.min(box[1], e[1]), Math.max(box[2], e[2]), Math.max(box[3], e[3])] : e; };
  for (const b of state.bodies.values()) if (b.info.is_static) grow(shapeExtent(b, b.x, b.y, b.angle));
  if (!box) for (const b of state.bodies.values()) grow(shapeExtent(b, b.x, b.y, b.angle));
  if (!box) box = [-5, -1, 5, 7];
  const bw = Math.max(box[2] - box[0], 1e-3), bh = Math.max(box[3] - box[1], 1e-3);
  const scale = Math.min(W / bw, H / bh) * FIT;
  const cx = (box[0] + box[2]) / 2, cy = (box[1] + box[3]) / 2;
  return { W, H, scale, ox: W / 2 - scale * cx, oy: H / 2 + scale * cy };
}
let lastView = view();

function toPixel(x, y) { const v = lastView; return [v.ox + v.scale * x, v.oy - v.scale * y]; }
function toWorld(px, py) { const v = lastView; return [(px - v.ox) / v.scale, (v.oy - py) / v.scale]; }

function css(c) { return 'rgb(' + c.r + ',' + c.g + ',' + c.b + ')'; }
function darker(c) { return 'rgb(' + (c.r * 0.55 | 0) + ',' + (c.g * 0.55 | 0) + ',' + (c.b * 0.55 | 0) + ')'; }

function drawBody(b, x, y, a, px) {
  const s = b.info.shape;
  ctx.save();
  ctx.translate(x, y); ctx.rotate(a);
  ctx.beginPath();
  if (s.Rect) ctx.rect(-s.Rect.width / 2, -s.Rect.height / 2, s.Rect.width, s.Rect.height);
  else if (s.Circle) ctx.arc(0, 0, s.Circle.radius, 0, 2 * Math.PI);
  else if (s.Capsule) {
    const r = s.Capsule.radius, h = s.Capsule.length / 2 - r;
    ctx.arc(h, 0, r, -Math.PI / 2, Math.PI / 2);
    ctx.arc(-h, 0, r, Math.PI / 2, 3 * Math.PI / 2);
    ctx.closePath();
  } else if (s.Segment) {  // a line of terrain: stroked, as thick as it is (at least 2 px)
    const g = s.Segment;
    ctx.moveTo(g.a.x, g.a.y); ctx.lineTo(g.b.x, g.b.y);
    ctx.lineWidth = Math.max(2 * g.radius, 2 * px);
    ctx.lineCap = 'round';
    ctx.strokeStyle = css(b.info.colour);
    ctx.stroke();
    ctx.restore();
    return;
  } else {
    const v = s.Polygon.vertices;
    ctx.moveTo(v[0].x, v[0].y);
    for (let i = 1; i < v.length; i++) ctx.lineTo(v[i].x, v[i].y);
    ctx.closePath();
  }
  ctx.fillStyle = css(b.info.colour);
  ctx.fill();
  ctx.lineWidth = px;
  ctx.strokeStyle = darker(b.info.colour);
  ctx.stroke();
  if (s.Circle) {  // a mark along the body's x axis, so a rolling ball is seen to turn
    ctx.beginPath(); ctx.moveTo(s.Circle.radius * 0.3, 0); ctx.lineTo(s.Circle.radius, 0);
    ctx.lineWidth = 2 * px; ctx.stroke();
  }
  ctx.restore();
}

// Where the world is drawn: the simulated time `delay` behind the newest snapshot's expected
// arrival, interpolated between the two recorded pose sets around it.
function interval() {
  const h = state.history;
  if (h.length < 2) return 1 / 60;
  const dts = [];
  for (let i = Math.max(1, h.length - 10); i < h.length; i++) { const d = h[i].t - h[i - 1].t; if (d > 0) dts.push(d); }
  dts.sort((a, b) => a - b);
  return dts.length ? dts[dts.length >> 1] : 1 / 60;
}

function sample(now) {
  const h = state.history;
  const delay = 2 * interval();
  if (!h.length || !state.offsets.length) return { poses: null, t: state.time, delay };
  const offset = Math.min(...state.offsets);
  const t = (now - offset) / 1000 - delay;
  if (t >= h[h.length - 1].t) return { poses: h[h.length - 1].poses, t, delay };
  if (t <= h[0].t) return { poses: h[0].poses, t, delay };
  let i = h.length - 1;
  while (i > 0 && h[i - 1].t > t) i--;
  const a = h[i - 1], b = h[i], u = (t - a.t) / (b.t - a.t);
  const poses = new Map();
  for (const [k, pb] of b.poses) {
    const pa = a.poses.get(k);
    // angles come within [-pi, pi): turn the short way round
    const da = pa ? pb[2] - pa[2] - 2 * Math.PI * Math.round((pb[2] - pa[2]) / (2 * Math.PI)) : 0;
    poses.set(k, pa ? [pa[0] + (pb[0] - pa[0]) * u, pa[1] + (pb[1] - pa[1]) * u, pa[2] + da * u] : pb);
  }
  return { poses, t, delay };
}

let fpsCount = 0, fpsStart = performance.now(), lastDelay = 0;
function frame(now) {
  const dpr = window.devicePixelRatio || 1;
  const W = canvas.clientWidth, H = canvas.clientHeight;
  if (canvas.width !== Math.round(W * dpr) || canvas.height !== Math.round(H * dpr)) {
    canvas.width = Math.round(W * dpr); canvas.height = Math.round(H * dpr);
  }
  lastView = view();
  const v = lastView;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = '#16161d';
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  ctx.setTransform(v.scale * dpr, 0, 0, -v.scale * dpr, v.ox * dpr, v.oy * dpr);
  const px = 1 / v.scale;
  const s = sample(now);
  lastDelay = s.delay;
  for (const b of state.bodies.values()) if (b.info.is_static) drawBody(b, b.x, b.y, b.angle, px);
  for (const [k, b] of state.bodies) {
    if (b.info.is_static) continue;
    const p = s.poses && s.poses.get(k);
    if (p) drawBody(b, p[0], p[1], p[2], px); else drawBody(b, b.x, b.y, b.angle, px);
  }
  if (pendingTilt && pendingTilt.seenAt && s.t >= pendingTilt.t) {
    metrics.tiltToVisible.push(now - pendingTilt.sentAt);
    pendingTilt = null;
  }
  metrics.framesDrawn++;
  fpsCount++;
  if (now - fpsStart >= 1000) { metrics.fps = fpsCount * 1000 / (now - fpsStart); fpsCount = 0; fpsStart = now; }
  status();
  requestAnimationFrame(frame);
}

const ARROWS = ['→', '↗', '↑', '↖', '←', '↙', '↓', '↘'];
function arrow(g) {
  if (Math.hypot(g.x, g.y) < 1e-3) return '·';
  const a = Math.atan2(g.y, g.x);
  return ARROWS[((Math.round(a / (Math.PI / 4)) % 8) + 8) % 8];
}

let lastStatus = 0;
function status() {
  const now = performance.now();
  if (now - lastStatus < 100) return;
  lastStatus = now;
  const g = state.gravity;
  const conn = !metrics.connected ? 'reconnecting' : !state.alive && !state.joined ? 'waiting for server' : state.alive ? 'live' : 'no server';
  const parts = [state.world || '?', 'frame ' + state.frame, state.bodies.size + ' bodies',
    'g ' + arrow(g) + ' ' + Math.hypot(g.x, g.y).toFixed(2), state.snapTimes.length + ' Hz',
    'latency ' + (metrics.rtt === null ? '?' : (metrics.rtt / 2).toFixed(1)) + ' ms + buffer ' + (lastDelay * 1000).toFixed(0) + ' ms',
    metrics.fps.toFixed(0) + ' fps', conn];
  if (state.scene) parts.push(state.scene);
  document.getElementById('status').textContent = parts.join(' │ ');
}

// ---------------------------------------------------------------------------------------
// Controls: the motion sensor, keys, orientation buttons, taps, reset.

const G = 9.81;
let lastSent = null, lastSentAt = 0, latest = null, flushTimer = null;
const MIN_GAP_MS = 1000 / 30;

// A reading in Android's convention (at rest it points up, m/s^2), screen frame.
function tilt(x, y, z) {
  latest = { x, y, z };
  const now = performance.now();
  if (lastSent && Math.abs(x - lastSent.x) < 0.05 && Math.abs(y - lastSent.y) < 0.05 && Math.abs(z - lastSent.z) < 0.05) return;
  if (now - lastSentAt < MIN_GAP_MS) {
    if (!flushTimer) flushTimer = setTimeout(() => { flushTimer = null; const l = latest; lastSent = null; tilt(l.x, l.y, l.z); }, MIN_GAP_MS - (now - lastSentAt));
    return;
  }
  if (send('Tilt', { Accelerometer: { x, y, z } })) {
    if (pendingTilt && now - pendingTilt.sentAt > 2000) pendingTilt = null;
    if (!pendingTilt) pendingTilt = { sentAt: now, g0: { ...state.gravity }, seenAt: null, t: null };
    lastSent = latest; lastSentAt = now; metrics.tilts++;
  }
}

let invert = false;
function onMotion(e) {
  const a = e.accelerationIncludingGravity;
  if (!a || a.x === null || a.y === null) return;
  let x = a.x, y = a.y, z = a.z || 0;
  if (invert) { x = -x; y = -y; z = -z; }
  // device frame -> screen frame when the page has turned with the device
  const ang = ((screen.orientation && screen.orientation.angle) || window.orientation || 0) * Math.PI / 180;
  if (ang) { const c = Math.cos(ang), s = Math.sin(ang); [x, y] = [c * x - s * y, s * x + c * y]; }
  motionSeen = true;
  tilt(x, y, z);
}
let motionOn = false, motionSeen = false;
// `quiet`: the attempt at load, which may be refused for want of a tap (iOS); only a tap's
// refusal is shown.
async function enableMotion(quiet) {
  if (motionOn) return;
  try {
    if (typeof DeviceMotionEvent !== 'undefined' && typeof DeviceMotionEvent.requestPermission === 'function') {
      const r = await DeviceMotionEvent.requestPermission();
      if (r !== 'granted') { if (!quiet) note('motion sensor: permission ' + r); return; }
    }
  } catch (e) { if (!quiet) note('motion sensor: ' + e.message); return; }
  if (motionOn) return;
  window.addEventListener('devicemotion', onMotion);
  motionOn = true;
  document.getElementById('motion').classList.add('on');
  if (!window.isSecureContext) note('motion sensors need HTTPS');
}

// Keys: a virtual device, as tiltbox-tilt's keyboard: roll about the screen's normal, and a
// lean back towards flat.
let roll = 0, lean = 0;
function sendVirtual() {
  const r = roll * Math.PI / 180, l = lean * Math.PI / 180;
  tilt(G * Math.sin(r) * Math.cos(l), G * Math.cos(r) * Math.cos(l), G * Math.sin(l));
}
window.addEventListener('keydown', e => {
  const step = 15;
  if (e.key === 'ArrowLeft') roll += step;
  else if (e.key === 'ArrowRight') roll -= step;
  else if (e.key === 'ArrowUp') lean = Math.min(90, lean + step);
  else if (e.key === 'ArrowDown') lean = Math.max(0, lean - step);
  else return;
  e.preventDefault();
  sendVirtual();
});
for (const b of document.querySelectorAll('button[data-o]')) {
  b.addEventListener('click', () => {
    const o = +b.dataset.o;
    roll = [0, 180, 90, -90, 0][o]; lean = o === 4 ? 90 : 0;
    if (send('Tilt', { Orientation: ORIENTATIONS[o] })) {
      pendingTilt = { sentAt: performance.now(), g0: { ...state.gravity }, seenAt: null, t: null };
      metrics.tilts++;
    }
  });
}
document.getElementById('motion').addEventListener('click', () => enableMotion(false));
document.getElementById('invert').addEventListener('change', e => { invert = e.target.checked; });
document.getElementById('reset').addEventListener('click', () => send('Reset', null));
document.getElementById('worlds').addEventListener('change', e => {
  location.hash = 'world=' + encodeURIComponent(e.target.value);
  state.world = e.target.value;
  connect(e.target.value);
});

// A tap drops a body where the finger is: a crate, a ball, a capsule, a wedge in turn.
const PALETTE = [[0xd6, 0x45, 0x41], [0xe8, 0xa3, 0x3d], [0x3a, 0x7b, 0xd5], [0x2e, 0xcc, 0x71], [0x9b, 0x59, 0xb6], [0xf1, 0xc4, 0x0f]];
const KINDS = [
  { Rect: { width: 0.5, height: 0.5 } },
  { Circle: { radius: 0.25 } },
  { Capsule: { length: 0.9, radius: 0.18 } },
  // a right triangle with its centroid at the tap
  { Polygon: { vertices: [{ x: -0.2, y: -0.15 }, { x: 0.4, y: -0.15 }, { x: -0.2, y: 0.3 }] } },
];
let spawnCount = 0;

// Dragging: a finger (or the mouse) that comes down on a dynamic body takes hold of it over
// `…/drag` (one hand per pointer, named by a random id of this page's), pulls it along as it
// moves and lets go as it lifts, so a flick throws; one that comes down on empty space spawns.
// Moves go out at most 30 times a second a hand (the gateway allows a page 120 commands a
// second, a phone tilts at 30), and again every second while a finger rests, so the daemon
// does not let go of a hand it has not heard from for 3 s.
const PAGE_HANDS = Math.floor(Math.random() * 0x3fffffff) * 1024;
const hands = new Map();  // pointerId -> { hand, target, sent }
const MOVE_EVERY_MS = 1000 / 30, KEEPALIVE_MS = 1000;

function insideShape(s, lx, ly, slop) {
  if (s.Rect) return Math.abs(lx) <= s.Rect.width / 2 + slop && Math.abs(ly) <= s.Rect.height / 2 + slop;
  if (s.Circle) return Math.hypot(lx, ly) <= s.Circle.radius + slop;
  if (s.Capsule) {
    const h = s.Capsule.length / 2 - s.Capsule.radius;
    return Math.hypot(Math.max(Math.abs(lx) - h, 0), ly) <= s.Capsule.radius + slop;
  }
  if (s.Polygon) {
    const v = s.Polygon.vertices;
    for (let i = 0; i < v.length; i++) {
      const a = v[i], b = v[(i + 1) % v.length], ex = b.x - a.x, ey = b.y - a.y;
      const len = Math.hypot(ex, ey) || 1;
      if ((ex * (ly - a.y) - ey * (lx - a.x)) / len < -slop) return false;
    }
    return true;
  }
  return false;
}

// The dynamic body under world point (x, y) as drawn (within 6 px), if any.
function bodyAt(x, y) {
  const slop = 6 / lastView.scale;
  let found = null;
  for (const [k, b] of state.bodies) {
    if (b.info.is_static) continue;
    const c = Math.cos(-b.angle), s = Math.sin(-b.angle), dx = x - b.x, dy = y - b.y;
    if (insideShape(b.info.shape, c * dx - s * dy, s * dx + c * dy, slop)) found = { key: k, b };
  }
  return found;
}

function eventPoint(e) {
  const r = canvas.getBoundingClientRect();
  return toWorld(e.clientX - r.left, e.clientY - r.top);
}

function moveHand(h, now) {
  if (send('Drag', { Move: { hand: h.hand, target: h.target } })) { h.sent = now; metrics.drags++; }
}

canvas.addEventListener('pointerdown', e => {
  enableMotion();
  const [x, y] = eventPoint(e);
  const hit = bodyAt(x, y);
  if (hit) {
    const h = { hand: PAGE_HANDS + (e.pointerId & 1023), target: { x, y }, sent: performance.now() };
    if (send('Drag', { Grab: { hand: h.hand, id: hit.b.info.id, point: { x, y } } })) {
      hands.set(e.pointerId, h);
      metrics.drags++;
      try { canvas.setPointerCapture(e.pointerId); } catch (_) { /* synthetic pointers */ }
    }
    return;
  }
  const c = PALETTE[spawnCount % PALETTE.length];
  const shape = KINDS[spawnCount % KINDS.length];
  const body = { name: null, shape, position: { x, y }, angle: 0, velocity: { x: 0, y: 0 },
    angular_velocity: 0, density: 1, friction: 0.5, restitution: shape.Circle ? 0.5 : 0.1,
    colour: { r: c[0], g: c[1], b: c[2] } };
  if (send('Spawn', { bodies: [body] })) { spawnCount++; metrics.spawns++; }
});

canvas.addEventListener('pointermove', e => {
  const h = hands.get(e.pointerId);
  if (!h) return;
  const [x, y] = eventPoint(e);
  h.target = { x, y };
  const now = performance.now();
  if (now - h.sent >= MOVE_EVERY_MS) moveHand(h, now);
});

function letGo(e) {
  const h = hands.get(e.pointerId);
  if (!h) return;
  hands.delete(e.pointerId);
  const [x, y] = eventPoint(e);
  h.target = { x, y };
  moveHand(h, performance.now());
  send('Drag', { Release: { hand: h.hand } });
}
canvas.addEventListener('pointerup', letGo);
canvas.addEventListener('pointercancel', letGo);

setInterval(() => {
  const now = performance.now();
  for (const h of hands.values()) if (now - h.sent >= KEEPALIVE_MS) moveHand(h, now);
}, 250);

// Everything a test or a curious user may look at, from the console.
window.tiltbox = {
  state, metrics, snapshots, SnapshotDecoder, decodeFrame, decodeMessage, encodeMessage, encodeFrame, toPixel,
  toWorld,
  view: () => lastView,
  motionSeen: () => motionSeen,
  pixel(x, y) {
    const dpr = window.devicePixelRatio || 1;
    const d = ctx.getImageData(Math.round(x * dpr), Math.round(y * dpr), 1, 1).data;
    return [d[0], d[1], d[2]];
  },
  hello: () => hello,
  hands: () => hands.size,
};

// Listen at once where no permission is asked (older Android browsers, desktops) or where it is
// granted without a tap (Chromium asks the site's sensor permission since it has
// `DeviceMotionEvent.requestPermission`); iOS refuses without a tap and waits for one.
enableMotion(true);
connect(params.get('world') || '');
requestAnimationFrame(frame);
})();
