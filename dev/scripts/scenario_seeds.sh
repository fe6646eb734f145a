#!/usr/bin/env bash
# A shipped scenario run end to end for each seed (`mrslam run --seed`); prints one table row per seed from the
# runs' report.json: seed, wall time, each robot's SLAM RMSE (m), the end merges (against the start frames, and at
# the robots' last poses), and for a team: final coverage, time to 90 %, online merges accepted / refused / false,
# time of the first correct one (s).
#
# Usage: dev/scripts/scenario_seeds.sh SCENARIO.toml OUT [SEEDS...]   (default seeds 1 2 3 4 5)
# Uses target/debug/mrslam (the dev profile is optimised) unless MRSLAM names another binary.
# Writes OUT/sSEED/ (maps, report.json) and OUT/sSEED.txt (the run's summary).
set -euo pipefail
scenario=$1
out=$2
shift 2
seeds=("${@:-1 2 3 4 5}")
bin=${MRSLAM:-target/debug/mrslam}
mkdir -p "$out"
for s in ${seeds[@]}; do
  rm -rf "$out/s$s"
  "$bin" run "$scenario" --seed "$s" --out "$out/s$s" --quiet > "$out/s$s.txt"
done
python3 - "$out" ${seeds[@]} <<'PY'
import json, os, sys

out, seeds = sys.argv[1], sys.argv[2:]


def fmt(x, digits=3):
    return "-" if x is None else f"{x:.{digits}f}"


for s in seeds:
    r = json.load(open(os.path.join(out, f"s{s}", "report.json")))
    robots = ", ".join(f"{n} {fmt(v['slam_rmse_m'])}" for n, v in sorted(r["robots"].items()))
    merges = "; ".join(
        f"{m['algorithm']} "
        + ("refused" if not m["accepted"] else ("SUCCESS" if m["success"] else "WRONG"))
        + (f" {fmt(m['rotation_error_deg'], 2)} deg / {fmt(m['translation_error_m'])} m" if m["accepted"] else "")
        + (
            f" (at the robots' last poses {fmt(m['rotation_error_at_end_deg'], 2)} deg /"
            f" {fmt(m['translation_error_at_end_m'])} m)"
            if m["accepted"] and m.get("rotation_error_at_end_deg") is not None
            else ""
        )
        for m in r["merges"]
    )
    row = [s, f"{r['wall_s']:.1f} s", robots, merges or "-"]
    t = r.get("team")
    if t:
        row += [
            f"{100 * t['final_coverage']:.1f} %",
            fmt(t["time_to_90_s"], 0) + " s" if t["time_to_90_s"] is not None else "never",
            f"{t['merges_accepted']} / {t['merges_refused']} / {t['merges_false']}",
            fmt(t["first_correct_merge_s"], 0),
        ]
    print("| " + " | ".join(str(c) for c in row) + " |")
PY
