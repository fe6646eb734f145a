#!/usr/bin/env bash
# The SLAM goal table on the three benchmark logs read without their ODOM lines (odometry only in the scan lines,
# as some logs are published): each log's ODOM lines dropped into OUT/data, then dev/scripts/slam_seeds.sh on
# those, seeds 0-4.
#   dev/scripts/slam_no_odom_seeds.sh OUT [PRESET] [LOGS...]      (MRSLAM=path/to/mrslam; run from the repository)
set -euo pipefail
out=${1:?usage: slam_no_odom_seeds.sh OUT [PRESET] [LOGS...]}
shift
preset=${1:-matched}
[ $# -gt 0 ] && shift
logs=("$@")
[ ${#logs[@]} -eq 0 ] && logs=(aces fr079 intel)
data=${DATA:-../shared/data/logs}
mkdir -p "$out/data"
for log in "${logs[@]}"; do
  [ -f "$out/data/$log.clf.gz" ] || gzip -dc "$data/$log.clf.gz" | grep -v '^ODOM' | gzip > "$out/data/$log.clf.gz"
  cp "$data/$log.relations" "$out/data/$log.relations"
done
DATA="$out/data" "$(dirname "$0")/slam_seeds.sh" "$out/runs" "$preset" "${logs[@]}"
