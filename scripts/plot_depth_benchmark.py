#!/usr/bin/env python3
"""Draws `benchmark depth` output: milliseconds per frame against the voxel size for this package,
liboctomap's insertPointCloud (plain and discretized) and each peer compiled in, with the goals
(10x liboctomap discretized, 5x the fastest peer) as dashed lines and each ratio written beside
this package's points.

Usage: plot_depth_benchmark.py BENCHMARK_OUTPUT OUTPUT_PNG
(BENCHMARK_OUTPUT: what `benchmark depth <folder> --resolution R,... [--peer-frames P]` printed;
its "depth resolution=..." lines are read.)
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after choosing the headless backend)
from matplotlib.ticker import NullFormatter  # noqa: E402

PEER_LABELS = {"bonxai": "Bonxai", "ufomap_discrete": "UFOMap (discrete)"}


def read_rows(path):
    """One dict of key -> text per "depth resolution=..." line."""
    rows = []
    with open(path) as source:
        for line in source:
            if not line.startswith("depth resolution="):
                continue
            fields = dict(item.split("=", 1) for item in line.split()[1:] if "=" in item)
            rows.append(fields)
    return rows


def column(rows, key):
    """(resolutions, values) of the rows with a positive value for key."""
    points = [(float(r["resolution"]), float(r[key])) for r in rows if float(r.get(key, 0)) > 0]
    return [p[0] for p in points], [p[1] for p in points]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    rows = sorted(read_rows(sys.argv[1]), key=lambda r: float(r["resolution"]))
    if not rows:
        sys.exit("plot_depth_benchmark.py: no 'depth resolution=' lines in %s" % sys.argv[1])
    peers = [key[: -len("_ms_per_frame")] for key in rows[0]
             if key.endswith("_ms_per_frame") and key not in
             ("ms_per_frame", "octomap_ms_per_frame", "octomap_discretize_ms_per_frame",
              "cpu_ms_per_frame")]
    figure, axes = plt.subplots(figsize=(8, 5.5))
    x, ours = column(rows, "ms_per_frame")
    axes.plot(x, ours, "o-", color="tab:blue", linewidth=2.5, label="occupancy_fusion (pyramid)")
    for key, label, style in (("octomap_ms_per_frame", "liboctomap", "s:"),
                              ("octomap_discretize_ms_per_frame", "liboctomap, discretize", "s-")):
        xs, ys = column(rows, key)
        if xs:
            axes.plot(xs, ys, style, color="tab:gray", label=label)
    colors = ["tab:green", "tab:orange", "tab:purple", "tab:brown"]
    fastest_peer = {}
    for peer, color in zip(peers, colors):
        xs, ys = column(rows, peer + "_ms_per_frame")
        axes.plot(xs, ys, "^-", color=color, label=PEER_LABELS.get(peer, peer))
        for r, y in zip(xs, ys):
            fastest_peer[r] = min(y, fastest_peer.get(r, float("inf")))
    xs, ys = column(rows, "octomap_discretize_ms_per_frame")
    if xs:
        axes.plot(xs, [y / 10 for y in ys], "--", color="tab:gray",
                  label="goal: 10x liboctomap, discretize")
    if fastest_peer:
        rs = sorted(fastest_peer)
        axes.plot(rs, [fastest_peer[r] / 5 for r in rs], "--", color="tab:green",
                  label="goal: 5x the fastest peer")
    for row in rows:
        ratio = float(row.get("speedup_discretize", 0))
        if ratio > 0:
            axes.annotate("%.1fx" % ratio, (float(row["resolution"]), float(row["ms_per_frame"])),
                          textcoords="offset points", xytext=(8, 4), color="tab:blue")
    axes.set_xscale("log")
    axes.set_yscale("log")
    axes.set_xticks([float(r["resolution"]) for r in rows])
    axes.set_xticklabels([r["resolution"] for r in rows])
    axes.xaxis.set_minor_formatter(NullFormatter())
    axes.set_xlabel("voxel size [m]")
    axes.set_ylabel("ms per frame (median)")
    axes.set_title("Depth images, %s frames, %s threads: time per frame"
                   % (rows[0].get("frames", "?"), rows[0].get("threads", "?")))
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
