#!/usr/bin/env python3
"""Markdown table of `mrslam slam --summary` files in a folder (dev/scripts/slam_seeds.sh writes them)."""
import json
import statistics
import sys
from pathlib import Path

rows = {}
for p in sorted(Path(sys.argv[1]).glob("*.json")):
    s = json.loads(p.read_text())
    m = s.get("metric") or {}
    key = (Path(s["log"]).name.split(".")[0], s["preset"])
    rows.setdefault(key, []).append((s["seed"], m, s))
print("| log | preset | seed | translation m | rotation deg | relations | real time | peak MiB | loops kept / searched | open "
      "| contradicted / judged | searches everywhere (kept) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for (log, preset), runs in sorted(rows.items()):
    for seed, m, s in sorted(runs, key=lambda r: r[0]):
        t = {"mean": m.get("translation_mean_m", float("nan"))}
        r = {"mean": m.get("rotation_mean_deg", float("nan"))}
        lc = s.get("loop_closure") or {}
        print(f"| {log} | {preset} | {seed} | {t.get('mean', float('nan')):.4f} | {r.get('mean', float('nan')):.3f} | "
              f"{m.get('used', '?')} ({m.get('missing', '?')} missing) | {s['real_time_factor']:.1f}x | "
              f"{(s.get('peak_memory_bytes') or 0) / 2**20:.0f} | {lc.get('closures', '-')} / {lc.get('candidates', '-')} | "
              f"{lc.get('open_loops', '-')} | {lc.get('contradicted', '-')} / {lc.get('judged', '-')}"
              f"{' **flagged**' if lc.get('contradicts_itself') else ''} | "
              f"{lc.get('relocalisations', '-')} ({lc.get('relocalised', '-')}) |")
    ts = [m.get("translation_mean_m", float("nan")) for _, m, _ in runs]
    med = statistics.median(ts)
    print(f"| {log} | {preset} | median | {med:.4f} | | | | | | worst/median {max(ts) / med:.2f} | | |")
