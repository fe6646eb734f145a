#!/usr/bin/env bash
# The SLAM goal table: `mrslam slam` with the CLI's defaults (or PRESET) and only --seed changed, on the three
# benchmark logs of ../shared/data/logs, seeds 0-4; one JSON summary per run in OUT, then a Markdown table.
#   dev/scripts/slam_seeds.sh OUT [PRESET] [LOGS...]
# Run from the repository after `cargo build --release` (or with MRSLAM=path/to/mrslam); one run at a time, so the real-time factors are of an
# otherwise idle machine.
set -euo pipefail
out=${1:?usage: slam_seeds.sh OUT [PRESET] [LOGS...]}
preset=${2:-matched}
shift $(( $# >= 2 ? 2 : 1 ))
logs=("$@")
[ ${#logs[@]} -eq 0 ] && logs=(aces fr079 intel)
data=${DATA:-../shared/data/logs}
mkdir -p "$out"
for log in "${logs[@]}"; do
  for seed in 0 1 2 3 4; do
    s="$out/$log-$preset-seed$seed"
    [ -f "$s.json" ] && continue
    "${MRSLAM:-./target/release/mrslam}" slam "$data/$log.clf.gz" --preset "$preset" --seed "$seed" -o "$s.yaml" \
      --relations "$data/$log.relations" --summary "$s.json" --quiet > "$s.txt"
  done
done
python3 dev/scripts/slam_table.py "$out"
