#!/usr/bin/env bash
# The generated benchmark's long loop with the other lidars: scenarios/aces_loop.toml with both Pioneers' SICK LMS
# (80 m, 180°) replaced by the Hokuyo URG-04LX (4 m, 240°) and by the RPLidar A1 (6 m, 360°, sweeping at 5.5 Hz),
# each written as logs and mapped by `mrslam slam` with the CLI's defaults (dev/scripts/sim_log_seeds.sh), seeds 0-4.
#   dev/scripts/sim_log_lidars.sh OUT      (MRSLAM=path/to/mrslam; run from the repository)
set -euo pipefail
out=${1:?usage: sim_log_lidars.sh OUT}
mkdir -p "$out"
world=$(cd worlds/aces && pwd)/aces.toml
for lidar in hokuyo_urg_04lx rplidar_a1; do
  sed -e "s/lidar = \"sick_lms\"/lidar = \"$lidar\"/" -e "s#world = \"../worlds/aces/aces.toml\"#world = \"$world\"#" \
    -e "s/name = \"aces_loop\"/name = \"aces_loop_$lidar\"/" scenarios/aces_loop.toml > "$out/aces_loop_$lidar.toml"
  echo "## $lidar"
  "$(dirname "$0")/sim_log_seeds.sh" "$out/aces_loop_$lidar.toml" "$out/$lidar" 0 1 2 3 4
done
