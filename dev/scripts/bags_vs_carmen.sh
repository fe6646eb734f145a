#!/usr/bin/env bash
# Every ACES bag of ../shared/data/bags mapped by `mrslam slam` against the CARMEN text it was made from: the
# relation error of each, and the largest difference of any pose in the trajectories (0 = the same file but for
# its first comment line). Also the log without its ODOM lines, converted by ../shared/tools/clf_to_bag.py
# (needs `python3 -m pip install rosbags==0.11.9`; skipped when the library is missing).
#   dev/scripts/bags_vs_carmen.sh OUT          (run from the repository; MRSLAM=path/to/mrslam, default target/release)
set -euo pipefail
out=${1:?usage: bags_vs_carmen.sh OUT}
shared=${SHARED:-../shared}
mrslam=${MRSLAM:-./target/release/mrslam}
logs=$shared/data/logs
bags=$shared/data/bags
mkdir -p "$out"

# slam NAME LOG [ARGS...]: maps LOG into OUT/NAME.{yaml,txt,json}, prints the relation error.
slam() {
  local name=$1 log=$2
  shift 2
  "$mrslam" slam "$log" -o "$out/$name.yaml" --trajectory "$out/$name.txt" --summary "$out/$name.json" \
    --relations "$logs/aces.relations" --quiet "$@" > "$out/$name.out"
}

# same A B...: the largest difference of stamp, x, y or theta between A's poses and each B's.
same() {
  python3 - "$@" <<'PY'
import json, sys
def poses(name):
    with open(name + '.txt') as f:
        return [[float(v) for v in line.split()[:4]] for line in f if line.strip() and not line.startswith('#')]
def error(name):
    m = json.load(open(name + '.json'))['metric']
    return f"{m['translation_mean_m']:.4f} m / {m['rotation_mean_deg']:.3f} deg"
reference = poses(sys.argv[1])
print(f"| {sys.argv[1].split('/')[-1]} | {len(reference)} | {error(sys.argv[1])} | (reference) |")
for other in sys.argv[2:]:
    p = poses(other)
    assert len(p) == len(reference), other
    worst = max(abs(a - b) for x, y in zip(reference, p) for a, b in zip(x, y))
    print(f"| {other.split('/')[-1]} | {len(p)} | {error(other)} | {worst:g} |")
PY
}

echo "| run | poses | error | largest pose difference |"
echo "|---|---|---|---|"
slam carmen "$logs/aces.clf.gz"
slam zstd_mcap "$bags/aces_zstd.mcap"
slam lz4_bag "$bags/aces_lz4.bag"
slam bz2_bag "$bags/aces_bz2.bag"
slam zstd_mcap_tf "$bags/aces_zstd.mcap" --base-frame base_link
same "$out/carmen" "$out/zstd_mcap" "$out/lz4_bag" "$out/bz2_bag" "$out/zstd_mcap_tf"

# The first 300 s (the lines stamped at most 370.3, as the bags' README says).
gzip -dc "$logs/aces.clf.gz" | awk '{ if ($1=="FLASER") t=$(9+$2); else if ($1=="ODOM") t=$8; else t=0;
  if (t<=370.3) print }' > "$out/head.clf"
slam head_carmen "$out/head.clf"
slam head_bag "$bags/aces_head.bag"
slam head_mcap "$bags/aces_head_mcap"
slam head_sqlite3 "$bags/aces_head_sqlite3"
same "$out/head_carmen" "$out/head_bag" "$out/head_mcap" "$out/head_sqlite3"

# Without ODOM lines: the bag's /odom is then the FLASER lines' odometry fields.
if python3 -c 'import rosbags' 2>/dev/null; then
  gzip -dc "$logs/aces.clf.gz" | grep -v '^ODOM' > "$out/no_odom.clf"
  rm -rf "$out/no_odom_mcap"
  python3 "$shared/tools/clf_to_bag.py" "$out/no_odom.clf" "$out/no_odom_mcap" --format ros2-mcap > /dev/null
  slam no_odom_carmen "$out/no_odom.clf"
  slam no_odom_mcap "$out/no_odom_mcap"
  same "$out/no_odom_carmen" "$out/no_odom_mcap"
fi
