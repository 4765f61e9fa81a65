"""The package's decoders and encoders against the byte examples of docs/protocol.md, each
checked against the values its prose states (not against this package's own output)."""

import math
import os
import pathlib
import struct
import unittest

from tiltbox_client import DecodeError, SnapshotDecoder, decode, encode

REPO = pathlib.Path(os.environ.get("TILTBOX_REPO", pathlib.Path(__file__).resolve().parents[3]))
DOC = (REPO / "docs" / "protocol.md").read_text()


def blocks_after(marker):
    """The hex lines of the first text block after `marker`: one bytes object per line."""
    at = DOC.index(marker)
    start = DOC.index("```text\n", at) + 8
    body = DOC[start : DOC.index("```", start)]
    lines = []
    for line in body.splitlines():
        toks = []
        for t in line.split():
            if len(t) != 2:
                break
            try:
                toks.append(int(t, 16))
            except ValueError:
                break
        lines.append(bytes(toks))
    return lines


def f32(v):
    """`v` rounded to f32, as the wire carries it."""
    return struct.unpack("<f", struct.pack("<f", v))[0]


def payload_after(marker):
    return b"".join(blocks_after(marker))


class Documented(unittest.TestCase):
    def test_the_keyframe_and_delta_examples_give_the_poses_their_prose_states(self):
        key = decode("Snapshot", payload_after("**Worked example (keyframe).**"))
        delta = decode("Snapshot", payload_after("**Worked example (delta).**"))
        self.assertEqual((key["frame"], key["reference"], key["grid"]), (1, 0, 10))
        self.assertAlmostEqual(key["time"], 1 / 60, places=15)
        d = SnapshotDecoder()
        poses = d.apply(key)["poses"]
        self.assertEqual([(p["id"]["index"], p["x"], p["y"]) for p in poses], [(1, -1.0, 1.0), (2, 1.033203125, 1.0)])
        moved = d.apply(delta)
        self.assertFalse(moved["keyframe"])
        self.assertEqual([(p["id"]["index"], p["x"], p["y"]) for p in moved["poses"]], [(2, 1.06640625, 1.0)])
        # The same delta again is older than the last applied: skipped.
        self.assertIsNone(d.apply(delta))

    def test_the_added_and_rejected_examples_say_what_their_prose_says(self):
        added = decode("Event", payload_after("**Worked example (Added).**"))
        body = added["kind"]["Added"]["bodies"][0]
        self.assertEqual(added["frame"], 1)
        self.assertEqual((body["id"], body["name"]), ({"index": 3, "generation": 0}, "crate"))
        self.assertEqual(body["shape"], {"Rect": {"width": 0.5, "height": 0.5}})
        self.assertEqual((body["colour"], body["position"], body["mass"]), ({"r": 0xD6, "g": 0x45, "b": 0x41}, {"x": 0.0, "y": 2.0}, 0.25))
        rejected = decode("Event", payload_after("**Worked example (Rejected).**"))["kind"]["Rejected"]
        self.assertEqual(rejected["key"], "tiltbox/bricks/gravity")
        self.assertEqual(rejected["reason"], "truncated SetGravity: the payload ended in the middle of a field")

    def test_the_hits_example_says_what_its_prose_says(self):
        e = decode("Event", payload_after("**Worked example (Hits).**"))
        self.assertEqual(e["frame"], 72)
        hit = e["kind"]["Hits"]["hits"][0]
        self.assertEqual((hit["pair"]["a"]["id"]["index"], hit["pair"]["b"]["id"]["index"]), (0, 10))
        self.assertEqual((hit["point"]["y"], hit["approach_speed"]), (f32(0.05), f32(6.05)))
        self.assertEqual(e["kind"]["Hits"]["dropped"], 0)

    def test_commands_encode_to_the_documented_bytes(self):
        self.assertEqual(encode("SetGravity", {"x": 0.0, "y": -9.81}), payload_after("### SetGravity"))
        ref = {"index": 3, "generation": 0}
        self.assertEqual(encode("Remove", {"ids": [ref]}), payload_after("### Remove"))
        self.assertEqual(encode("Reset", None), payload_after("### Reset"))
        v = {"id": {"index": 5, "generation": 0}, "velocity": {"x": 0.5, "y": 0.0}, "angular_velocity": 0.0}
        self.assertEqual(encode("SetVelocity", v), payload_after("Body 5v0 to the right at 0.5 m/s"))
        grab, move, release = blocks_after("### Drag")[:3]
        self.assertEqual(encode("Drag", {"Grab": {"hand": 7, "id": ref, "point": {"x": 1.0, "y": 2.0}}}), grab)
        self.assertEqual(encode("Drag", {"Move": {"hand": 7, "target": {"x": 1.5, "y": 2.0}}}), move)
        self.assertEqual(encode("Drag", {"Release": {"hand": 7}}), release)
        upside, upright = blocks_after("send `(-9.81·x, -9.81·y, -9.81·z)`")[:2]
        self.assertEqual(encode("Tilt", {"Orientation": "PortraitUpsideDown"}), upside)
        self.assertEqual(encode("Tilt", {"Accelerometer": {"x": 0.0, "y": f32(9.81), "z": 0.0}}), upright)

    def test_the_world_query_examples_encode_and_decode_as_their_prose_says(self):
        ray = {"RayClosest": {"origin": {"x": 0.0, "y": 5.0}, "translation": {"x": 0.0, "y": -10.0}}}
        self.assertEqual(encode("WorldQuery", ray), payload_after("A ray from (0, 5) straight down 10 m"))
        answer = decode("QueryAnswer", payload_after("Its answer after frame 5"))["Hits"]
        self.assertEqual(answer["frame"], 5)
        hit = answer["hits"][0]
        self.assertEqual(hit["hit"], {"id": {"index": 4, "generation": 0}, "shape": 0})
        self.assertEqual((hit["point"], hit["normal"]), ({"x": 0.0, "y": f32(0.4)}, {"x": 0.0, "y": 1.0}))
        self.assertEqual(hit["fraction"], f32(0.46))

    def test_the_build_remove_joints_and_joints_broken_examples(self):
        def body(motion, x, colour, shape):
            return {"motion": motion, "position": {"x": x, "y": 5.0}, "colour": colour,
                    "parts": [{"shape": shape}]}
        pin = body("Static", 0.0, {"r": 0x5B, "g": 0x5B, "b": 0x66}, {"Rect": {"width": 0.25, "height": 0.25}})
        disc = body("Dynamic", 1.5, {"r": 0xD6, "g": 0x45, "b": 0x41}, {"Circle": {"radius": 0.25}})
        hinge = {"a": {"New": 0}, "b": {"New": 1}, "anchor_a": {"x": 0.0, "y": 0.0},
                 "anchor_b": {"x": -1.5, "y": 0.0}, "kind": {"Revolute": {}}}
        self.assertEqual(encode("Build", {"bodies": [pin, disc], "joints": [hinge]}), payload_after("### Build"))
        self.assertEqual(encode("RemoveJoints", {"ids": [{"index": 2, "generation": 0}]}),
                         payload_after("### RemoveJoints"))
        e = decode("Event", payload_after("**Worked example (JointsBroken).**"))
        self.assertEqual(e["frame"], 300)
        self.assertEqual(e["kind"]["JointsBroken"]["joints"],
                         [{"id": {"index": 2, "generation": 0}, "force": 9.75, "torque": 0.0}])

    def test_a_body_built_sleeping_is_motion_3(self):
        # docs/protocol.md, BuildBody: motion 3 `Sleeping`, appended.
        b = {"motion": "Sleeping", "position": {"x": 0.0, "y": 0.0},
             "parts": [{"shape": {"Circle": {"radius": 0.25}}}]}
        payload = encode("Build", {"bodies": [b], "joints": []})
        self.assertEqual(payload[:4], bytes([1, 1, 0, 3]))  # version, one body, no name, Sleeping

    def test_garbage_is_an_error_never_a_wrong_value(self):
        for bad in [b"", b"\x02\x00", b"\x01", b"\x01\x01\x02\x03"]:
            with self.assertRaises(DecodeError):
                decode("Event", bad)
        with self.assertRaises(DecodeError):
            decode("Snapshot", b"\x01" + payload_after("**Worked example (keyframe).**")[1:])
        # A u64 varint of ten bytes reads; eleven do not.
        self.assertEqual(decode("Stats", bytes([1] + [0xFF] * 9 + [1] + [0] * 11))["frame"], 2**64 - 1)


if __name__ == "__main__":
    unittest.main()
