#!/usr/bin/env bash
# What an online merge attempt costs: a team scenario run for each seed with its attempts' correlative search kept
# near the robots' contact (`search_near_contact = true`) and searching every transform (`false`, the default;
# the gate holds the contact's bound either way); every attempt of every run listed from report.json (time in
# the run, the stage that decided, the two teams' known areas, each stage's time: dev/scripts/attempt_times.py),
# then the median of each variant.
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
for variant in near everywhere; do
  echo "$variant:"
  python3 dev/scripts/attempt_times.py $(for s in ${seeds[@]}; do echo "$out/$variant-s$s/report.json"; done)
done
