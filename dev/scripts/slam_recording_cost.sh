#!/usr/bin/env bash
# What a rerun recording costs `mrslam slam` (benchmarks/runs/2026-12-02-viz-slam-recording.md): each log mapped
# twice with `--rrd` and twice without, one run at a time, with the benchmark relations; prints a Markdown table
# of each run's time, real-time factor and peak memory (from its --summary) and the recording's size.
#   dev/scripts/slam_recording_cost.sh OUT [LOGS...]      (default LOGS: fr079 aces)
# Run from the repository after `cargo build --release`. DATA: the logs' folder (default ../shared/data/logs,
# LOG.clf.gz and LOG.relations); MRSLAM: the binary (default target/release/mrslam).
set -euo pipefail
out=${1:?usage: slam_recording_cost.sh OUT [LOGS...]}
shift
logs=("$@")
[ ${#logs[@]} -eq 0 ] && logs=(fr079 aces)
data=${DATA:-../shared/data/logs}
bin=${MRSLAM:-./target/release/mrslam}
mkdir -p "$out"
echo "| log | run | --rrd | time s | real-time factor | peak memory MB | recording MB |"
echo "|---|---|---|---|---|---|---|"
for log in "${logs[@]}"; do
  for i in 1 2; do
    for rec in yes no; do
      s="$out/$log-$i-rrd-$rec"
      flags=()
      [ "$rec" = yes ] && flags=(--rrd "$s.rrd")
      "$bin" slam "$data/$log.clf.gz" -o "$s.yaml" --relations "$data/$log.relations" --summary "$s.json" \
        --quiet "${flags[@]}" > "$s.txt"
      size=-
      [ "$rec" = yes ] && size=$(python3 -c "import os,sys; print(f'{os.path.getsize(sys.argv[1]) / 1e6:.1f}')" "$s.rrd")
      python3 - "$s.json" "$log" "$i" "$rec" "$size" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
peak = s.get("peak_memory_bytes")
peak = "-" if peak is None else f"{peak / 1e6:.0f}"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {s['time_s']:.1f} | {s['real_time_factor']:.1f} | {peak} | {sys.argv[5]} |")
PY
    done
  done
done
