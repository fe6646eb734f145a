#!/usr/bin/env python3
"""`mrslam merge` and OpenCV's SIFT merge side by side on the same map pairs: the issue's speed check.

setup: python3 -m pip install opencv-python-headless pillow numpy pyyaml
usage: merge_vs_opencv.py --mrslam target/release/mrslam [--runs 3] [--threads 1] [--algorithm cascade]
                          [--opencv-cold] A1.yaml B1.yaml [A2.yaml B2.yaml ...]

Per pair, one after the other: `mrslam merge A B` --runs times (the report's `time_ms`: the merge itself, maps
already read) and `opencv_merge.py A B --runs R --threads T` (detect+compute, ratio test, RANSAC; its median
total). Prints one line per pair (sizes, both medians, the ratio, the stage that decided) and the median ratio.

Each `mrslam merge` is a fresh process: its memory is touched for the first time, which on a VM costs up to
half of a merge. OpenCV's runs share one process, so all but its first reuse memory already touched. With
--opencv-cold, every OpenCV run is a fresh process too (`--runs 1`, R times): both tools measured as a user
runs them on one pair.
"""
import argparse, json, os, re, statistics, subprocess, sys, tempfile

p = argparse.ArgumentParser()
p.add_argument("maps", nargs="+")
p.add_argument("--mrslam", required=True)
p.add_argument("--runs", type=int, default=3)
p.add_argument("--threads", type=int, default=1)
p.add_argument("--algorithm", default="cascade")
p.add_argument("--opencv-cold", action="store_true")
args = p.parse_args()
if len(args.maps) % 2:
    sys.exit("maps come in pairs: A1 B1 A2 B2 ...")
here = os.path.dirname(os.path.abspath(__file__))
ratios = []
print(f"{'pair':<52} {'mrslam ms':>10} {'opencv ms':>10} {'ratio':>6}  decided by")
with tempfile.TemporaryDirectory() as tmp:
    for a, b in zip(args.maps[::2], args.maps[1::2]):
        times, stage, accepted = [], "", False
        for _ in range(args.runs):
            report = os.path.join(tmp, "r.json")
            subprocess.run([args.mrslam, "merge", a, b, "-o", os.path.join(tmp, "m.yaml"), "--report", report,
                            "--algorithm", args.algorithm], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            r = json.load(open(report))
            times.append(r["time_ms"])
            stage, accepted = r.get("stage") or r.get("algorithm", ""), r.get("accepted", False)
        cv_runs = [1] * args.runs if args.opencv_cold else [args.runs]
        cv = statistics.median(
            float(re.search(r"total ([0-9.]+)", subprocess.run(
                [sys.executable, os.path.join(here, "opencv_merge.py"), a, b, "--runs", str(n), "--threads",
                 str(args.threads)], capture_output=True, text=True, check=True).stdout).group(1))
            for n in cv_runs)
        ours = statistics.median(times)
        ratios.append(ours / cv)
        short = lambda m: os.path.join(os.path.basename(os.path.dirname(os.path.abspath(m))), os.path.basename(m))
        name = f"{short(a)} {short(b)}"
        verdict = stage if accepted else f"refused ({stage})"
        print(f"{name:<52} {ours:>10.1f} {cv:>10.1f} {ours / cv:>6.2f}  {verdict}", flush=True)
how = "a fresh process per run" if args.opencv_cold else "its runs in one process"
print(f"median ratio {statistics.median(ratios):.2f} over {len(ratios)} pairs (OpenCV on {args.threads} thread(s), {how})")
