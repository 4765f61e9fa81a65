"""The client against a real daemon (its endpoint in TILTBOX_ENDPOINT; `cargo test --test
python_client` starts one on the embedded Falling Bricks scene and runs this)."""

import os
import queue
import time
import unittest

from tiltbox_client import Client

ENDPOINT = os.environ.get("TILTBOX_ENDPOINT")


def wait_for(q, test, timeout=10.0):
    """The first item of queue `q` for which `test` is true, within `timeout` seconds."""
    end = time.monotonic() + timeout
    while True:
        left = end - time.monotonic()
        if left <= 0:
            raise AssertionError("timed out waiting")
        try:
            item = q.get(timeout=left)
        except queue.Empty:
            continue
        if test(item):
            return item


@unittest.skipUnless(ENDPOINT, "set TILTBOX_ENDPOINT to a daemon's endpoint (cargo test --test python_client does)")
class AgainstTheDaemon(unittest.TestCase):
    def setUp(self):
        self.c = Client(ENDPOINT)
        self.poses, self.events, self.stats = queue.Queue(), queue.Queue(), queue.Queue()
        self.c.on_poses(self.poses.put)
        self.c.on_events(self.events.put)
        self.c.on_stats(self.stats.put)

    def tearDown(self):
        self.c.close()

    def test_scene_poses_stats_and_commands(self):
        scene = self.c.scene()
        self.assertEqual(scene["scene"], "Falling Bricks")
        names = {b["name"] for b in scene["bodies"]}
        self.assertTrue({"floor", "red brick", "purple brick"} <= names, names)
        # A keyframe lists every dynamic body (the six bricks), none of the four walls.
        key = wait_for(self.poses, lambda s: s["keyframe"])
        self.assertEqual(len(key["poses"]), 6)
        self.assertTrue(all(-4.0 < p["x"] < 4.0 and 0.0 < p["y"] < 6.0 for p in key["poses"]), key)
        stats = wait_for(self.stats, lambda s: True, timeout=3.0)
        self.assertGreaterEqual(stats["bodies"], 10)

        # A ray down the middle of the box meets something on its way to the floor, facing up.
        hit = self.c.ray({"x": 0.0, "y": 5.5}, {"x": 0.0, "y": -6.0})
        self.assertIsNotNone(hit)
        self.assertGreater(hit["normal"]["y"], 0.0)
        self.assertLessEqual(hit["point"]["y"], 5.5)
        refused = self.c.query({"Point": {"point": {"x": float("nan"), "y": 0.0}}})
        self.assertIn("point.x", refused["Refused"]["reason"])

        # Spawn a ball, then find it in the Added event and in the snapshots.
        ball = {"name": "py ball", "shape": {"Circle": {"radius": 0.3}}, "position": {"x": 0.0, "y": 5.0},
                "colour": {"r": 1, "g": 2, "b": 3}}
        self.c.spawn([ball])
        added = wait_for(self.events, lambda e: "Added" in e["kind"])["kind"]["Added"]["bodies"][0]
        self.assertEqual((added["name"], added["colour"]), ("py ball", {"r": 1, "g": 2, "b": 3}))
        self.assertAlmostEqual(added["mass"], 3.14159265 * 0.09, places=5)
        ball_id = added["id"]
        wait_for(self.poses, lambda s: any(p["id"] == ball_id for p in s["poses"]))

        # Grab it and hold it up at (2, 4): half a second later it is within 5 cm of there.
        here = next(b for b in self.c.scene()["bodies"] if b["id"] == ball_id)["position"]
        self.c.grab(11, ball_id, here)
        target = {"x": 2.0, "y": 4.0}
        for _ in range(10):
            self.c.move(11, target)
            time.sleep(0.05)
        time.sleep(0.5)
        at = next(b for b in self.c.scene()["bodies"] if b["id"] == ball_id)["position"]
        self.assertLess(((at["x"] - 2.0) ** 2 + (at["y"] - 4.0) ** 2) ** 0.5, 0.05, at)
        self.c.release(11)

        # Gravity up: the next snapshots carry it.
        self.c.set_gravity(0.0, 9.81)
        wait_for(self.poses, lambda s: abs(s["gravity"]["y"] - 9.81) < 1e-4)

        # A bad spawn is refused, naming the field, and adds nothing.
        self.c.spawn([dict(ball, shape={"Circle": {"radius": -1.0}})])
        rejected = wait_for(self.events, lambda e: "Rejected" in e["kind"])["kind"]["Rejected"]
        self.assertTrue(rejected["key"].endswith("/spawn"), rejected)
        self.assertIn("radius", rejected["reason"])
        self.c.remove([ball_id])
        removed = wait_for(self.events, lambda e: "Removed" in e["kind"])["kind"]["Removed"]
        self.assertEqual(removed["ids"], [ball_id])

        # Build an L of two boxes hanging from the world on a hinge: the Built event and the
        # scene with joints list both, the L is a compound of 1 + 0.5 kg.
        l_shape = {"position": {"x": -2.0, "y": 4.0}, "parts": [
            {"shape": {"Rect": {"width": 1.0, "height": 1.0}}},
            {"shape": {"Rect": {"width": 1.0, "height": 0.5}}, "offset": {"x": 1.0, "y": -0.25}}]}
        hinge = {"a": "World", "b": {"New": 0}, "anchor_a": {"x": -2.0, "y": 4.5},
                 "anchor_b": {"x": 0.0, "y": 0.5}, "kind": {"Revolute": {}}}
        self.c.build([l_shape], [hinge])
        built = wait_for(self.events, lambda e: "Built" in e["kind"])["kind"]["Built"]
        body, joint = built["bodies"][0], built["joints"][0]
        self.assertEqual(len(body["shape"]["Compound"]["parts"]), 2)
        self.assertAlmostEqual(body["mass"], 1.5, places=5)
        self.assertEqual((joint["joint"]["a"], joint["joint"]["b"]), ("World", {"Live": body["id"]}))
        listed = self.c.scene_with_joints()
        self.assertIn(joint["id"], [j["id"] for j in listed["joints"]])
        self.c.remove_joints([joint["id"]])
        gone = wait_for(self.events, lambda e: "JointsRemoved" in e["kind"])["kind"]["JointsRemoved"]
        self.assertEqual(gone["ids"], [joint["id"]])

    def test_a_client_that_closes_lets_go_of_what_it_held(self):
        """The client keeps its hand's liveliness token; closing the session ends it, and the
        daemon lets go at once instead of after its 3 s time-out."""
        ball = {"name": "held ball", "shape": {"Circle": {"radius": 0.3}}, "position": {"x": 2.0, "y": 1.0}}
        self.c.spawn([ball])
        added = wait_for(self.events, lambda e: "Added" in e["kind"])["kind"]["Added"]["bodies"][0]
        hand = Client(ENDPOINT)
        hand.grab(31, added["id"], added["position"])
        for _ in range(10):
            hand.move(31, {"x": 2.0, "y": 4.5})
            time.sleep(0.05)
        time.sleep(0.5)
        held = next(b for b in self.c.scene()["bodies"] if b["id"] == added["id"])["position"]
        self.assertGreater(held["y"], 4.0, held)
        hand.close()
        left = time.monotonic()
        while next(b for b in self.c.scene()["bodies"] if b["id"] == added["id"])["position"]["y"] > 3.5:
            self.assertLess(time.monotonic() - left, 1.5, "still held after the client closed")
            time.sleep(0.05)
        self.c.remove([added["id"]])


if __name__ == "__main__":
    unittest.main()
