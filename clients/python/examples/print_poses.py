"""Print every body's pose as the daemon moves it.

    python examples/print_poses.py [ENDPOINT] [WORLD]
"""

import sys
import time

from tiltbox_client import Client

endpoint = sys.argv[1] if len(sys.argv) > 1 else "tcp/127.0.0.1:7447"
world = sys.argv[2] if len(sys.argv) > 2 else "bricks"
with Client(endpoint, world) as c:
    names = {(b["id"]["index"], b["id"]["generation"]): b["name"] for b in c.scene()["bodies"]}

    def show(s):
        for p in s["poses"]:
            name = names.get((p["id"]["index"], p["id"]["generation"]), "?")
            print(f'{s["frame"]:>7} {name:<16} {p["x"]:8.3f} {p["y"]:8.3f} {p["angle"]:7.3f}')

    c.on_poses(show)
    c.on_events(lambda e: names.update(
        {(b["id"]["index"], b["id"]["generation"]): b["name"] for b in e["kind"].get("Added", {}).get("bodies", [])}
    ))
    while True:
        time.sleep(1)
