#!/usr/bin/env python3
"""docs/acquisition.md's measured tables from the reports `scripts/acquire-sweep OUT` leaves in
OUT/<scene>/acquire-*/report.json (standard library only).

Table 1: per defect, the fewest patterns K (among those run) at which each method makes it
visible, acquired CNR >= 5 (under the sensor model), in its best channel; beside it the bright
field's CNR through the same sensor (one image) and the best exact-T CNR (today's contrast
table: Monte Carlo noise). MeanX and MeanY are left out of "best channel": they are position
maps, whose contrast is the lens's mapping, not the defect (the deflection map is their
defect-free-subtracted form). Table 2: each method's median |error| per channel at its largest K, over all scenes.
"""
import glob
import json
import math
import os
import sys


ORDER = ["fields", "gray", "stripes", "compressive-w32", "compressive", "compressive-hadamard", "brute-force"]


def num(v):
    if isinstance(v, (int, float)):
        return float(v)
    if v == "inf":
        return math.inf
    return math.nan


def fmt(v):
    if math.isnan(v):
        return "-"
    if math.isinf(v):
        return "inf"
    return f"{v:.3g}"


def main(out):
    reports = []
    for path in sorted(glob.glob(os.path.join(out, "*", "acquire-*", "report.json"))):
        with open(path) as f:
            r = json.load(f)
        r["_scene"] = os.path.basename(os.path.dirname(os.path.dirname(path)))
        r["_name"] = os.path.basename(os.path.dirname(path))[len("acquire-"):]
        reports.append(r)
    methods = sorted({r["_name"] for r in reports}, key=lambda m: ORDER.index(m)
                     if m in ORDER else 99)
    scenes = sorted({r["_scene"] for r in reports})
    print("| scene | defect | bright field CNR (acquired, 1 image) | best exact-T CNR (MC noise) | "
          + " | ".join(f"{m}: fewest K (channel, CNR)" for m in methods) + " |")
    print("|---|---|---|---|" + "---|" * len(methods))
    for scene in scenes:
        rs = {r["_name"]: r for r in reports if r["_scene"] == scene}
        any_r = next(iter(rs.values()))
        ndef = len(any_r["runs"][0]["defects"])
        for d in range(ndef):
            first = any_r["runs"][0]["defects"][d]
            bright = num(first["bright_field"]["acquired"])
            exact_best, exact_ch = -1.0, ""
            cells = []
            for m in methods:
                r = rs.get(m)
                if r is None:
                    cells.append("not run")
                    continue
                best = None
                for run in r["runs"]:
                    dd = run["defects"][d]
                    for ch, c in dd["channels"].items():
                        if ch in ("MeanX", "MeanY"):
                            continue
                        e = num(c["exact"])
                        if not math.isnan(e) and e > exact_best:
                            exact_best, exact_ch = e, ch
                        s = num(c["acquired"])
                        if s >= r["visible_cnr"] and (best is None or run["patterns"] < best[0]
                                                      or (run["patterns"] == best[0] and s > best[2])):
                            best = (run["patterns"], ch, s)
                cells.append(f"{best[0]} ({best[1]}, {fmt(best[2])})" if best else
                             f"not visible up to K = {r['runs'][-1]['patterns']}")
            print(f"| {scene} | {first['defect']} ({first['label']}) | {fmt(bright)} | "
                  f"{fmt(exact_best)} ({exact_ch}) | " + " | ".join(cells) + " |")
    print()
    print("| method | K | channel | median abs error | 95th percentile | relative RMS error |")
    print("|---|---|---|---|---|---|")
    for m in methods:
        rs = [r for r in reports if r["_name"] == m]
        if not rs:
            continue
        last = {}
        for r in rs:
            run = r["runs"][-1]
            for ch, e in run["errors"].items():
                last.setdefault(ch, []).append((run["patterns"], num(e["median_abs_error"]), num(e["p95_abs_error"]),
                                                num(e["relative_rmse"])))
        for ch, vals in last.items():
            k = vals[0][0]
            med = sorted(v[1] for v in vals)[len(vals) // 2]
            p95 = sorted(v[2] for v in vals)[len(vals) // 2]
            rel = sorted(v[3] for v in vals)[len(vals) // 2]
            print(f"| {m} | {k} | {ch} | {fmt(med)} | {fmt(p95)} | {fmt(rel)} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out/paper")
