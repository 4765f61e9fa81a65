"""Tilt the world from the keyboard (a, d: left, right; w: upright; q: quit), or from a sensor
stream: lines of "x y z" (m/s^2, device axes) on standard input with --stdin.

    python examples/tilt.py [ENDPOINT]            # keys
    my_sensor | python examples/tilt.py --stdin   # a stream
"""

import sys

from tiltbox_client import Client

args = [a for a in sys.argv[1:] if not a.startswith("--")]
endpoint = args[0] if args else "tcp/127.0.0.1:7447"
with Client(endpoint) as c:
    if "--stdin" in sys.argv:
        for line in sys.stdin:
            try:
                x, y, z = (float(v) for v in line.split())
            except ValueError:
                print("skipped (want three numbers):", line.strip(), file=sys.stderr)
                continue
            c.tilt(x, y, z)
    else:
        keys = {"a": "LandscapeLeft", "d": "LandscapeRight", "w": "Portrait", "s": "PortraitUpsideDown"}
        for line in sys.stdin:
            key = line.strip()[:1]
            if key == "q":
                break
            if key in keys:
                c.tilt_to(keys[key])
