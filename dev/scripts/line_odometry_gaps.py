#!/usr/bin/env python3
"""The scan lines around each gap in a CARMEN log, against its ODOM lines: for every scan that follows a gap of more
than five median scan periods, how far the odometry fields of the line before it, its own and the next one's lie from
the ODOM lines interpolated at the line's stamp minus LAG seconds (how old the scan lines' odometry usually is: see
line_odometry_vs_odom.py). A line written stale (a logger's last reading from before the gap) stands out.

    python3 dev/scripts/line_odometry_gaps.py ../shared/data/logs/aces.clf.gz [LAG]      (LAG: 0.12 s by default)
"""
import bisect
import gzip
import math
import sys


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def main(path, lag):
    odom, lines = [], []
    with gzip.open(path, "rt") if path.endswith(".gz") else open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "ODOM":
                odom.append((float(p[7]), float(p[1]), float(p[2]), float(p[3])))
            elif p[0] == "FLASER":
                n = int(p[1])
                v = p[2 + n:]
                lines.append((float(v[6]), float(v[3]), float(v[4]), float(v[5])))
    odom.sort()
    stamps = [o[0] for o in odom]

    def at(t):
        i = bisect.bisect_right(stamps, t)
        if i == 0 or i == len(stamps):
            return None
        a, b = odom[i - 1], odom[i]
        f = (t - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 0.0
        return a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2]), a[3] + f * wrap(b[3] - a[3])

    gaps = sorted(lines[i + 1][0] - lines[i][0] for i in range(len(lines) - 1))
    period = gaps[len(gaps) // 2]
    print(f"{path}: {len(odom)} ODOM lines, {len(lines)} FLASER lines, median scan period {period:.3f} s")
    print("| gap (s) | at (s) | line | distance (m) | heading (rad) |")
    print("|---|---|---|---|---|")
    for i in range(1, len(lines) - 1):
        gap = lines[i][0] - lines[i - 1][0]
        if gap <= 5 * period:
            continue
        for j in (i - 1, i, i + 1):
            o = at(lines[j][0] - lag)
            if o is None:
                continue
            d = math.hypot(lines[j][1] - o[0], lines[j][2] - o[1])
            print(f"| {gap:.2f} | {lines[i][0]:.2f} | {j - i:+d} | {d:.3f} | {abs(wrap(lines[j][3] - o[2])):.3f} |")


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 0.12)
