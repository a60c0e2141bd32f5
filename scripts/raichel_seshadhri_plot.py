#!/usr/bin/env python3
"""Log-log plot of the engine comparison (flexiso bench --algorithm
raichel-seshadhri --csv rows.csv): value comparisons per field against the
vertex count, both engines, next to n log2 n and the paper's bound.

usage: scripts/raichel_seshadhri_plot.py rows.csv docs/raichel_seshadhri.png
(needs matplotlib)"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

rows = list(csv.DictReader(open(sys.argv[1])))
out = sys.argv[2]
fig, ax = plt.subplots(figsize=(8.5, 6), dpi=80)
styles = {
    "short-and-fat": ("tab:green", "o"),
    "tall-and-thin": ("tab:red", "s"),
    "volume": ("tab:blue", "^"),
}
for fam, (colour, marker) in styles.items():
    sel = sorted((r for r in rows if r["family"] == fam), key=lambda r: int(r["vertices"]))
    if not sel:
        continue
    n = [int(r["vertices"]) for r in sel]
    rs = [sum(int(r[k]) for k in ("rs_links", "rs_paint", "rs_number", "rs_locate", "rs_arc_sort")) for r in sel]
    tree = [int(r["rs_links"]) + int(r["rs_paint"]) for r in sel]
    csa = [int(r["csa_comparisons"]) for r in sel]
    line = "-" if fam != "volume" else "none"
    ax.plot(n, rs, marker=marker, color=colour, linestyle=line, label=f"RS total, {fam}")
    ax.plot(n, tree, marker=marker, color=colour, linestyle=":" if fam != "volume" else "none",
            mfc="none", label=f"RS tree only (links + painting), {fam}")
    ax.plot(n, csa, marker="x", color=colour, linestyle="--" if fam != "volume" else "none",
            label=f"current engine, {fam}")
    # Theorem 1's bound with constant 1: N + sum over supernodes of log2 l_v,
    # N the mesh's size (7 edges per vertex of the Freudenthal grid).
    bound = [7 * int(r["vertices"]) + float(r["shape_term"]) for r in sel]
    ax.plot(n, bound, color=colour, linestyle="-." if fam != "volume" else "none",
            marker="_" if fam == "volume" else None, markersize=12, linewidth=1.2,
            label=f"paper's bound N + Σ log2 ℓ_v (constant 1), {fam}")
ns = sorted({int(r["vertices"]) for r in rows})
ax.plot(ns, [v * math.log2(v) for v in ns], color="black", label="n log2 n (a comparison sort)")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("vertices n")
ax.set_ylabel("value comparisons")
ax.set_title("Contour tree: value comparisons, Raichel-Seshadhri vs sort + sweeps")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=7, loc="upper left")
fig.tight_layout()
fig.savefig(out)
