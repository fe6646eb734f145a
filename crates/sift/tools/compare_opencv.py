#!/usr/bin/env python3
"""Compares mrslam-sift keypoints with OpenCV's (both JSON lists of {x,y,size,angle,response,octave,descriptor}).

usage: compare_opencv.py OURS.json OPENCV.json [--px 1.0] [--size-tol 0.2]

Prints the share of OpenCV keypoints that have one of ours within --px pixels and --size-tol relative size
(and the reverse), the share of those whose angle also agrees within 5 degrees, and the mean L2 distance
between matched descriptors (0..~512 scale; unrelated SIFT descriptors are typically 400+ apart).
"""
import argparse, json, math
import numpy as np

p = argparse.ArgumentParser()
p.add_argument("ours"); p.add_argument("opencv")
p.add_argument("--px", type=float, default=1.0); p.add_argument("--size-tol", type=float, default=0.2)
a = p.parse_args()
ours = json.load(open(a.ours)); cv = json.load(open(a.opencv))


def arr(kps):
    if not kps:
        return np.zeros((0, 4)), np.zeros((0, 128))
    return (np.array([[k["x"], k["y"], k["size"], k["angle"]] for k in kps], dtype=np.float64),
            np.array([k["descriptor"] for k in kps], dtype=np.float64))


A, DA = arr(ours); B, DB = arr(cv)


def match(P, Q, DP, DQ):
    """For each row of P: best row of Q within px and size tolerance (angle-aware), or -1."""
    if len(Q) == 0:
        return np.full(len(P), -1)
    order = np.argsort(Q[:, 0]); Qs = Q[order]; xs = Qs[:, 0]
    best = np.full(len(P), -1)
    for i, (x, y, s, ang) in enumerate(P):
        lo, hi = np.searchsorted(xs, x - a.px), np.searchsorted(xs, x + a.px, side="right")
        if lo == hi:
            continue
        c = Qs[lo:hi]
        ok = (np.hypot(c[:, 0] - x, c[:, 1] - y) <= a.px) & (np.abs(c[:, 2] - s) <= a.size_tol * s)
        if not ok.any():
            continue
        idx = np.nonzero(ok)[0]
        dang = np.abs((c[idx, 3] - ang + 180) % 360 - 180)
        best[i] = order[lo + idx[np.argmin(dang)]]
    return best


m_cv = match(B, A, DB, DA)
m_ours = match(A, B, DA, DB)
hit = m_cv >= 0
n_cv, n_ours = len(B), len(A)
print(f"keypoints: opencv {n_cv}, ours {n_ours}")
if n_cv:
    print(f"opencv keypoints with one of ours within {a.px} px and {a.size_tol:.0%} size: "
          f"{hit.sum()}/{n_cv} = {100 * hit.mean():.1f}%")
if n_ours:
    print(f"our keypoints with an opencv one within {a.px} px and {a.size_tol:.0%} size: "
          f"{(m_ours >= 0).sum()}/{n_ours} = {100 * (m_ours >= 0).mean():.1f}%")
if hit.any():
    i = np.nonzero(hit)[0]; j = m_cv[i]
    dang = np.abs((B[i, 3] - A[j, 3] + 180) % 360 - 180)
    dd = np.linalg.norm(DB[i] - DA[j], axis=1)
    print(f"of the matched: angle within 5 deg {100 * (dang <= 5).mean():.1f}%, "
          f"descriptor L2 distance median {np.median(dd):.1f}, mean {dd.mean():.1f}")
