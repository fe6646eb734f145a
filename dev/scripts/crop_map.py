#!/usr/bin/env python3
"""Crops a map_server map (trinary PGM) to the part its walls span, with a margin, and frees its specks.

Usage: crop_map.py IN.yaml OUT.yaml [--min-cells 20] [--margin 2.0] [--min-group 8] [--trajectory T.txt [--radius 0.35]]

Rows and columns holding fewer than --min-cells occupied cells are the ends of long rays (through glass and open
doors), not the building: the crop keeps the span of the others, plus --margin metres, and moves the origin so
that every kept cell keeps its world position. Writes OUT.yaml and the PGM beside it. Used to make the worlds
of worlds/ from our SLAM maps of the benchmark logs.
"""
import argparse
import os

import numpy as np


def read_pgm(path):
    with open(path, "rb") as f:
        data = f.read()
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    assert fields[0] == b"P5", "binary PGM only"
    w, h = int(fields[1]), int(fields[2])
    pixels = np.frombuffer(data[pos + 1:pos + 1 + w * h], dtype=np.uint8).reshape(h, w)
    return pixels


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--min-cells", type=int, default=20)
    ap.add_argument("--margin", type=float, default=2.0)
    ap.add_argument("--trajectory", help="the log's trajectory (`stamp x y theta`): cells within --radius of it "
                    "become free (the robot drove there: what the map holds there moved, a person or a door)")
    ap.add_argument("--radius", type=float, default=0.35)
    ap.add_argument("--min-group", type=int, default=8,
                    help="groups of touching occupied cells smaller than this become free: specks (a person walking "
                    "by, a noisy return) would stand in a simulated corridor as pillars")
    a = ap.parse_args()
    meta = {}
    with open(a.input) as f:
        for line in f:
            if ":" in line:
                k, v = line.split(":", 1)
                meta[k.strip()] = v.strip()
    res = float(meta["resolution"])
    ox, oy = [float(v) for v in meta["origin"].strip("[]").split(",")[:2]]
    img = read_pgm(os.path.join(os.path.dirname(a.input), meta["image"]))
    h, w = img.shape
    occupied = img < 100
    rows = np.nonzero(occupied.sum(axis=1) >= a.min_cells)[0]
    cols = np.nonzero(occupied.sum(axis=0) >= a.min_cells)[0]
    m = int(round(a.margin / res))
    r0, r1 = max(rows[0] - m, 0), min(rows[-1] + m + 1, h)
    c0, c1 = max(cols[0] - m, 0), min(cols[-1] + m + 1, w)
    crop = img[r0:r1, c0:c1].copy()
    # Connected groups of occupied cells (8-neighbourhood) smaller than --min-group are freed.
    occ = crop < 100
    seen = np.zeros_like(occ)
    specks = np.zeros_like(occ)
    for r, c in np.argwhere(occ):
        if seen[r, c]:
            continue
        group, todo = [], [(r, c)]
        seen[r, c] = True
        while todo:
            y, x = todo.pop()
            group.append((y, x))
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    v, u = y + dy, x + dx
                    if 0 <= v < occ.shape[0] and 0 <= u < occ.shape[1] and occ[v, u] and not seen[v, u]:
                        seen[v, u] = True
                        todo.append((v, u))
        if len(group) < a.min_group:
            for y, x in group:
                specks[y, x] = True
    crop[specks] = 254
    if a.trajectory:
        k = int(round(a.radius / res))
        disk = [(dr, dc) for dr in range(-k, k + 1) for dc in range(-k, k + 1) if dr * dr + dc * dc <= k * k]
        driven = 0
        for line in open(a.trajectory):
            f = line.split("#")[0].split()
            if len(f) < 4:
                continue
            x, y = float(f[1]), float(f[2])
            r, c = h - 1 - int((y - oy) / res) - r0, int((x - ox) / res) - c0
            for dr, dc in disk:
                v, u = r + dr, c + dc
                if 0 <= v < crop.shape[0] and 0 <= u < crop.shape[1] and crop[v, u] < 100:
                    crop[v, u] = 254
                    driven += 1
        print(f"{driven} occupied cells on the robot's path freed")
    print(f"{int(specks.sum())} specks of {int(occ.sum())} occupied cells freed")
    # PGM rows run from the top (the largest y): the origin is the bottom-left cell's corner.
    new_ox = ox + c0 * res
    new_oy = oy + (h - r1) * res
    pgm = os.path.splitext(a.output)[0] + ".pgm"
    with open(pgm, "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (crop.shape[1], crop.shape[0]))
        f.write(np.ascontiguousarray(crop).tobytes())
    with open(a.output, "w") as f:
        f.write(f"image: {os.path.basename(pgm)}\nmode: trinary\nresolution: {res}\n"
                f"origin: [{new_ox:.3f}, {new_oy:.3f}, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    print(f"{a.output}: {crop.shape[1]}x{crop.shape[0]} cells of {w}x{h}, origin [{new_ox:.3f}, {new_oy:.3f}]")


if __name__ == "__main__":
    main()
