#!/usr/bin/env python3
"""Records what a build of mrslam produces, and compares two records: a refactoring must change nothing.

    dev/scripts/same_behaviour.py record BIN OUT [--only GROUP[,GROUP]] [--data ../shared/data]
    dev/scripts/same_behaviour.py compare BASE NEW [--rrd-diff BIN]

Groups: `scenarios` (the four shipped scenarios, with their .rrd), `slam` (ACES, FR079 and Intel at seed 0:
map, trajectory, summary), `studies` (`study logs` ACES in 2 parts, a small map-level `study overlap` with
every algorithm). `compare` checks maps and trajectories byte for byte, JSON and CSV files with every wall-time
field removed (studies' plots, which show times, are skipped), and recordings with `rrd_diff` (the dev crate's binary) when given; it prints each difference and
exits 1 when there is one.
"""

import argparse
import csv
import io
import json
import pathlib
import subprocess
import sys
import time

REPO = pathlib.Path(__file__).resolve().parents[2]
SCENARIOS = ["paper_corridor", "paper_two_rooms", "explore_two_rooms", "fr079_two_robots"]
LOGS = ["aces", "fr079", "intel"]


def run(cmd, log):
    """Runs one command, its output appended to `log`; a non-zero exit other than 2 (a refused merge) stops."""
    t = time.time()
    with open(log, "a") as f:
        f.write("$ " + " ".join(map(str, cmd)) + "\n")
        f.flush()
        rc = subprocess.call([str(c) for c in cmd], stdout=f, stderr=subprocess.STDOUT, cwd=REPO)
    print(f"  {time.time() - t:6.1f} s  exit {rc}  {' '.join(map(str, cmd[1:4]))}", flush=True)
    if rc not in (0, 2):
        sys.exit(f"failed (exit {rc}): {' '.join(map(str, cmd))}; see {log}")


def record(args):
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    data = pathlib.Path(args.data).resolve()
    bin_ = pathlib.Path(args.bin).resolve()
    log = out / "commands.log"
    groups = args.only.split(",") if args.only else ["scenarios", "slam", "studies"]
    if "scenarios" in groups:
        for s in SCENARIOS:
            d = out / "scenarios" / s
            d.mkdir(parents=True, exist_ok=True)
            run([bin_, "run", f"scenarios/{s}.toml", "--out", d, "--algorithm", "all", "--rrd", d / "run.rrd"], log)
    if "slam" in groups:
        d = out / "slam"
        d.mkdir(parents=True, exist_ok=True)
        for name in LOGS:
            run([bin_, "slam", data / "logs" / f"{name}.clf.gz", "-o", d / f"{name}.yaml", "--trajectory",
                 d / f"{name}.txt", "--relations", data / "logs" / f"{name}.relations", "--summary",
                 d / f"{name}.json", "--seed", "0"], log)
    if "studies" in groups:
        d = out / "studies"
        d.mkdir(parents=True, exist_ok=True)
        run([bin_, "study", "logs", data / "logs" / "aces.clf.gz", "--relations", data / "logs" / "aces.relations",
             "--parts", "2", "--algorithms", "sift,rmap,correlative,cascade", "--out", d / "aces-2", "--quiet"], log)
        run([bin_, "study", "overlap", "--floorplans", "2", "--overlaps", "0.1:0.5:0.2", "--trials", "3",
             "--algorithms", "sift,rmap,correlative,cascade", "--seed", "7", "--out", d / "overlap", "--quiet"], log)


TIME_WORDS = ("time", "_ms", "ms_per", "seconds", "wall", "elapsed", "duration_s", "real_time", "speed", "peak_memory")


def is_time(name):
    """Whether a JSON key or CSV column holds a wall time or a memory figure (differs between two runs)."""
    name = name.lower()
    return any(w in name for w in TIME_WORDS) or name.endswith("_s")


def strip_times(v):
    """The JSON value with every field whose name speaks of wall time or memory removed."""
    if isinstance(v, dict):
        return {k: strip_times(x) for k, x in v.items() if not is_time(k)}
    if isinstance(v, list):
        return [strip_times(x) for x in v]
    return v


def csv_rows(path):
    rows = list(csv.reader(io.StringIO(path.read_text())))
    if not rows:
        return rows
    keep = [i for i, h in enumerate(rows[0]) if not is_time(h)]
    return [[r[i] for i in keep if i < len(r)] for r in rows]


def compare(args):
    base, new = pathlib.Path(args.base), pathlib.Path(args.new)
    problems = []
    files = sorted(p.relative_to(base) for p in base.rglob("*") if p.is_file() and p.name != "commands.log")
    for rel in files:
        a, b = base / rel, new / rel
        if not b.exists():
            problems.append(f"{rel}: missing in {new}")
            continue
        if rel.suffix == ".json":
            ja, jb = strip_times(json.loads(a.read_text())), strip_times(json.loads(b.read_text()))
            if ja != jb:
                problems.append(f"{rel}: JSON differs (wall times aside)")
        elif rel.suffix == ".csv":
            if csv_rows(a) != csv_rows(b):
                problems.append(f"{rel}: CSV differs (wall-time columns aside)")
        elif rel.name == "plot.png":
            continue  # a study's plot shows merge times; its numbers are in the CSV files compared
        elif rel.suffix == ".rrd":
            if args.rrd_diff:
                r = subprocess.run([args.rrd_diff, a, b], capture_output=True, text=True)
                if r.returncode != 0:
                    problems.append(f"{rel}: recordings differ: {r.stdout.strip()} {r.stderr.strip()}")
        elif a.read_bytes() != b.read_bytes():
            problems.append(f"{rel}: bytes differ")
    for p in problems:
        print(p)
    print(f"{len(files)} files compared, {len(problems)} differ")
    sys.exit(1 if problems else 0)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    r.add_argument("bin")
    r.add_argument("out")
    r.add_argument("--only")
    r.add_argument("--data", default=str(REPO.parent / "shared" / "data"))
    c = sub.add_parser("compare")
    c.add_argument("base")
    c.add_argument("new")
    c.add_argument("--rrd-diff")
    a = ap.parse_args()
    record(a) if a.cmd == "record" else compare(a)


if __name__ == "__main__":
    main()
