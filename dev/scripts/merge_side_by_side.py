#!/usr/bin/env python3
"""`mrslam merge` by several algorithms and OpenCV's SIFT merge at several thread counts, one after the other on
each map pair: the side-by-side speed tables of benchmarks/runs/2026-12-02-merge-speed-vs-opencv.md (sift,
correlative; OpenCV 1 and 2 threads) and 2026-12-02-merge-cascade.md (cascade, correlative, sift; OpenCV 1 thread).

setup: python3 -m pip install opencv-python-headless pillow numpy pyyaml
usage: merge_side_by_side.py --mrslam target/release/mrslam [--algorithms sift,correlative] [--threads 1,2]
                             [--runs 3] A1.yaml B1.yaml [A2.yaml B2.yaml ...]

Per pair, in this order: each algorithm's `mrslam merge A B --algorithm ALG` --runs times (the merge's time, as
its `time:` line prints it: maps already read; the median), then `opencv_merge.py A B --runs R --threads T` for
each T (its median total). Prints a Markdown table: the pair, the maps' sizes, each algorithm's median ms and
verdict (the cascade's deciding stage), OpenCV's median ms and inliers per thread count, and each algorithm's time
over OpenCV's on the first thread count. Under load, compare the ratios of one row, not absolute times.
"""
import argparse, json, os, re, statistics, subprocess, sys, tempfile

p = argparse.ArgumentParser()
p.add_argument("maps", nargs="+")
p.add_argument("--mrslam", required=True)
p.add_argument("--algorithms", default="sift,correlative")
p.add_argument("--threads", default="1,2")
p.add_argument("--runs", type=int, default=3)
args = p.parse_args()
if len(args.maps) % 2:
    sys.exit("maps come in pairs: A1 B1 A2 B2 ...")
algorithms = [a for a in args.algorithms.split(",") if a]
threads = [int(t) for t in args.threads.split(",") if t]
here = os.path.dirname(os.path.abspath(__file__))


def size(yaml_path):
    """The map image's width x height, read from the PGM or PNG the YAML names."""
    from PIL import Image
    image = next(l.split(":", 1)[1].strip().strip("'\"") for l in open(yaml_path) if l.startswith("image:"))
    path = image if os.path.isabs(image) else os.path.join(os.path.dirname(os.path.abspath(yaml_path)), image)
    w, h = Image.open(path).size
    return f"{w}x{h}"


def mrslam(a, b, algorithm, tmp):
    """Median merge time (ms) over --runs runs, and the verdict."""
    times, verdict = [], ""
    for _ in range(args.runs):
        report = os.path.join(tmp, "r.json")
        subprocess.run([args.mrslam, "merge", a, b, "-o", os.path.join(tmp, "m.yaml"), "--report", report,
                        "--algorithm", algorithm], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        r = json.load(open(report))
        times.append(r["time_ms"])
        stage = r.get("stage") or r.get("algorithm", algorithm)
        verdict = f"accepted ({stage})" if r.get("accepted") else "refused"
    return statistics.median(times), verdict


def opencv(a, b, t):
    """OpenCV's median total (ms) over --runs runs in one process, and its RANSAC inliers."""
    out = subprocess.run([sys.executable, os.path.join(here, "opencv_merge.py"), a, b, "--runs", str(args.runs),
                          "--threads", str(t)], capture_output=True, text=True, check=True).stdout
    return float(re.search(r"total ([0-9.]+)", out).group(1)), int(re.search(r"([0-9]+) inliers", out).group(1))


heads = [f"mrslam {a}" for a in algorithms] + [f"OpenCV {t} thr" for t in threads]
heads += [f"{a} / OpenCV ({threads[0]} thr)" for a in algorithms] if threads else []
print("| pair | sizes (px) | " + " | ".join(heads) + " |")
print("|---" * (2 + len(heads)) + "|")
with tempfile.TemporaryDirectory() as tmp:
    for a, b in zip(args.maps[::2], args.maps[1::2]):
        ours = [mrslam(a, b, alg, tmp) for alg in algorithms]
        theirs = [opencv(a, b, t) for t in threads]
        cells = [f"{ms:.0f} ms, {v}" for ms, v in ours] + [f"{ms:.0f} ms, {n} inliers" for ms, n in theirs]
        cells += [f"{ms / theirs[0][0]:.2f}" for ms, _ in ours] if theirs else []
        name = f"{os.path.basename(a)} {os.path.basename(b)}"
        print(f"| {name} | {size(a)}, {size(b)} | " + " | ".join(cells) + " |", flush=True)
