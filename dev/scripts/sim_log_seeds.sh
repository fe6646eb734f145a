#!/usr/bin/env bash
# The generated benchmark: a scenario written as logs (`mrslam sim log`) for each seed, every robot's log mapped
# by `mrslam slam` with the CLI's defaults and scored against the relations its truth implies; prints a table.
#
# Usage: dev/scripts/sim_log_seeds.sh SCENARIO.toml OUT [SEEDS...]   (default seeds 0 1 2 3 4)
# Needs a release build (cargo build --release). Writes OUT/sSEED/ (logs, truth, relations, maps, summaries).
set -euo pipefail
scenario=$1
out=$2
shift 2
seeds=("${@:-0 1 2 3 4}")
bin=${MRSLAM:-target/release/mrslam}
mkdir -p "$out"
for s in ${seeds[@]}; do
  dir="$out/s$s"
  "$bin" sim log "$scenario" --out "$dir" --seed "$s" --quiet > "$dir.txt"
  for clf in "$dir"/*.clf; do
    r=$(basename "$clf" .clf)
    "$bin" slam "$clf" -o "$dir/$r.yaml" --trajectory "$dir/$r.txt" --relations "$dir/$r.relations" --summary "$dir/$r.json" --quiet > "$dir/$r.slam.txt"
  done
done
python3 - "$out" <<'PY'
import glob, json, math, os, sys
out = sys.argv[1]


def loop_error(seed_dir, name):
    """Worst translational error (m) over the loop relations (stamps more than 60 s apart), or None."""
    poses = {}
    with open(os.path.join(seed_dir, name + ".txt")) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                t, x, y, a = map(float, line.split()[:4])
                poses[round(t, 3)] = (x, y, a)
    worst = None
    with open(os.path.join(seed_dir, name + ".relations")) as f:
        for line in f:
            if not line.strip() or line.startswith("#"):
                continue
            t1, t2, dx, dy, *_ = map(float, line.split()[:8])
            if t2 - t1 <= 60.0:
                continue
            (x1, y1, a1), (x2, y2, _) = poses[round(t1, 3)], poses[round(t2, 3)]
            c, s = math.cos(a1), math.sin(a1)
            ex, ey = c * (x2 - x1) + s * (y2 - y1), -s * (x2 - x1) + c * (y2 - y1)
            e = math.hypot(ex - dx, ey - dy)
            worst = e if worst is None else max(worst, e)
    return worst


rows = {}
for summary in sorted(glob.glob(os.path.join(out, "s*", "log.json"))):
    seed_dir = os.path.dirname(summary)
    log = json.load(open(summary))
    for robot in log["robots"]:
        s = json.load(open(os.path.join(seed_dir, robot["name"] + ".json")))
        m = s["metric"]
        rows.setdefault(robot["name"], []).append((log["seed"], robot, m, loop_error(seed_dir, robot["name"])))
print("| robot | driven (m) | longest loop (m) | translation (m), per seed | rotation (deg), per seed | loop relations: worst (m), per seed |")
print("|---|---|---|---|---|---|")
for name, runs in rows.items():
    runs.sort(key=lambda r: r[0])
    d_min = min(r[1]["distance_m"] for r in runs)
    d_max = max(r[1]["distance_m"] for r in runs)
    driven = f"{d_min:.0f}" if round(d_min) == round(d_max) else f"{d_min:.0f}-{d_max:.0f}"
    loop = max(r[1]["longest_loop_m"] for r in runs)
    t = ", ".join(f"{r[2]['translation_mean_m']:.4f}" for r in runs)
    d = ", ".join(f"{r[2]['rotation_mean_deg']:.3f}" for r in runs)
    loops = ", ".join("none" if r[3] is None else f"{r[3]:.3f}" for r in runs)
    print(f"| {name} | {driven} | {loop:.0f} | {t} | {d} | {loops} |")
PY
