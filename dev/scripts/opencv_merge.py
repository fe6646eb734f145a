#!/usr/bin/env python3
"""OpenCV's SIFT merge of two ROS map_server maps, timed: the peer that `mrslam merge`'s speed is measured against.

setup: python3 -m pip install opencv-python-headless pillow numpy pyyaml   (any OpenCV >= 4.4 has SIFT)
usage: opencv_merge.py A.yaml B.yaml [--runs 7] [--threads 1]

The paper's recipe as OpenCV users write it: each map's image as stored (map_server greys), SIFT
detect+compute on both, brute-force L2 matching with Lowe's ratio test (0.75), and a RANSAC similarity
(cv2.estimateAffinePartial2D, 3 px reprojection threshold). Prints the median time of each stage and of the
whole over --runs runs, and the transform found (b's pixels to a's), so that both tools run on the same pair.
"""
import argparse, os, statistics, time
import cv2
import numpy as np
from PIL import Image


def read_map(yaml_path):
    image = None
    for line in open(yaml_path):
        key, _, value = line.partition(":")
        if key.strip() == "image":
            image = value.strip().strip("'\"")
    if image is None:
        raise SystemExit(f"{yaml_path}: no `image:` line")
    path = image if os.path.isabs(image) else os.path.join(os.path.dirname(yaml_path), image)
    return np.array(Image.open(path).convert("L"))


p = argparse.ArgumentParser()
p.add_argument("a"); p.add_argument("b")
p.add_argument("--runs", type=int, default=7); p.add_argument("--threads", type=int, default=1)
args = p.parse_args()
cv2.setNumThreads(args.threads)
a, b = read_map(args.a), read_map(args.b)
sift = cv2.SIFT_create()
matcher = cv2.BFMatcher(cv2.NORM_L2)
stages = {"detect": [], "match": [], "ransac": [], "total": []}
for _ in range(args.runs):
    t0 = time.perf_counter()
    ka, da = sift.detectAndCompute(a, None)
    kb, db = sift.detectAndCompute(b, None)
    t1 = time.perf_counter()
    good = []
    if da is not None and db is not None and len(ka) >= 2 and len(kb) >= 2:
        for pair in matcher.knnMatch(db, da, k=2):
            if len(pair) == 2 and pair[0].distance < 0.75 * pair[1].distance:
                good.append(pair[0])
    t2 = time.perf_counter()
    m, inliers = None, None
    if len(good) >= 3:
        src = np.float32([kb[g.queryIdx].pt for g in good])
        dst = np.float32([ka[g.trainIdx].pt for g in good])
        m, inliers = cv2.estimateAffinePartial2D(src, dst, method=cv2.RANSAC, ransacReprojThreshold=3.0)
    t3 = time.perf_counter()
    for k, v in zip(stages, (t1 - t0, t2 - t1, t3 - t2, t3 - t0)):
        stages[k].append(v * 1000)
med = {k: statistics.median(v) for k, v in stages.items()}
print(f"opencv {cv2.__version__}: {a.shape[1]}x{a.shape[0]} and {b.shape[1]}x{b.shape[0]} px, "
      f"{len(ka)} and {len(kb)} keypoints, {len(good)} matches, "
      f"{0 if inliers is None else int(inliers.sum())} inliers, {args.threads} thread(s), median of {args.runs} runs")
print("median ms: " + ", ".join(f"{k} {v:.1f}" for k, v in med.items()))
if m is not None:
    angle = np.degrees(np.arctan2(m[1, 0], m[0, 0]))
    print(f"transform b->a (pixels): rotation {angle:.2f} deg, translation {m[0, 2]:.1f} {m[1, 2]:.1f} px")
else:
    print("no transform")
