"""The tiltbox wire format (docs/protocol.md): decoders for what the daemon sends, encoders for
every command, and the snapshot decoder that rebuilds poses from keyframes and deltas.

Messages are plain dicts shaped as the Rust types serialize to JSON (an enum is a dict with one
key, its variant's name), so a value reads the same here, in the web page and in Rust.
Everything is in metres, seconds, radians and kilograms; f32 fields are given as Python floats.
"""

import math
import struct

VERSION = 1
"""The first byte of every payload but a snapshot's."""
SNAPSHOT_VERSION = 2
"""The first byte of a `…/poses` payload (quantized poses)."""
ANGLE_STEPS = 65536


class DecodeError(ValueError):
    """A payload that is not the message it should be: what was wrong with it."""


class Reader:
    """Postcard primitives over one payload (after its version byte)."""

    def __init__(self, data):
        self.b = bytes(data)
        self.i = 0

    def need(self, n):
        if self.i + n > len(self.b):
            raise DecodeError("truncated: the payload ended in the middle of a field")

    def u8(self):
        self.need(1)
        v = self.b[self.i]
        self.i += 1
        return v

    def varint(self, max_bytes):
        v, shift = 0, 0
        for _ in range(max_bytes):
            byte = self.u8()
            v |= (byte & 0x7F) << shift
            if byte & 0x80 == 0:
                if max_bytes == 5 and v > 0xFFFFFFFF:
                    raise DecodeError("a varint is longer than its type allows")
                return v
            shift += 7
        raise DecodeError("a varint is longer than its type allows")

    def u32(self):
        return self.varint(5)

    def u64(self):
        return self.varint(10)

    def signed(self):
        v = self.varint(10)
        return v // 2 if v % 2 == 0 else -(v + 1) // 2

    def u16le(self):
        self.need(2)
        (v,) = struct.unpack_from("<H", self.b, self.i)
        self.i += 2
        return v

    def f32(self):
        self.need(4)
        (v,) = struct.unpack_from("<f", self.b, self.i)
        self.i += 4
        return v

    def f64(self):
        self.need(8)
        (v,) = struct.unpack_from("<d", self.b, self.i)
        self.i += 8
        return v

    def bool(self):
        b = self.u8()
        if b > 1:
            raise DecodeError("a bool byte is neither 0 nor 1")
        return b == 1

    def string(self):
        n = self.u32()
        self.need(n)
        raw = self.b[self.i : self.i + n]
        self.i += n
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError as e:
            raise DecodeError("a string is not valid UTF-8") from e

    def option(self, f):
        t = self.u8()
        if t > 1:
            raise DecodeError("an option tag is neither 0 nor 1")
        return f(self) if t == 1 else None

    def seq(self, f):
        n = self.u32()
        if n > len(self.b) - self.i:
            raise DecodeError("truncated: a sequence is longer than the payload")
        return [f(self) for _ in range(n)]

    def variant(self, count, name):
        v = self.u32()
        if v >= count:
            raise DecodeError("unknown variant in " + name)
        return v


class Writer:
    """Postcard primitives, appended to a byte array."""

    def __init__(self):
        self.b = bytearray()

    def u8(self, v):
        self.b.append(v & 0xFF)

    def varint(self, v):
        if v < 0:
            raise ValueError("a varint is never negative")
        while True:
            byte = v & 0x7F
            v >>= 7
            self.b.append(byte | (0x80 if v else 0))
            if not v:
                return

    def f32(self, v):
        self.b += struct.pack("<f", v)

    def string(self, s):
        raw = s.encode("utf-8")
        self.varint(len(raw))
        self.b += raw

    def vector(self, v):
        self.f32(v["x"])
        self.f32(v["y"])


def vector(r):
    return {"x": r.f32(), "y": r.f32()}


def body_ref(r):
    return {"index": r.u32(), "generation": r.u32()}


def colour(r):
    return {"r": r.u8(), "g": r.u8(), "b": r.u8()}


