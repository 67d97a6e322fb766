#!/usr/bin/env python3
"""Plots `benchmark dynamic --curves CSV`: per event, the ghost left by each mapper as a share of
the voxels (cells) the object held, over the frames after it has gone.

Usage: plot_dynamic_scenes.py <curves.csv> <out.png> [--resolution R] [--speed S]
"""
import argparse
import collections
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("curves")
    parser.add_argument("out")
    parser.add_argument("--resolution", type=float, default=0.05)
    parser.add_argument("--speed", type=float, default=0.0)
    args = parser.parse_args()
    series = collections.defaultdict(list)  # (event, mapper) -> [(frame, share)]
    with open(args.curves, newline="") as handle:
        for row in csv.DictReader(handle):
            if abs(float(row["resolution"]) - args.resolution) > 1e-9:
                continue
            if abs(float(row["speed"]) - args.speed) > 1e-9:
                continue
            held = int(row["object_voxels"])
            if held == 0:
                continue
            share = int(row["ghost"]) / held
            series[(row["event"], row["mapper"])].append((int(row["frames_without_object"]), share))
    events = sorted({event for event, _ in series})
    # One colour per mapper in every panel (a panel may lack a mapper that mapped nothing).
    mappers = sorted({mapper for _, mapper in series})
    colours = {mapper: f"C{i}" for i, mapper in enumerate(mappers)}
    figure, axes = plt.subplots(1, len(events), figsize=(5 * len(events), 4), squeeze=False)
    for axis, event in zip(axes[0], events):
        for (line_event, mapper), points in sorted(series.items()):
            if line_event != event:
                continue
            axis.plot([p[0] for p in points], [p[1] for p in points], label=mapper,
                      color=colours[mapper])
        axis.axhline(0.05, color="grey", linestyle="--", linewidth=0.8)
        axis.axvline(5, color="grey", linestyle=":", linewidth=0.8)
        axis.set_title(f"{event}, {args.resolution} m, {args.speed} m/s")
        axis.set_xlabel("frames after the object has gone")
        axis.set_ylabel("ghost / object's voxels")
        axis.set_ylim(0, 1.3)
        axis.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(args.out, dpi=90)


if __name__ == "__main__":
    main()
