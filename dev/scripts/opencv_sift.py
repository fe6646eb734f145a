#!/usr/bin/env python3
"""OpenCV's SIFT on one grey image, on one thread: the peer mrslam-sift is measured and checked against
(crates/sift/tools/compare.sh and bench_vs_opencv.sh run it; `mrslam features --json` writes the same layout).

setup: python3 -m pip install opencv-python-headless pillow numpy
usage: opencv_sift.py IMAGE [--runs 7] [--json KEYPOINTS.json]

Prints the median time of detect+compute over --runs runs and the keypoint count. With --json, writes a list of
keypoints: x, y (pixels, the top-left pixel's centre at 0,0, as OpenCV reports them), size, angle (degrees),
response, octave (OpenCV's packed octave) and descriptor (128 integers).
"""
import argparse, json, statistics, time

import cv2
import numpy as np
from PIL import Image

p = argparse.ArgumentParser()
p.add_argument("image")
p.add_argument("--runs", type=int, default=7)
p.add_argument("--json")
args = p.parse_args()
cv2.setNumThreads(1)
img = np.array(Image.open(args.image).convert("L"))
sift = cv2.SIFT_create()
times = []
keypoints, descriptors = [], None
for _ in range(max(1, args.runs)):
    start = time.perf_counter()
    keypoints, descriptors = sift.detectAndCompute(img, None)
    times.append((time.perf_counter() - start) * 1000)
print(f"opencv {cv2.__version__} sift: {img.shape[1]}x{img.shape[0]} px, {len(keypoints)} keypoints, "
      f"median {statistics.median(times):.1f} ms (min {min(times):.1f}, max {max(times):.1f}) "
      f"over {len(times)} runs, 1 thread")
if args.json:
    rows = descriptors if descriptors is not None else []
    listed = [{"x": k.pt[0], "y": k.pt[1], "size": k.size, "angle": k.angle, "response": k.response,
               "octave": k.octave, "descriptor": [int(v) for v in d]} for k, d in zip(keypoints, rows)]
    with open(args.json, "w") as f:
        json.dump(listed, f)
