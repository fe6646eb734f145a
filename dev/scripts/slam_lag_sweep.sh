#!/usr/bin/env bash
# How a map of a log without ODOM lines depends on the lag its scan lines' odometry is re-timed by: `mrslam slam`
# with the CLI's defaults and `--set scan_odometry_line_lag_s=LAG` for each lag, every relation scored, then a
# Markdown table (lag, errors, loop edges kept, loops left open). The estimated lag's run is the row "estimate".
#   dev/scripts/slam_lag_sweep.sh LOG RELATIONS OUT [LAGS...]      (MRSLAM=path/to/mrslam; run from the repository)
# e.g. a log without its ODOM lines: gzip -dc ../shared/data/logs/aces.clf.gz | grep -v '^ODOM' | gzip > aces_no_odom.clf.gz
set -euo pipefail
log=${1:?usage: slam_lag_sweep.sh LOG RELATIONS OUT [LAGS...]}
relations=${2:?usage: slam_lag_sweep.sh LOG RELATIONS OUT [LAGS...]}
out=${3:?usage: slam_lag_sweep.sh LOG RELATIONS OUT [LAGS...]}
shift 3
lags=("$@")
[ ${#lags[@]} -eq 0 ] && lags=(0.03 0.04 0.05 0.06 0.07 0.08 0.09 0.10 0.11 0.12 0.13 0.14 0.15)
mkdir -p "$out"
run() {
  local name=$1
  shift
  [ -f "$out/$name.json" ] && return
  "${MRSLAM:-./target/release/mrslam}" slam "$log" -o "$out/$name.yaml" --relations "$relations" \
    --summary "$out/$name.json" --quiet "$@" > "$out/$name.txt"
}
run estimate
for lag in "${lags[@]}"; do
  run "lag$lag" --set "scan_odometry_line_lag_s=$lag"
done
python3 - "$out" estimate "${lags[@]/#/lag}" <<'PY'
import json, sys
out, names = sys.argv[1], sys.argv[2:]
print("| lag (s) | translation (m) | max (m) | rotation (deg) | loop edges kept | loops left open "
      "| contradicted / judged | searches everywhere (kept) |")
print("|---|---|---|---|---|---|---|---|")
for name in names:
    s = json.load(open(f"{out}/{name}.json"))
    m, l, lag = s["metric"], s["loop_closure"] or {}, s["line_odometry_lag"] or {}
    used = lag.get("used_s", 0.0)
    label = f"{used:.3f} (estimate)" if name == "estimate" else f"{used:.3f}"
    print(f"| {label} | {m['translation_mean_m']:.4f} | {m['translation_max_m']:.2f} | {m['rotation_mean_deg']:.3f} "
          f"| {l.get('closures', '-')} | {l.get('open_loops', '-')} "
          f"| {l.get('contradicted', '-')} / {l.get('judged', '-')}{' **flagged**' if l.get('contradicts_itself') else ''} "
          f"| {l.get('relocalisations', '-')} ({l.get('relocalised', '-')}) |")
PY
