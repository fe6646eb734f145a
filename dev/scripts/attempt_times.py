#!/usr/bin/env python3
"""Every online merge attempt of one or more runs (their report.json): when, which robots, how much each team's map
knew, the stage that decided, the verdict, the attempt's time and each stage's; then the median over all of them.

    mrslam run scenarios/team_fr079.toml --out OUT --quiet
    python3 dev/scripts/attempt_times.py OUT/report.json [MORE/report.json ...]

The times are wall times in the run (the robots' SLAMs wait for the attempt): run it on an idle machine.
"""
import json
import statistics
import sys


def main(paths):
    print("| run | at | robots | known m² | decided by | accepted / correct | time | sift / sift+boundary / correlative |")
    print("|---|---|---|---|---|---|---|---|")
    times = []
    for path in paths:
        for a in json.load(open(path))["team"]["attempts"]:
            verdict = "yes / yes" if a["correct"] else ("yes / **no**" if a["accepted"] else "no")
            known = " / ".join(f"{k:.0f}" for k in a["known_m2"])
            st = a.get("stage_ms", {})
            stages = " / ".join(f"{st[k]:.0f}" if k in st else "-" for k in ("sift", "sift+boundary", "correlative"))
            print(f"| {path} | {a['time_s']:.0f} s | {' and '.join(a['robots'])} | {known} | {a['stage']} | {verdict} "
                  f"| {a['time_ms']:.0f} ms | {stages} ms |")
            times.append(a["time_ms"])
    if times:
        print(f"\n{len(times)} attempts, median {statistics.median(times):.0f} ms, range {min(times):.0f}-{max(times):.0f} ms")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