def shape_spec(r, in_compound=False):
    v = r.variant(6, "ShapeSpec")
    if v == 0:
        return {"Rect": {"width": r.f32(), "height": r.f32()}}
    if v == 1:
        return {"Circle": {"radius": r.f32()}}
    if v == 2:
        return {"Capsule": {"length": r.f32(), "radius": r.f32()}}
    if v == 3:
        return {"Polygon": {"vertices": r.seq(vector)}}
    if v == 5:
        if in_compound:
            raise DecodeError("a compound's part is itself a compound")
        return {"Compound": {"parts": r.seq(part_shape)}}
    a, b, radius = vector(r), vector(r), r.f32()
    prev, nxt = r.option(vector), r.option(vector)
    return {"Segment": {"a": a, "b": b, "radius": radius, "prev": prev, "next": nxt, "one_sided": r.bool()}}


def part_shape(r):
    """One shape of a body of several: the shape, its offset and angle in the body's frame."""
    return {"shape": shape_spec(r, True), "offset": vector(r), "angle": r.f32()}


def _opt_f32(r):
    return r.option(lambda q: q.f32())


def _limit(r):
    return {"lower": r.f32(), "upper": r.f32()}


def _motor(r):
    return {"speed": r.f32(), "max": r.f32()}


def _spring(r):
    return {"hertz": r.f32(), "damping_ratio": r.f32()}


def joint_end(r):
    v = r.variant(3, "JointEnd")
    if v == 0:
        return "World"
    if v == 1:
        return {"New": r.u32()}
    return {"Live": body_ref(r)}


def joint_kind(r):
    v = r.variant(6, "JointKindSpec")
    if v == 0:
        return {"Revolute": {"reference_angle": _opt_f32(r), "limit": r.option(_limit),
                             "motor": r.option(_motor), "spring": r.option(_spring)}}
    if v == 1:
        return {"Prismatic": {"axis": vector(r), "reference_angle": _opt_f32(r),
                              "limit": r.option(_limit), "motor": r.option(_motor),
                              "spring": r.option(_spring)}}
    if v == 2:
        return {"Distance": {"length": _opt_f32(r), "spring": r.option(_spring),
                             "limit": r.option(_limit)}}
    if v == 3:
        return {"Weld": {"reference_angle": _opt_f32(r), "linear_hertz": r.f32(),
                         "linear_damping_ratio": r.f32(), "angular_hertz": r.f32(),
                         "angular_damping_ratio": r.f32()}}
    if v == 4:
        return {"Wheel": {"axis": vector(r), "spring": r.option(_spring),
                          "limit": r.option(_limit), "motor": r.option(_motor)}}
    return {"Motor": {"angular_offset": r.f32(), "max_force": r.f32(), "max_torque": r.f32(),
                      "correction_factor": r.f32()}}


def joint_spec(r):
    return {
        "a": joint_end(r), "b": joint_end(r), "anchor_a": vector(r), "anchor_b": vector(r),
        "kind": joint_kind(r), "collide_connected": r.bool(), "break_force": _opt_f32(r),
        "break_torque": _opt_f32(r),
    }


def joint_info(r):
    return {"id": body_ref(r), "joint": joint_spec(r)}


def broken_joint(r):
    return {"id": body_ref(r), "force": r.f32(), "torque": r.f32()}


def body_info(r):
    return {
        "id": body_ref(r),
        "name": r.string(),
        "shape": shape_spec(r),
        "is_static": r.bool(),
        "colour": colour(r),
        "position": vector(r),
        "angle": r.f32(),
        "velocity": vector(r),
        "angular_velocity": r.f32(),
        "mass": r.f32(),
        "friction": r.f32(),
        "restitution": r.f32(),
    }


def _list_id(r, at):
    """An id in a list sorted by slot: 2 (index - next) + (generation != 0), then the generation."""
    head = r.varint(6)
    generation = r.u32() if head % 2 == 1 else 0
    index = at[0] + head // 2
    if index > 0xFFFFFFFF:
        raise DecodeError("a body index beyond u32")
    at[0] = index + 1
    return {"index": index, "generation": generation}


