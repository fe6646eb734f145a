#!/usr/bin/env bash
# What an online merge attempt costs: a team scenario run for each seed with its attempts' correlative search kept
# near the robots' contact (`search_near_contact = true`) and searching every transform (`false`, the default;
# the gate holds the contact's bound either way); every attempt of every run listed from report.json (time in
# the run, where the robots' SLAMs share the cores, the stage that decided, the two teams' known areas, each
# stage's time), then the median of each variant.
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
# The variants: the same scenario beside the original (its world path is relative to it), the setting added.
dir=$(dirname "$scenario")
name=$(basename "$scenario" .toml)
trap 'rm -f "$dir/.$name-near.toml" "$dir/.$name-everywhere.toml"' EXIT
sed 's/^\[team\]$/[team]\nsearch_near_contact = true/' "$scenario" > "$dir/.$name-near.toml"
sed 's/^\[team\]$/[team]\nsearch_near_contact = false/' "$scenario" > "$dir/.$name-everywhere.toml"
for s in ${seeds[@]}; do
  for variant in near everywhere; do
    [ -f "$out/$variant-s$s/report.json" ] ||
      "$bin" run "$dir/.$name-$variant.toml" --seed "$s" --out "$out/$variant-s$s" --quiet > /dev/null
  done
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
