#!/usr/bin/env python3
"""Two runs of one study compared trial by trial: every column of results.csv but the wall time. Prints the trials
that differ (and in which columns) and how many are the same.

    python3 dev/scripts/compare_study_results.py benchmarks/studies/team_fr079/results.csv OUT/results.csv
"""
import csv
import sys


def main(a_path, b_path):
    a = {r["trial"]: r for r in csv.DictReader(open(a_path))}
    b = {r["trial"]: r for r in csv.DictReader(open(b_path))}
    same = differ = 0
    for trial, row in sorted(b.items(), key=lambda t: int(t[0])):
        if trial not in a:
            continue
        columns = [k for k in row if k != "wall_s" and row[k] != a[trial].get(k)]
        if columns:
            differ += 1
            shown = [(k, a[trial].get(k, "")[:40], row[k][:40]) for k in columns if k != "coverage_curve"]
            curve = " (coverage curve differs)" if "coverage_curve" in columns else ""
            print(f"trial {trial} (n {row.get('n')}, {row.get('coordination')}, seed {row.get('seed')}): {shown}{curve}")
        else:
            same += 1
    print(f"{same} trials the same, {differ} differ, {len(b) - same - differ} only in {b_path}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
