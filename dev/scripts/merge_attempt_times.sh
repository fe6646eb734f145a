#!/usr/bin/env bash
# What a merge attempt costs on robots' maps: a team scenario run for each seed, then every pair of its robots'
# final maps merged alone by `mrslam merge` (the cascade, the gate of the online merges) with `--report`, one
# at a time. Prints one row per pair (the stage that decided, accepted, wall time and the stages' times) and
# the median; then the online attempts of the runs (their time in the run, where the robots' SLAMs share the
# cores). Final maps are larger than most maps at contact (but a joined team merges its fused map).
#
# Usage: dev/scripts/merge_attempt_times.sh SCENARIO.toml OUT [SEEDS...]   (default seeds 0 1 2)
# Uses target/debug/mrslam (the dev profile is optimised) unless MRSLAM names another binary; reuses OUT/sSEED
# when its report.json is there.
set -euo pipefail
scenario=$1
out=$2
shift 2
seeds=("${@:-0 1 2}")
bin=${MRSLAM:-target/debug/mrslam}
mkdir -p "$out"
for s in ${seeds[@]}; do
  [ -f "$out/s$s/report.json" ] || "$bin" run "$scenario" --seed "$s" --out "$out/s$s" --quiet > "$out/s$s.txt"
  robots=$(python3 -c "import json,sys; print(' '.join(sorted(json.load(open(sys.argv[1]))['robots'])))" \
    "$out/s$s/report.json")
  set -- $robots
  while [ $# -gt 1 ]; do
    a=$1
    shift
    for b in "$@"; do
      "$bin" merge "$out/s$s/$a.yaml" "$out/s$s/$b.yaml" -o "$out/s$s/pair_${a}_$b.yaml" \
        --report "$out/s$s/pair_${a}_$b.json" > /dev/null
    done
  done
done
python3 - "$out" ${seeds[@]} <<'PY'
import glob, json, os, statistics, sys

out, seeds = sys.argv[1], sys.argv[2:]
print("| seed | maps | decided by | accepted | time | SIFT features (both stages) | correlative |")
print("|---|---|---|---|---|---|---|")
alone, online = [], []
for s in seeds:
    for path in sorted(glob.glob(os.path.join(out, f"s{s}", "pair_*.json"))):
        r = json.load(open(path))
        t = r.get("timings_ms") or {}
        features = t.get("sift/features", 0) + t.get("sift+boundary/features", 0)
        pair = os.path.basename(path)[5:-5].replace("_", " and ")
        print(f"| {s} | {pair} | {r['stage']} | {r['accepted']} | {r['time_ms']:.0f} ms | "
              f"{features:.0f} ms | {t.get('correlative', 0):.0f} ms |")
        alone.append(r["time_ms"])
    team = json.load(open(os.path.join(out, f"s{s}", "report.json"))).get("team") or {}
    online += [a["time_ms"] for a in team.get("attempts", [])]
if alone:
    print(f"\nalone: {len(alone)} merges, median {statistics.median(alone):.0f} ms, "
          f"range {min(alone):.0f}-{max(alone):.0f} ms")
if online:
    print(f"online (in the runs): {len(online)} attempts, median {statistics.median(online):.0f} ms, "
          f"range {min(online):.0f}-{max(online):.0f} ms")
PY
