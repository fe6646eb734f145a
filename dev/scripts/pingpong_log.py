#!/usr/bin/env python3
"""A long benchmark log from a short one: the log played forwards, then backwards, then forwards, ...

    dev/scripts/pingpong_log.py LOG.clf.gz RELATIONS PASSES OUT.clf.gz OUT.relations

A backward pass replays the lines in reverse order: the robot drives the same path in reverse, every scan seen
from the pose it was taken at, the odometry poses the same (so each pass starts where the last one ended and the
odometry stays continuous; ODOM speeds negated). Stamps run on: pass k maps a stamp t to
start_k + (t - t0) forwards or start_k + (t_end - t) backwards. Every relation of the log is repeated in every
pass at the mapped stamps (the relative pose between two scans does not depend on when they were replayed), so
the long log is scored over all of them. For measuring a SLAM's memory and speed over hours of a real building
(plain Python, no dependencies); only ODOM and FLASER lines are kept (PARAM and comments pass through once).
"""
import gzip
import sys


def opener(path, mode):
    return gzip.open(path, mode) if path.endswith(".gz") else open(path, mode)


def main():
    if len(sys.argv) != 6:
        sys.exit(__doc__.strip().splitlines()[2].strip())
    src, rel_src, passes, out, rel_out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
    header, records = [], []
    with opener(src, "rt") as f:
        for line in f:
            fields = line.split()
            if not fields:
                continue
            if fields[0] in ("ODOM", "FLASER"):
                # ipc_timestamp ipc_hostname logger_timestamp close every line
                records.append((float(fields[-3]), fields))
            elif fields[0] in ("PARAM",) or fields[0].startswith("#"):
                header.append(line.rstrip("\n"))
    if not records:
        sys.exit(f"{src}: no ODOM or FLASER lines")
    t0 = min(t for t, _ in records)
    t_end = max(t for t, _ in records)
    span = t_end - t0
    gap = 0.1  # seconds between the last line of a pass and the first of the next
    logger0 = min(float(f[-1]) for _, f in records)

    def stamp(k, t):
        start = t0 + k * (span + gap)
        return start + (t - t0) if k % 2 == 0 else start + (t_end - t)

    with opener(out, "wt") as f:
        for h in header:
            f.write(h + "\n")
        for k in range(passes):
            order = records if k % 2 == 0 else list(reversed(records))
            for t, fields in order:
                g = list(fields)
                s = stamp(k, t)
                g[-3] = f"{s:.6f}"
                g[-1] = f"{logger0 + (s - t0):.6f}"
                if k % 2 == 1 and g[0] == "ODOM":
                    g[4] = f"{-float(g[4]):.6f}"  # tv: the robot drives the path in reverse
                f.write(" ".join(g) + "\n")
    n = 0
    with opener(rel_src, "rt") as f, opener(rel_out, "wt") as o:
        rels = [line.split() for line in f if line.strip() and not line.startswith("#")]
        for k in range(passes):
            for r in rels:
                a, b = stamp(k, float(r[0])), stamp(k, float(r[1]))
                o.write(" ".join([f"{a:.6f}", f"{b:.6f}"] + r[2:]) + "\n")
                n += 1
    print(f"{out}: {passes} passes of {span:.1f} s ({passes * span / 3600:.2f} h), {len(records) * passes} lines; "
          f"{rel_out}: {n} relations")


if __name__ == "__main__":
    main()
