#!/usr/bin/env python3
"""Plots `benchmark loop-closure --curves CSV` and puts its `--grids PREFIX` pictures side by side.

Usage: plot_loop_closure.py <curves.csv> <grids prefix> <out.png> [--corrections F,F,...]
The curves: false-occupied voxels and projected_map's agreement with the true-pose map (strict
IoU and within one cell) over the frames, one line per mapping, the corrections as dashed lines;
below them the four projected maps (without submaps, re-anchored by path and by tf, true poses).
"""
import argparse
import csv
import collections

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

MAPPINGS = ["without_submaps", "reanchored_path", "reanchored_tf", "true_poses"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("curves")
    parser.add_argument("grids")
    parser.add_argument("out")
    parser.add_argument("--corrections", default="")
    args = parser.parse_args()
    rows = collections.defaultdict(list)
    with open(args.curves) as f:
        for row in csv.DictReader(f):
            rows[row["mapping"]].append(row)
    corrections = [int(x) for x in args.corrections.split(",") if x]
    figure = plt.figure(figsize=(14, 8))
    grid = figure.add_gridspec(2, 12, height_ratios=[1, 1.1])
    panels = [("false_occupied", "false-occupied voxels"),
              ("projected_iou", "projected_map IoU with true poses"),
              ("projected_within_one_cell", "... within one cell")]
    for column, (key, title) in enumerate(panels):
        axes = figure.add_subplot(grid[0, 4 * column:4 * column + 4])
        for mapping in MAPPINGS:
            frames = [int(r["frame"]) for r in rows[mapping]]
            values = [float(r[key]) for r in rows[mapping]]
            axes.plot(frames, values, label=mapping)
        for frame in corrections:
            axes.axvline(frame, color="grey", linestyle="--", linewidth=0.8)
        axes.set_title(title)
        axes.set_xlabel("frame")
        if column == 0:
            axes.legend(fontsize=8)
    for column, mapping in enumerate(MAPPINGS):
        axes = figure.add_subplot(grid[1, 3 * column:3 * column + 3])
        axes.imshow(mpimg.imread(f"{args.grids}_{mapping}.png"), cmap="gray")
        axes.set_title(mapping, fontsize=9)
        axes.axis("off")
    figure.tight_layout()
    figure.savefig(args.out, dpi=80)


if __name__ == "__main__":
    main()