def snapshot_frame(r):
    """A `…/poses` message as sent (version 2): grid steps, not metres (see SnapshotDecoder)."""
    frame, time, gravity = r.u64(), r.f64(), vector(r)
    reference, grid = r.u64(), r.u8()
    if grid > 24:
        raise DecodeError("the grid is finer than 2^-24 m")
    key = reference == 0
    n = r.u32()
    if n * (5 if key else 4) > len(r.b) - r.i:
        raise DecodeError("truncated: a sequence is longer than the payload")
    poses, at, px, py = [], [0], 0, 0
    for _ in range(n):
        pid, dx, dy = _list_id(r, at), r.signed(), r.signed()
        if key:
            px, py = px + dx, py + dy
            poses.append({"id": pid, "x": px, "y": py, "angle": r.u16le()})
        else:
            poses.append({"id": pid, "x": dx, "y": dy, "angle": r.signed()})
    gone = []
    if not key:
        m = r.u32()
        if m > len(r.b) - r.i:
            raise DecodeError("truncated: a sequence is longer than the payload")
        g = [0]
        gone = [_list_id(r, g) for _ in range(m)]
    return {"frame": frame, "time": time, "gravity": gravity, "reference": reference, "grid": grid, "poses": poses, "gone": gone}


def shape_hit(r):
    return {"id": body_ref(r), "shape": r.u32()}


def shape_pair(r):
    return {"a": shape_hit(r), "b": shape_hit(r)}


def hit_info(r):
    return {"pair": shape_pair(r), "point": vector(r), "normal": vector(r), "approach_speed": r.f32()}


def event(r):
    frame = r.u64()
    v = r.variant(10, "EventKind")
    if v == 0:
        kind = {"Added": {"bodies": r.seq(body_info)}}
    elif v == 1:
        kind = {"Removed": {"ids": r.seq(body_ref)}}
    elif v == 2:
        kind = {"Reset": {"scene": r.string(), "gravity": vector(r), "bodies": r.seq(body_info)}}
    elif v == 3:
        kind = {"Rejected": {"key": r.string(), "reason": r.string()}}
    elif v == 4:
        kind = {"Contacts": {"begin": r.seq(shape_pair), "end": r.seq(shape_pair), "dropped": r.u32()}}
    elif v == 5:
        kind = {"Hits": {"hits": r.seq(hit_info), "dropped": r.u32()}}
    elif v == 6:
        kind = {"Sensors": {"begin": r.seq(shape_pair), "end": r.seq(shape_pair), "dropped": r.u32()}}
    elif v == 7:
        kind = {"Built": {"bodies": r.seq(body_info), "joints": r.seq(joint_info)}}
    elif v == 8:
        kind = {"JointsRemoved": {"ids": r.seq(body_ref)}}
    else:
        kind = {"JointsBroken": {"joints": r.seq(broken_joint)}}
    return {"frame": frame, "kind": kind}


def scene_state(r):
    return {
        "world": r.string(),
        "scene": r.string(),
        "frame": r.u64(),
        "time": r.f64(),
        "gravity": vector(r),
        "bodies": r.seq(body_info),
    }


STATS_FIELDS = [
    ("frame", "u64"), ("bodies", "u32"), ("awake", "u32"), ("contacts", "u32"),
    ("step_us_median", "u32"), ("step_us_max", "u32"), ("lateness_us_max", "u32"),
    ("commands_applied", "u64"), ("commands_rejected", "u64"), ("steps_dropped", "u64"),
    ("commands_received", "u64"), ("commands_dropped", "u64"),
]


def stats(r):
    return {name: getattr(r, kind)() for name, kind in STATS_FIELDS}


def ray_hit(r):
    return {"hit": shape_hit(r), "point": vector(r), "normal": vector(r), "fraction": r.f32()}


def query_answer(r):
    v = r.variant(3, "QueryAnswer")
    if v == 0:
        return {"Hits": {"frame": r.u64(), "hits": r.seq(ray_hit)}}
    if v == 1:
        return {"Shapes": {"frame": r.u64(), "shapes": r.seq(shape_hit)}}
    return {"Refused": {"reason": r.string()}}


def scene_with_joints(r):
    return {"scene": scene_state(r), "joints": r.seq(joint_info)}


