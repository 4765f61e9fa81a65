// The world as the page knows it: the scene reply, then snapshots and events (the late join
// of docs/protocol.md), and a short history of full pose sets for interpolation.
import { SnapshotDecoder, idKey } from './wire.js';

const snapshots = new SnapshotDecoder();

const state = {
  world: '', scene: '', joined: false, frame: 0, time: 0, gravity: { x: 0, y: 0 },
  bodies: new Map(),   // id -> { info, x, y, angle }
  joints: new Map(),   // joint id -> JointSpec (ends 'World' or { Live: id })
  early: new Map(),    // poses of bodies whose Added event has not arrived yet
  buffer: [],          // frames received before the scene reply
  history: [],         // { t, poses: Map id -> [x, y, angle] }, oldest first
  offsets: [],         // arrival (ms) - simulated time (ms), recent snapshots
  stats: null, alive: false, snapTimes: [],
};

const metrics = {
  fps: 0, framesDrawn: 0, framesIn: 0, bytesIn: 0, rtt: null, errors: [], rejected: [],
  tilts: 0, spawns: 0, drags: 0, tiltToSnapshot: [], tiltToVisible: [], dragToVisible: [],
  connected: false,
};
// A tilt in flight, timed until its gravity is drawn: { sentAt, g0, seenAt, t } or null.
// A drag's first move, timed until its body is drawn 5 mm from where it was drawn when the
// move went out: { sentAt, key, from } or null.
const probe = { tilt: null, drag: null };
// What the world tells the person (a refusal); app.js puts it on the screen.
const hooks = { note: () => {} };

function resetWorld() {
  state.bodies.clear(); state.joints.clear(); state.early.clear(); state.history = [];
  state.offsets = [];
}

function addJoint(j) { state.joints.set(idKey(j.id), j.joint); }

// Whether a joint end is one of the bodies in `gone` (a set of id keys).
const endIn = (end, gone) => end.Live !== undefined && gone.has(idKey(end.Live));

function removeBodies(ids) {
  const gone = new Set(ids.map(idKey));
  for (const k of gone) state.bodies.delete(k);
  // a body's joints go with it
  for (const [k, j] of state.joints) if (endIn(j.a, gone) || endIn(j.b, gone)) state.joints.delete(k);
}

function addBody(info) {
  const k = idKey(info.id);
  const b = { info, x: info.position.x, y: info.position.y, angle: info.angle };
  const early = state.early.get(k);
  if (early) { b.x = early.x; b.y = early.y; b.angle = early.angle; state.early.delete(k); }
  state.bodies.set(k, b);
}

// The scene reply: a SceneState, or (tag 14) a SceneWithJoints.
function applyScene(reply) {
  const s = reply.scene || reply;
  resetWorld();
  (reply.joints || []).forEach(addJoint);
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
  const pending = probe.tilt;
  if (pending && !pending.seenAt &&
      Math.hypot(s.gravity.x - pending.g0.x, s.gravity.y - pending.g0.y) > 0.01) {
    pending.seenAt = now; pending.t = s.time;
    metrics.tiltToSnapshot.push(now - pending.sentAt);
  }
  record(now);
}

function applyEvent(e) {
  const k = e.kind;
  if (k.Added) k.Added.bodies.forEach(addBody);
  else if (k.Removed) removeBodies(k.Removed.ids);
  else if (k.Built) { k.Built.bodies.forEach(addBody); k.Built.joints.forEach(addJoint); }
  else if (k.JointsRemoved) k.JointsRemoved.ids.forEach(id => state.joints.delete(idKey(id)));
  else if (k.JointsBroken) k.JointsBroken.joints.forEach(j => state.joints.delete(idKey(j.id)));
  else if (k.Reset) {
    resetWorld();
    state.scene = k.Reset.scene; state.gravity = k.Reset.gravity;
    k.Reset.bodies.forEach(addBody);
    record(performance.now());
  } else if (k.Rejected) {
    metrics.rejected.push(k.Rejected);
    hooks.note('refused by the daemon: ' + k.Rejected.reason);
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


export {
  idKey, state, metrics, probe, hooks, snapshots, resetWorld, applyScene, apply, record,
};
