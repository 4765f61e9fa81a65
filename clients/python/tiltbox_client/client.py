"""A tiltbox client over Zenoh: read the world (scene, poses, events, stats) and send every
command the daemon takes. Payloads are the ones docs/protocol.md documents (`wire.py`)."""

import json
import threading

import zenoh

from .wire import SnapshotDecoder, decode, encode


class Client:
    """One Zenoh session to a daemon. `endpoint` is where the daemon (or a router) listens
    (`tcp/127.0.0.1:7447` for the daemon's embedded defaults); `world` names the world
    (`bricks` unless the daemon was started with another), or give the key `prefix` itself."""

    def __init__(self, endpoint="tcp/127.0.0.1:7447", world="bricks", prefix=None):
        conf = zenoh.Config()
        conf.insert_json5("mode", json.dumps("client"))
        conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
        conf.insert_json5("scouting/multicast/enabled", "false")
        self.session = zenoh.open(conf)
        self.prefix = prefix or "tiltbox/" + world
        self._subscribers = []
        self._hands = {}  # hand -> [its liveliness token, let go]

    def key(self, suffix):
        """The full key of `suffix` (`poses`, `spawn`, ...)."""
        return self.prefix + "/" + suffix

    def close(self):
        self.session.close()

    def __enter__(self):
        return self

    def __exit__(self, *_):
        self.close()

    # Reading ------------------------------------------------------------------------------

    def scene(self, timeout=5.0):
        """The daemon's full state now (`…/scene`): a SceneState dict. Raises TimeoutError when
        no daemon answers within `timeout` seconds."""
        for reply in self.session.get(self.key("scene"), timeout=timeout):
            if reply.ok is not None:
                return decode("SceneState", reply.ok.payload.to_bytes())
        raise TimeoutError("no reply from " + self.key("scene") + " (is the daemon running?)")

    def scene_with_joints(self, timeout=5.0):
        """The state and every joint (`…/scene?joints`): {"scene": SceneState, "joints": [...]}."""
        for reply in self.session.get(self.key("scene") + "?joints", timeout=timeout):
            if reply.ok is not None:
                return decode("SceneWithJoints", reply.ok.payload.to_bytes())
        raise TimeoutError("no reply from " + self.key("scene") + " (is the daemon running?)")

    def query(self, q, timeout=5.0):
        """Ask `…/query` (a WorldQuery dict, see `wire.encode`): the QueryAnswer dict, {"Hits":
        ...}, {"Shapes": ...} or {"Refused": {"reason"}}."""
        for reply in self.session.get(self.key("query"), payload=encode("WorldQuery", q), timeout=timeout):
            if reply.ok is not None:
                return decode("QueryAnswer", reply.ok.payload.to_bytes())
        raise TimeoutError("no reply from " + self.key("query") + " (is the daemon running?)")

    def ray(self, origin, translation):
        """The closest hit of the ray from `origin` along `translation` ({x, y} m), or None."""
        answer = self.query({"RayClosest": {"origin": origin, "translation": translation}})
        if "Refused" in answer:
            raise ValueError(answer["Refused"]["reason"])
        hits = answer["Hits"]["hits"]
        return hits[0] if hits else None

    def on_poses(self, callback):
        """Call `callback(snapshot)` for every `…/poses` sample that gives poses: keyframes and
        deltas are decoded into {"frame", "time", "gravity", "keyframe", "poses"} with poses in
        metres and radians (a delta gives the bodies that moved)."""
        decoder, lock = SnapshotDecoder(), threading.Lock()

        def on_sample(sample):
            with lock:
                out = decoder.apply(decode("Snapshot", sample.payload.to_bytes()))
            if out is not None:
                callback(out)

        self._subscribers.append(self.session.declare_subscriber(self.key("poses"), on_sample))

    def on_events(self, callback):
        """Call `callback(event)` for every `…/events` sample: {"frame", "kind"}."""
        self._subscribe("events", "Event", callback)

    def on_stats(self, callback):
        """Call `callback(stats)` once a second with the daemon's `…/stats`."""
        self._subscribe("stats", "Stats", callback)

    def _subscribe(self, suffix, message, callback):
        def on_sample(sample):
            callback(decode(message, sample.payload.to_bytes()))

        self._subscribers.append(self.session.declare_subscriber(self.key(suffix), on_sample))

    # Commands -----------------------------------------------------------------------------

    def send(self, suffix, message, m, block=True):
        """Put command `message` (a dict as `wire.encode` takes it) on `…/suffix`; with
        congestion control Block unless `block` is False (tilts: the next one supersedes it)."""
        cc = zenoh.CongestionControl.BLOCK if block else zenoh.CongestionControl.DROP
        self.session.put(self.key(suffix), encode(message, m), congestion_control=cc)

    def set_gravity(self, x, y):
        self.send("gravity", "SetGravity", {"x": x, "y": y}, block=False)

    def tilt(self, x, y, z):
        """A raw accelerometer reading (m/s^2, device axes)."""
        self.send("tilt", "Tilt", {"Accelerometer": {"x": x, "y": y, "z": z}}, block=False)

    def tilt_to(self, orientation):
        """A discrete orientation: Portrait, PortraitUpsideDown, LandscapeLeft, LandscapeRight,
        FaceUp or FaceDown."""
        self.send("tilt", "Tilt", {"Orientation": orientation}, block=False)

    def spawn(self, bodies):
        """Add bodies (dicts as `wire.encode("Spawn", ...)` takes them), all or nothing."""
        self.send("spawn", "Spawn", {"bodies": bodies})

    def build(self, bodies, joints=()):
        """Add bodies of one or more shapes and joints between them (`…/build`), all or nothing;
        see `wire.encode("Build", ...)`. The daemon answers with a Built or Rejected event."""
        self.send("build", "Build", {"bodies": list(bodies), "joints": list(joints)})

    def remove_joints(self, ids):
        self.send("remove_joints", "RemoveJoints", {"ids": ids})

    def remove(self, ids):
        self.send("remove", "Remove", {"ids": ids})

    def reset(self):
        self.send("reset", "Reset", None)

    def set_velocity(self, body, velocity, angular_velocity=0.0):
        """Drive a kinematic body: `velocity` {x, y} m/s, `angular_velocity` rad/s."""
        m = {"id": body, "velocity": velocity, "angular_velocity": angular_velocity}
        self.send("velocity", "SetVelocity", m)

    def grab(self, hand, body, point):
        """Hand `hand` (an id of this client's) takes hold of `body` at `point` {x, y} m. The
        client keeps the hand's liveliness token (`…/hand/<hand>`) while it lives, so a client
        that dies lets go at once."""
        if hand not in self._hands:
            if len(self._hands) >= 16:  # drop the tokens of hands already let go
                for h in [h for h, (_, gone) in self._hands.items() if gone]:
                    self._hands.pop(h)[0].undeclare()
            self._hands[hand] = [self.session.liveliness().declare_token(self.key(f"hand/{hand}")), False]
        self._hands[hand][1] = False
        self.send("drag", "Drag", {"Grab": {"hand": hand, "id": body, "point": point}})

    def move(self, hand, target):
        self.send("drag", "Drag", {"Move": {"hand": hand, "target": target}})

    def release(self, hand):
        self.send("drag", "Drag", {"Release": {"hand": hand}})
        # The token stays a while: its end travels apart from the release, and arriving
        # first it would make the release a refusal.
        if hand in self._hands:
            self._hands[hand][1] = True
