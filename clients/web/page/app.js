// tiltbox-web's page: decodes the documented protocol (docs/protocol.md) from the gateway's
// WebSocket, rebuilds the world the way a late joiner does, draws it at the display's frame
// rate between buffered snapshots, and sends tilts, spawns and resets back.
// The page's modules (ES modules, served as they are, no build step): wire.js (the protocol),
// world.js (the world as the page knows it), this one (the connection, drawing and controls).
import {
  ORIENTATIONS, TAGS, TAG_OF, SnapshotDecoder, decodeFrame, decodeMessage, encodeMessage,
  encodeFrame,
} from './wire.js';
import {
  idKey, state, metrics, probe, hooks, snapshots, resetWorld, applyScene, apply, record,
} from './world.js';

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
    if (f.type === 'SceneState' || f.type === 'SceneWithJoints') {
      state.world = (f.message.scene || f.message).world;
      applyScene(f.message);
    }
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
hooks.note = s => note(s);
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

// The bounding box [x0, y0, x1, y1] of shape `s` placed at (x, y) turned by `a`.
function shapeExtent(s, x, y, a) {
  const c = Math.cos(a), sn = Math.sin(a);
  const pts = [];
  if (s.Compound) {
    let box = null;
    for (const p of s.Compound.parts) {
      const e = shapeExtent(p.shape, x + c * p.offset.x - sn * p.offset.y,
        y + sn * p.offset.x + c * p.offset.y, a + p.angle);
      box = box ? [Math.min(box[0], e[0]), Math.min(box[1], e[1]), Math.max(box[2], e[2]), Math.max(box[3], e[3])] : e;
    }
    return box;
  }
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
  for (const b of state.bodies.values()) if (b.info.is_static) grow(shapeExtent(b.info.shape, b.x, b.y, b.angle));
  if (!box) for (const b of state.bodies.values()) grow(shapeExtent(b.info.shape, b.x, b.y, b.angle));
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
  ctx.save();
  ctx.translate(x, y); ctx.rotate(a);
  drawShape(b.info.shape, b.info.colour, px);
  ctx.restore();
}

// Draw shape `s` in its body's frame (the context already placed there).
function drawShape(s, colour, px) {
  if (s.Compound) {
    for (const p of s.Compound.parts) {
      ctx.save();
      ctx.translate(p.offset.x, p.offset.y); ctx.rotate(p.angle);
      drawShape(p.shape, colour, px);
      ctx.restore();
    }
    return;
  }
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
    ctx.strokeStyle = css(colour);
    ctx.stroke();
    return;
  } else {
    const v = s.Polygon.vertices;
    ctx.moveTo(v[0].x, v[0].y);
    for (let i = 1; i < v.length; i++) ctx.lineTo(v[i].x, v[i].y);
    ctx.closePath();
  }
  ctx.fillStyle = css(colour);
  ctx.fill();
  ctx.lineWidth = px;
  ctx.strokeStyle = darker(colour);
  ctx.stroke();
  if (s.Circle) {  // a mark along the body's x axis, so a rolling ball is seen to turn
    ctx.beginPath(); ctx.moveTo(s.Circle.radius * 0.3, 0); ctx.lineTo(s.Circle.radius, 0);
    ctx.lineWidth = 2 * px; ctx.stroke();
  }
}

// A joint end's anchor in world coordinates, with each body at the pose `poseOf` gives.
function anchorAt(end, local, poseOf) {
  if (end === 'World') return [local.x, local.y];
  const p = end.Live && poseOf(idKey(end.Live));
  if (!p) return null;
  const c = Math.cos(p[2]), s = Math.sin(p[2]);
  return [p[0] + c * local.x - s * local.y, p[1] + s * local.x + c * local.y];
}

// The joints: a line between the two anchors and a dot at each.
let lastJointPixels = [];
function drawJoints(poseOf, px) {
  lastJointPixels = [];
  ctx.lineWidth = 1.5 * px;
  ctx.strokeStyle = ctx.fillStyle = '#e8e8f0';
  for (const j of state.joints.values()) {
    const a = anchorAt(j.a, j.anchor_a, poseOf), b = anchorAt(j.b, j.anchor_b, poseOf);
    if (!a || !b) continue;
    lastJointPixels.push([...toPixel(a[0], a[1]), ...toPixel(b[0], b[1])]);
    ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
    for (const q of [a, b]) { ctx.beginPath(); ctx.arc(q[0], q[1], 2.5 * px, 0, 2 * Math.PI); ctx.fill(); }
  }
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
  const poseOf = k => {
    const b = state.bodies.get(k);
    if (!b) return null;
    return (!b.info.is_static && s.poses && s.poses.get(k)) || [b.x, b.y, b.angle];
  };
  for (const [k, b] of state.bodies) {
    if (b.info.is_static) continue;
    const p = poseOf(k);
    drawBody(b, p[0], p[1], p[2], px);
  }
  if (state.joints.size) drawJoints(poseOf, px);
  if (probe.drag) timeDrag(poseOf, now);
  if (probe.tilt && probe.tilt.seenAt && s.t >= probe.tilt.t) {
    metrics.tiltToVisible.push(now - probe.tilt.sentAt);
    probe.tilt = null;
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
    if (probe.tilt && now - probe.tilt.sentAt > 2000) probe.tilt = null;
    if (!probe.tilt) probe.tilt = { sentAt: now, g0: { ...state.gravity }, seenAt: null, t: null };
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
      probe.tilt = { sentAt: performance.now(), g0: { ...state.gravity }, seenAt: null, t: null };
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
  if (s.Compound) {
    return s.Compound.parts.some(p => {
      const c = Math.cos(p.angle), sn = Math.sin(p.angle), dx = lx - p.offset.x, dy = ly - p.offset.y;
      return insideShape(p.shape, c * dx + sn * dy, -sn * dx + c * dy, slop);
    });
  }
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
  if (send('Drag', { Move: { hand: h.hand, target: h.target } })) {
    h.sent = now; metrics.drags++;
    if (h.fresh && !probe.drag) probe.drag = { sentAt: now, key: h.key, from: null };
    h.fresh = false;
  }
}

// The drag probe, at each frame drawn: the first frame after the move fixes where the body
// was drawn; the first one 5 mm away from there is the finger's move on the screen.
function timeDrag(poseOf, now) {
  const d = probe.drag, p = poseOf(d.key);
  if (!p || now - d.sentAt > 2000) { probe.drag = null; return; }
  if (!d.from) { d.from = [p[0], p[1]]; return; }
  if (Math.hypot(p[0] - d.from[0], p[1] - d.from[1]) >= 0.005) {
    metrics.dragToVisible.push(now - d.sentAt);
    probe.drag = null;
  }
}

canvas.addEventListener('pointerdown', e => {
  enableMotion();
  const [x, y] = eventPoint(e);
  const hit = bodyAt(x, y);
  if (hit) {
    const h = { hand: PAGE_HANDS + (e.pointerId & 1023), target: { x, y }, sent: performance.now(),
      key: hit.key, fresh: true };
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
  joints: () => state.joints.size,
  // The anchors of the joints last drawn, in CSS pixels: [[ax, ay, bx, by], ...].
  jointPixels: () => lastJointPixels,
  bodyAt: (x, y) => { const hit = bodyAt(x, y); return hit ? hit.key : null; },
};

// Listen at once where no permission is asked (older Android browsers, desktops) or where it is
// granted without a tap (Chromium asks the site's sensor permission since it has
// `DeviceMotionEvent.requestPermission`); iOS refuses without a tap and waits for one.
enableMotion(true);
connect(params.get('world') || '');
requestAnimationFrame(frame);
