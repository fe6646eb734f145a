#!/usr/bin/env python3
"""A scenario route from a trajectory file: a waypoint every STEP metres of the path driven.

Usage: route_from_trajectory.py TRAJECTORY [SEGMENT ...] [--step 1.0]

TRAJECTORY holds `stamp x y theta` lines (`mrslam slam --trajectory`, `mrslam sim log`'s .truth). A SEGMENT is
`FROM:TO`, seconds after the trajectory's first stamp: the poses between them, driven backwards when FROM > TO;
the route drives the segments one after the other (the whole trajectory when none is given). Prints the TOML
`route = [[x, y], ...]` line and, on stderr, the first pose (a start for the world's named points) and the
route's length. Used to drive simulated robots along the real robot's own path in a world made from that log's
map (`mrslam world from-map`): worlds/aces and scenarios/aces_loop.toml.
"""
import argparse
import math
import sys


def centred(route, map_yaml, reach):
    """Each waypoint moved within `reach` metres to the free cell farthest from every occupied cell."""
    import os

    import numpy as np
    meta = dict(l.split(":", 1) for l in open(map_yaml) if ":" in l)
    res = float(meta["resolution"])
    ox, oy = [float(v) for v in meta["origin"].strip(" []\n").split(",")[:2]]
    image = os.path.join(os.path.dirname(map_yaml), meta["image"].strip())
    if image.endswith(".png"):
        raise SystemExit("--map: give the YAML of a PGM map (e.g. the crop_map.py output)")
    data = open(image, "rb").read()
    head = data.split(maxsplit=4)
    w, h = int(head[1]), int(head[2])
    img = np.frombuffer(head[4][: w * h], dtype=np.uint8).reshape(h, w)
    occ = np.argwhere(img < 100)  # (row, col)
    k = int(round(reach / res))
    out = []
    for x, y, t in route:
        c, r = int((x - ox) / res), h - 1 - int((y - oy) / res)
        near = occ[(abs(occ[:, 0] - r) <= k + 20) & (abs(occ[:, 1] - c) <= k + 20)]
        best, best_d = (x, y), -1.0
        for dr in range(-k, k + 1):
            for dc in range(-k, k + 1):
                if dr * dr + dc * dc > k * k or img[r + dr, c + dc] < 200:
                    continue
                d = np.min(np.hypot(near[:, 0] - (r + dr), near[:, 1] - (c + dc))) if len(near) else 1e9
                if d > best_d:
                    best_d, best = d, (ox + (c + dc + 0.5) * res, oy + (h - 1 - r - dr + 0.5) * res)
        if not out or math.hypot(best[0] - out[-1][0], best[1] - out[-1][1]) > 0.3:
            out.append((best[0], best[1], t))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trajectory")
    ap.add_argument("segments", nargs="*", help="FROM:TO seconds after the first stamp (FROM > TO: backwards)")
    ap.add_argument("--step", type=float, default=1.0, help="metres between waypoints")
    ap.add_argument("--map", help="map YAML of the world: each waypoint moves (at most --reach metres) to where it "
                    "is farthest from the map's occupied cells (a real robot's path may graze a SLAM map's thick walls)")
    ap.add_argument("--reach", type=float, default=0.5)
    a = ap.parse_args()
    poses = []
    with open(a.trajectory) as f:
        for line in f:
            body = line.split("#")[0].split()
            if len(body) >= 4:
                poses.append(tuple(map(float, body[:4])))
    if not poses:
        raise SystemExit(f"{a.trajectory}: no poses")
    t0 = poses[0][0]
    path = []
    for seg in a.segments or [f"0:{poses[-1][0] - t0}"]:
        lo, hi = (float(v) for v in seg.split(":"))
        part = [(x, y, t) for s, x, y, t in poses if min(lo, hi) <= s - t0 <= max(lo, hi)]
        if not part:
            raise SystemExit(f"segment {seg}: no pose")
        if lo > hi:
            part = [(x, y, t + math.pi) for x, y, t in reversed(part)]
        path.extend(part)
    route, length, since = [], 0.0, 0.0
    for prev, p in zip(path, path[1:]):
        d = math.hypot(p[0] - prev[0], p[1] - prev[1])
        length += d
        since += d
        if since >= a.step:
            route.append(p)
            since = 0.0
    if not route or route[-1] != path[-1]:
        route.append(path[-1])
    if a.map:
        route = centred(route, a.map, a.reach)
    x, y, t = path[0]
    t = math.atan2(math.sin(t), math.cos(t))
    print(f"start: {{ x = {x:.3f}, y = {y:.3f}, theta = {t:.4f} }}; route of {length:.1f} m, {len(route)} waypoints",
          file=sys.stderr)
    print("route = [" + ", ".join(f"[{x:.2f}, {y:.2f}]" for x, y, _ in route) + "]")


if __name__ == "__main__":
    main()
