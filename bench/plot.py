#!/usr/bin/env python3
"""Plots the tracing benchmarks' CSV files (bench_trace, bench_scale --out DIR) as PNG images in DIR.

error_vs_time.png: render time against display-hit error over tessellation levels, with and
without refinement, and the analytic representation. scaling.png: time against paths and the
render's own peak RSS growth against nonzeros (bench_scale).
grin_error_vs_time.png: display-hit error of a TetGen-meshed inclusion against meshing and tracing
time over index tolerances (bench_grin).
Needs Debian's python3-matplotlib.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

folder = sys.argv[1] if len(sys.argv) > 1 else "."

rows = list(csv.DictReader(open(f"{folder}/error_vs_time.csv")))
fig, ax = plt.subplots(figsize=(7, 4.5))
for rep, marker in (("refined", "o"), ("mesh-only", "s"), ("analytic", "*")):
    pts = [r for r in rows if r["representation"] == rep]
    x = [float(r["render_seconds"]) for r in pts]
    y = [max(float(r["max_display_error_mm"]), 1e-16) for r in pts]
    ax.loglog(x, y, marker=marker, linestyle="-" if rep != "analytic" else "", label=rep, markersize=9)
    for r, xi, yi in zip(pts, x, y):
        if rep != "analytic":
            ax.annotate(f'{float(r["chord_tolerance_mm"]):g} mm', (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=7)
ax.set_xlabel("render time, 100 x 100 x 16 spp (s)")
ax.set_ylabel("max display-hit error vs analytic reference (mm)")
ax.set_title("Error against time over tessellation (chord tolerance) levels")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(f"{folder}/error_vs_time.png", dpi=120)

rows = [r for r in csv.DictReader(open(f"{folder}/scaling.csv")) if r["streamed"] == "0"]
fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 4.5))
x = [float(r["paths"]) for r in rows]
y = [float(r["render_seconds"]) for r in rows]
ax.loglog(x, y, "o")
for r, xi, yi in zip(rows, x, y):
    ax.annotate(f'{r["camera_pixels_per_side"]}^2 x {r["samples_per_pixel"]}', (xi, yi), textcoords="offset points",
                xytext=(4, -10), fontsize=7)
ax.set_xlabel("paths")
ax.set_ylabel("render time (s)")
ax.set_title("Time against paths")
ax.grid(True, which="both", alpha=0.3)
n = [float(r["nnz"]) for r in rows]
g = [float(r["rss_growth_bytes"]) / 1e6 for r in rows]
t = [float(r["matrix_bytes"]) / 1e6 for r in rows]
bx.loglog(n, g, "o", label="render's peak RSS growth")
bx.loglog(n, t, "x", label="T's arrays (8 B/nonzero + 8 B/row)")
bx.set_xlabel("nonzeros of T")
bx.set_ylabel("MB")
bx.set_title(f'Memory against nonzeros ({rows[0]["display_pixels_per_side"]}^2 display)')
bx.grid(True, which="both", alpha=0.3)
bx.legend()
fig.tight_layout()
fig.savefig(f"{folder}/scaling.png", dpi=120)

rows = list(csv.DictReader(open(f"{folder}/grin_error_vs_time.csv")))
fig, ax = plt.subplots(figsize=(7, 4.5))
x = [float(r["tetgen_seconds"]) + float(r["trace_seconds"]) for r in rows]
for key, marker, label in (("max_display_error_mm", "o", "largest"), ("mean_display_error_mm", "s", "mean")):
    ax.loglog(x, [float(r[key]) for r in rows], marker=marker, label=f"{label} display-hit error")
for r, xi in zip(rows, x):
    ax.annotate(f'{float(r["index_tolerance"]):g}, {int(r["tetrahedra"]):,} tets', (xi, float(r["max_display_error_mm"])),
                textcoords="offset points", xytext=(4, 4), fontsize=7)
ax.set_xlabel("TetGen + tracing time for 625 rays (s)")
ax.set_ylabel("display-hit error vs GRIN reference (mm)")
ax.set_title("Smooth inclusion (2.5 mm, delta_n 0.02): error against time")
ax.grid(True, which="both", alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(f"{folder}/grin_error_vs_time.png", dpi=120)