DECODERS = {
    "Snapshot": snapshot_frame,
    "Event": event,
    "SceneState": scene_state,
    "SceneWithJoints": scene_with_joints,
    "Stats": stats,
    "QueryAnswer": query_answer,
}


def decode(message, data):
    """Decode one payload (version byte included) as `message`: "Snapshot", "Event",
    "SceneState", "SceneWithJoints", "Stats" or "QueryAnswer". Raises DecodeError naming what
    was wrong."""
    f = DECODERS.get(message)
    if f is None:
        raise DecodeError("no message " + message)
    data = bytes(data)
    if not data:
        raise DecodeError("empty payload")
    version = SNAPSHOT_VERSION if message == "Snapshot" else VERSION
    if data[0] != version:
        raise DecodeError(f"unsupported protocol version {data[0]} (this client reads {version})")
    r = Reader(data[1:])
    m = f(r)
    if r.i != len(r.b):
        raise DecodeError(f"{len(r.b) - r.i} unexpected byte(s) after the end of a {message}")
    return m


ORIENTATIONS = ["Portrait", "PortraitUpsideDown", "LandscapeLeft", "LandscapeRight", "FaceUp", "FaceDown"]


def _write_shape(w, s):
    if "Rect" in s:
        w.varint(0); w.f32(s["Rect"]["width"]); w.f32(s["Rect"]["height"])
    elif "Circle" in s:
        w.varint(1); w.f32(s["Circle"]["radius"])
    elif "Capsule" in s:
        w.varint(2); w.f32(s["Capsule"]["length"]); w.f32(s["Capsule"]["radius"])
    elif "Polygon" in s:
        vs = s["Polygon"]["vertices"]
        w.varint(3); w.varint(len(vs))
        for v in vs:
            w.vector(v)
    else:
        raise ValueError("a spawned or built shape is a Rect, Circle, Capsule or Polygon")


def _ref(w, r):
    w.varint(r["index"]); w.varint(r["generation"])


def _spawn_body(w, b):
    if b.get("name") is None:
        w.u8(0)
    else:
        w.u8(1); w.string(b["name"])
    _write_shape(w, b["shape"])
    w.vector(b["position"]); w.f32(b.get("angle", 0.0))
    w.vector(b.get("velocity", {"x": 0.0, "y": 0.0})); w.f32(b.get("angular_velocity", 0.0))
    w.f32(b.get("density", 1.0)); w.f32(b.get("friction", 0.6)); w.f32(b.get("restitution", 0.0))
    c = b.get("colour", {"r": 128, "g": 128, "b": 128})
    w.u8(c["r"]); w.u8(c["g"]); w.u8(c["b"])


def _opt(w, v, f):
    if v is None:
        w.u8(0)
    else:
        w.u8(1); f(v)


MOTIONS = ["Dynamic", "Kinematic", "Static", "Sleeping"]
JOINT_KINDS = ["Revolute", "Prismatic", "Distance", "Weld", "Wheel", "Motor"]


def _part(w, p):
    """A PartSpec: shape, offset, angle, then material, filter and reports (defaults: density 1,
    friction 0.6, restitution 0, category 1, mask all, group 0, no sensor, no reports)."""
    _write_shape(w, p["shape"]); w.vector(p.get("offset", {"x": 0.0, "y": 0.0}))
    w.f32(p.get("angle", 0.0))
    w.f32(p.get("density", 1.0)); w.f32(p.get("friction", 0.6)); w.f32(p.get("restitution", 0.0))
    f = p.get("filter", {})
    w.varint(f.get("category", 1)); w.varint(f.get("mask", 2**64 - 1))
    g = f.get("group", 0)
    w.varint(2 * g if g >= 0 else -2 * g - 1)
    for flag in ("sensor", "contact_events", "hit_events"):
        w.u8(1 if p.get(flag, False) else 0)


def _build_body(w, b):
    _opt(w, b.get("name"), w.string)
    w.varint(MOTIONS.index(b.get("motion", "Dynamic")))
    w.vector(b["position"]); w.f32(b.get("angle", 0.0))
    w.vector(b.get("velocity", {"x": 0.0, "y": 0.0})); w.f32(b.get("angular_velocity", 0.0))
    c = b.get("colour", {"r": 128, "g": 128, "b": 128})
    w.u8(c["r"]); w.u8(c["g"]); w.u8(c["b"])
    w.varint(len(b["parts"]))
    for p in b["parts"]:
        _part(w, p)


