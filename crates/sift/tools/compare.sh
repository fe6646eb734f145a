#!/usr/bin/env bash
# Runs mrslam-sift and OpenCV 4.10 SIFT on one image and compares their keypoints.
# usage: crates/sift/tools/compare.sh IMAGE [RUNS]
# needs: python3 -m pip install opencv-python-headless==4.10.0.84 pillow numpy
set -euo pipefail
img="$1"; runs="${2:-7}"
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
out="$(mktemp -d)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
(cd "$root" && cargo run -q --release -p mrslam-dev --bin sift_json -- "$img" "$out/ours.json" --runs "$runs")
tool="$root/dev/scripts/opencv_sift.py"
python3 "$tool" "$img" --runs "$runs" --json "$out/opencv.json"
python3 "$here/compare_opencv.py" "$out/ours.json" "$out/opencv.json"
