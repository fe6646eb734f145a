#!/usr/bin/env bash
# Interleaved timing of mrslam-sift and OpenCV 4.10 SIFT (both single-threaded) on the synthetic 1024x1024
# images, so that both see the same machine load: ROUNDS rounds of RUNS runs each, alternating.
# usage: crates/sift/tools/bench_vs_opencv.sh [ROUNDS] [RUNS]
set -euo pipefail
rounds="${1:-4}"; runs="${2:-7}"
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
dir="$(mktemp -d)"
(cd "$root" && cargo build -q --release -p mrslam-dev --bin gen_images --bin sift_json)
"$CARGO_TARGET_DIR/release/gen_images" "$dir" > /dev/null
tool="$root/dev/scripts/opencv_sift.py"
for img in map_1024 texture_1024; do
  ours=(); cv=()
  for _ in $(seq "$rounds"); do
    ours+=("$("$CARGO_TARGET_DIR/release/sift_json" "$dir/$img.png" "$dir/o.json" --runs "$runs" | sed -E 's/.*median ([0-9.]+) ms.*/\1/')")
    cv+=("$(python3 "$tool" "$dir/$img.png" --runs "$runs" | sed -E 's/.*median ([0-9.]+) ms.*/\1/')")
  done
  python3 - "$img" "${ours[*]}" "${cv[*]}" <<'PY'
import statistics, sys
name, ours, cv = sys.argv[1], [float(v) for v in sys.argv[2].split()], [float(v) for v in sys.argv[3].split()]
o, c = statistics.median(ours), statistics.median(cv)
print(f"{name}: mrslam-sift median of round medians {o:.1f} ms {ours}, opencv {c:.1f} ms {cv}, ratio {o / c:.2f}")
PY
done