def _joint_end(w, e):
    if e == "World":
        w.varint(0)
    elif "New" in e:
        w.varint(1); w.varint(e["New"])
    else:
        w.varint(2); _ref(w, e["Live"])


def _joint(w, j):
    """A JointSpec: {a, b, anchor_a, anchor_b, kind: {"Revolute": {...}}, collide_connected,
    break_force, break_torque}; settings left out of a kind are None."""
    _joint_end(w, j["a"]); _joint_end(w, j["b"])
    w.vector(j.get("anchor_a", {"x": 0.0, "y": 0.0})); w.vector(j.get("anchor_b", {"x": 0.0, "y": 0.0}))
    (name, k), = j["kind"].items()
    w.varint(JOINT_KINDS.index(name))
    lim = lambda v: (w.f32(v["lower"]), w.f32(v["upper"]))
    mot = lambda v: (w.f32(v["speed"]), w.f32(v["max"]))
    spr = lambda v: (w.f32(v["hertz"]), w.f32(v["damping_ratio"]))
    if name in ("Prismatic", "Wheel"):
        w.vector(k["axis"])
    if name in ("Revolute", "Prismatic"):
        _opt(w, k.get("reference_angle"), w.f32); _opt(w, k.get("limit"), lim)
        _opt(w, k.get("motor"), mot); _opt(w, k.get("spring"), spr)
    elif name == "Distance":
        _opt(w, k.get("length"), w.f32); _opt(w, k.get("spring"), spr); _opt(w, k.get("limit"), lim)
    elif name == "Weld":
        _opt(w, k.get("reference_angle"), w.f32)
        for f in ("linear_hertz", "linear_damping_ratio", "angular_hertz", "angular_damping_ratio"):
            w.f32(k.get(f, 0.0))
    elif name == "Wheel":
        _opt(w, k.get("spring"), spr); _opt(w, k.get("limit"), lim); _opt(w, k.get("motor"), mot)
    else:
        for f in ("angular_offset", "max_force", "max_torque", "correction_factor"):
            w.f32(k[f])
    w.u8(1 if j.get("collide_connected", False) else 0)
    _opt(w, j.get("break_force"), w.f32); _opt(w, j.get("break_torque"), w.f32)


def encode(message, m):
    """Encode a command (version byte + postcard): "SetGravity" {x, y}; "Tilt"
    {"Orientation": name} or {"Accelerometer": {x, y, z}}; "Spawn" {bodies}; "Remove" {ids};
    "Build" {bodies: [{motion, position, parts: [{shape, offset, ...}], ...}], joints: [...]};
    "RemoveJoints" {ids};
    "Reset" None; "SetVelocity" {id, velocity, angular_velocity}; "Drag" {"Grab": {hand, id,
    point}}, {"Move": {hand, target}} or {"Release": {hand}}; and the `…/query` request
    "WorldQuery" {"RayClosest": {origin, translation}}, {"RayAll": {..., limit}}, {"Point":
    {point}} or {"Box": {min, max}}, each with an optional "filter" {category, mask}."""
    w = Writer()
    w.u8(VERSION)
    if message == "SetGravity":
        w.vector(m)
    elif message == "Tilt":
        if "Orientation" in m:
            w.varint(0); w.varint(ORIENTATIONS.index(m["Orientation"]))
        else:
            a = m["Accelerometer"]
            w.varint(1); w.f32(a["x"]); w.f32(a["y"]); w.f32(a["z"])
    elif message == "Spawn":
        w.varint(len(m["bodies"]))
        for b in m["bodies"]:
            _spawn_body(w, b)
    elif message == "Remove":
        w.varint(len(m["ids"]))
        for r in m["ids"]:
            _ref(w, r)
    elif message == "Reset":
        pass
    elif message == "Build":
        w.varint(len(m["bodies"]))
        for b in m["bodies"]:
            _build_body(w, b)
        w.varint(len(m["joints"]))
        for j in m["joints"]:
            _joint(w, j)
    elif message == "RemoveJoints":
        w.varint(len(m["ids"]))
        for r in m["ids"]:
            _ref(w, r)
    elif message == "SetVelocity":
        _ref(w, m["id"]); w.vector(m["velocity"]); w.f32(m["angular_velocity"])
    elif message == "WorldQuery":
        _world_query(w, m)
    elif message == "Drag":
        if "Grab" in m:
            g = m["Grab"]
            w.varint(0); w.varint(g["hand"]); _ref(w, g["id"]); w.vector(g["point"])
        elif "Move" in m:
            w.varint(1); w.varint(m["Move"]["hand"]); w.vector(m["Move"]["target"])
        else:
            w.varint(2); w.varint(m["Release"]["hand"])
    else:
        raise ValueError("not a command: " + message)
    return bytes(w.b)


