#!/usr/bin/env bash
# What an online merge attempt costs: a team scenario run for each seed as shipped (attempts search near the
# robots' contact) and with `search_near_contact = false` (every transform, as `mrslam merge` of two files);
# every attempt of every run listed from report.json (time in the run, where the robots' SLAMs share the cores,
# the stage that decided, the two teams' known areas), then the median of each variant.
#
# Usage: dev/scripts/merge_attempt_times.sh SCENARIO.toml OUT [SEEDS...]   (default seeds 0 1 2)
# Uses target/debug/mrslam (the dev profile is optimised) unless MRSLAM names another binary; reuses a run whose
# report.json is there. Run it alone: the times are wall times.
set -euo pipefail
scenario=$1
out=$2
shift 2
seeds=("${@:-0 1 2}")
bin=${MRSLAM:-target/debug/mrslam}
mkdir -p "$out"
# The variant: the same scenario beside the original (its world path is relative to it), the search unbounded.
dir=$(dirname "$scenario")
name=$(basename "$scenario" .toml)
everywhere="$dir/.$name-everywhere.toml"
trap 'rm -f "$everywhere"' EXIT
sed 's/^\[team\]$/[team]\nsearch_near_contact = false/' "$scenario" > "$everywhere"
for s in ${seeds[@]}; do
  [ -f "$out/near-s$s/report.json" ] || "$bin" run "$scenario" --seed "$s" --out "$out/near-s$s" --quiet > /dev/null
  [ -f "$out/everywhere-s$s/report.json" ] || "$bin" run "$everywhere" --seed "$s" --out "$out/everywhere-s$s" --quiet > /dev/null
done
python3 - "$out" ${seeds[@]} <<'PY'
import json, os, statistics, sys

out, seeds = sys.argv[1], sys.argv[2:]
print("| variant | seed | at | robots | known m² | decided by | accepted / correct | time in the run | sift / sift+boundary / correlative |")
print("|---|---|---|---|---|---|---|---|---|")
times = {"near": [], "everywhere": []}
for variant in times:
    for s in seeds:
        report = json.load(open(os.path.join(out, f"{variant}-s{s}", "report.json")))
        for a in report["team"]["attempts"]:
            verdict = "yes / yes" if a["correct"] else ("yes / **no**" if a["accepted"] else "no")
            known = " / ".join(f"{k:.0f}" for k in a["known_m2"])
            st = a.get("stage_ms", {})
            stages = " / ".join(f"{st[k]:.0f}" if k in st else "-" for k in ("sift", "sift+boundary", "correlative"))
            print(f"| {variant} | {s} | {a['time_s']:.0f} s | {' and '.join(a['robots'])} | {known} | {a['stage']} | "
                  f"{verdict} | {a['time_ms']:.0f} ms | {stages} ms |")
            times[variant].append(a["time_ms"])
print()
for variant, t in times.items():
    if t:
        print(f"{variant}: {len(t)} attempts, median {statistics.median(t):.0f} ms, range {min(t):.0f}-{max(t):.0f} ms")
PY
