#!/usr/bin/env python3
"""Frees the occupied cells of a world's map within a radius of a scenario's routes (specks left in corridors).

A map made by SLAM from a real log keeps small occupied specks in its corridors (people walking by, a chair
seen once). In a world made from that map they become posts the simulated robots drive into: a route drawn
along the real robot's path passes them where the real robot passed freely. This frees every occupied cell
within --radius of the straight segments between the scenario's route points (and its robots' start points),
in the map's image (PNG or PGM, trinary: 0 occupied, 254 free, 205 unknown), and says how many it freed.

    python3 dev/scripts/clear_route.py worlds/aces/aces.yaml scenarios/aces_loop.toml --radius 0.45
"""
import argparse
import math
import pathlib
import tomllib

import numpy as np
from PIL import Image


def read_yaml(path):
    """The few keys of a map_server YAML this needs: image, resolution, origin."""
    keys = {}
    for line in pathlib.Path(path).read_text().splitlines():
        if ":" in line and not line.lstrip().startswith("#"):
            k, v = line.split(":", 1)
            keys[k.strip()] = v.strip()
    origin = [float(x) for x in keys["origin"].strip("[]").split(",")]
    return keys["image"], float(keys["resolution"]), origin


def segments(scenario, named):
    """The straight segments each robot drives: from its start through its route points."""
    for robot in scenario.get("robots", []):
        start = robot.get("start")
        if isinstance(start, str):
            start = named.get(start)
        if isinstance(start, dict):
            start = [start["x"], start["y"]]
        points = ([start[:2]] if start else []) + [p[:2] for p in robot.get("route", [])]
        yield from zip(points, points[1:])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("map", help="the world's map_server YAML (its image is rewritten)")
    ap.add_argument("scenario", help="the scenario whose routes must be clear")
    ap.add_argument("--world", help="the world TOML naming the start points (default: the scenario's world)")
    ap.add_argument("--radius", type=float, default=0.45, help="metres either side of a route segment")
    args = ap.parse_args()
    scenario = tomllib.loads(pathlib.Path(args.scenario).read_text())
    world_path = args.world or (pathlib.Path(args.scenario).parent / scenario["world"])
    named = {k: [v["x"], v["y"]] if isinstance(v, dict) else v
             for k, v in tomllib.loads(pathlib.Path(world_path).read_text()).get("named_points", {}).items()}
    image_name, res, origin = read_yaml(args.map)
    image_path = pathlib.Path(args.map).parent / image_name
    img = np.array(Image.open(image_path))
    h, w = img.shape
    # Cell centres in world coordinates (row 0 is the top of the image: the largest y).
    xs = origin[0] + (np.arange(w) + 0.5) * res
    ys = origin[1] + (h - np.arange(h) - 0.5) * res
    rows, cols = np.nonzero(img < 100)
    px, py = xs[cols], ys[rows]
    near = np.zeros(len(rows), bool)
    for (ax, ay), (bx, by) in segments(scenario, named):
        dx, dy = bx - ax, by - ay
        length2 = dx * dx + dy * dy
        t = np.clip(((px - ax) * dx + (py - ay) * dy) / length2, 0.0, 1.0) if length2 > 0 else 0.0
        near |= np.hypot(px - (ax + t * dx), py - (ay + t * dy)) < args.radius
    img[rows[near], cols[near]] = 254
    Image.fromarray(img).save(image_path)
    print(f"{int(near.sum())} of {len(rows)} occupied cells within {args.radius} m of the routes freed in {image_path}")


if __name__ == "__main__":
    main()