def _world_query(w, m):
    (name, q), = m.items()
    f = q.get("filter", {"category": 1, "mask": 2**64 - 1})
    if name in ("RayClosest", "RayAll"):
        w.varint(0 if name == "RayClosest" else 1); w.vector(q["origin"]); w.vector(q["translation"])
    elif name == "Point":
        w.varint(2); w.vector(q["point"])
    elif name == "Box":
        w.varint(3); w.vector(q["min"]); w.vector(q["max"])
    else:
        raise ValueError("a WorldQuery is RayClosest, RayAll, Point or Box")
    w.varint(f["category"]); w.varint(f["mask"])
    if name == "RayAll":
        w.varint(q["limit"])


def _key(i):
    return (i["index"], i["generation"])


class SnapshotDecoder:
    """Rebuilds poses from `…/poses` payloads (docs/protocol.md, "Decoding"): keeps the latest
    keyframe; a delta is applied only against the keyframe it names, and only if it is newer than
    the last one applied. `apply` gives, for a keyframe, every dynamic body; for a delta, the
    bodies whose pose changed since the previous one given out (None for a skipped delta). Poses
    are {"id", "x", "y", "angle"} in metres and radians, angles within [-pi, pi)."""

    def __init__(self):
        self.skipped = 0
        self.key = None
        self.changed = {}
        self.last = 0

    @staticmethod
    def _pose(pid, q, grid):
        step = 2.0 ** -grid
        a = q[2] - ANGLE_STEPS if q[2] >= ANGLE_STEPS // 2 else q[2]
        return {"id": pid, "x": q[0] * step, "y": q[1] * step, "angle": a * (2 * math.pi / ANGLE_STEPS)}

    def apply(self, f):
        out = []
        if f["reference"] == 0:
            poses = {}
            for p in f["poses"]:
                q = (p["x"], p["y"], p["angle"])
                poses[_key(p["id"])] = (p["id"], q)
                out.append(self._pose(p["id"], q, f["grid"]))
            self.key = {"frame": f["frame"], "grid": f["grid"], "poses": poses}
            self.changed = {}
        else:
            k = self.key
            if k is None or k["frame"] != f["frame"] - f["reference"] or k["grid"] != f["grid"] or f["frame"] <= self.last:
                self.skipped += 1
                return None
            now = {}
            for p in f["poses"]:
                key = _key(p["id"])
                kq = k["poses"].get(key, (None, None))[1]
                base = kq or (0, 0, 0)
                q = (base[0] + p["x"], base[1] + p["y"], (base[2] + p["angle"]) % ANGLE_STEPS)
                now[key] = (p["id"], q)
                was = self.changed[key][1] if key in self.changed else kq
                if was != q:
                    out.append(self._pose(p["id"], q, f["grid"]))
            gone = {_key(g) for g in f["gone"]}
            for key, (pid, _) in self.changed.items():
                if key not in now and key not in gone and key in k["poses"]:
                    out.append(self._pose(pid, k["poses"][key][1], f["grid"]))
            self.changed = now
        self.last = f["frame"]
        return {"frame": f["frame"], "time": f["time"], "gravity": f["gravity"], "keyframe": f["reference"] == 0, "poses": out}
