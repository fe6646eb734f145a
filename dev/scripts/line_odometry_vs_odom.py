#!/usr/bin/env python3
"""How late a CARMEN log's scan-line odometry is against its ODOM lines: the mean distance between each FLASER
line's odometry fields (odom_x, odom_y) and the ODOM lines interpolated at the line's stamp minus a lag, for lags
of 0 to 0.2 s. The lag with the least distance is how old the scan lines' odometry is.

    python3 dev/scripts/line_odometry_vs_odom.py ../shared/data/logs/aces.clf.gz
"""
import bisect
import gzip
import math
import sys


def wrap(a):
    """An angle in [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


def read(path):
    """A CARMEN log's ODOM lines and its FLASER lines' odometry fields, each (stamp, x, y, theta); ODOM sorted."""
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
    return odom, lines


def interpolator(odom):
    """The pose (x, y, theta) of the ODOM lines `odom` at a time, interpolated; None outside them."""
    stamps = [o[0] for o in odom]

    def at(t):
        i = bisect.bisect_right(stamps, t)
        if i == 0 or i >= len(stamps):
            return None
        (ta, xa, ya, ha), (tb, xb, yb, hb) = odom[i - 1], odom[i]
        s = (t - ta) / (tb - ta) if tb > ta else 0.0
        return xa + s * (xb - xa), ya + s * (yb - ya), ha + s * wrap(hb - ha)

    return at


def main(path):
    odom, lines = read(path)
    at = interpolator(odom)
    print(f"{path}: {len(odom)} ODOM lines, {len(lines)} FLASER lines")
    print("| lag (s) | mean distance (m) |")
    print("|---|---|")
    for k in range(0, 21, 2):
        lag = k / 100
        d = [math.hypot(q[0] - x, q[1] - y) for t, x, y, _ in lines if (q := at(t - lag)) is not None]
        print(f"| {lag:.2f} | {sum(d) / max(len(d), 1):.4f} |")


if __name__ == "__main__":
    main(sys.argv[1])
