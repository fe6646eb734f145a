#!/usr/bin/env python3
"""The scan lines around each gap in a CARMEN log, against its ODOM lines: for every scan that follows a gap of more
than five median scan periods, how far the odometry fields of the line before it, its own and the next one's lie from
the ODOM lines interpolated at the line's stamp minus LAG seconds (how old the scan lines' odometry usually is: see
line_odometry_vs_odom.py). A line written stale (a logger's last reading from before the gap) stands out.

    python3 dev/scripts/line_odometry_gaps.py ../shared/data/logs/aces.clf.gz [LAG]      (LAG: 0.12 s by default)
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from line_odometry_vs_odom import interpolator, read, wrap  # noqa: E402


def main(path, lag):
    odom, lines = read(path)
    at = interpolator(odom)
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
