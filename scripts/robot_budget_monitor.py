#!/usr/bin/env python3
"""Measures a running robot-budget graph (scripts/robot_budget.sh): per sensor topic the frames
sent, integrated and dropped, and the latency from each frame's stamp to the arrival here of the
first projected_map that holds it (the MapServer's projected_map_stamps lists the frames each
grid holds that the one before did not); the mapping manager's and the player's CPU share of the
machine's cores.

The measurement keeps off the cores it measures: the frames sent are read from the bag after the
run (the stamps in each message's std_msgs/Header, read from the raw bytes) rather than by
subscribing to the images here, and the bag's time comes from this node's wall clock less the
player's offset, the smallest (wall arrival - /clock) seen once the player has settled (from
the last second of the warm-up on), so that the player's /clock may run at 100 Hz without
rounding the latencies to its period. (The player's first /clock messages run up to 100 ms ahead
of its later ones: the smallest offset over the whole run took one of them, and every latency
was 100 ms too long.) (Images received in Python and a 1 kHz
/clock delivered to every node took about a third of 2 cores before.) A latency is that bag time
at the grid's arrival minus the frame's stamp.

That latency includes what the graph adds before any mapper sees a frame: the player's lag
behind its own /clock and the transport. For the topics given as --lag-topic this node also
receives each frame, or a small message the bag holds beside it with the same stamp (an image's
camera_info: TOPIC=PROXY), and splits the latency: the player's lag (the arrival here, in the
bag's time, minus the stamp) and the mapping's share (the grid's arrival minus the frame's, both
on this node's wall clock).

Writes a CSV with one row per window (--window s): per topic the frames sent, the median and the
99th percentile latency of the frames stamped in it; the processes' CPU share. Prints a summary.

Usage: robot_budget_monitor.py --duration S --warmup S --csv FILE --summary FILE
       --player-pid PID --bag BAG [--manager NAME] --topic TOPIC [--topic TOPIC]...
       [--lag-topic TOPIC[=PROXY]]...
"""

import argparse
import bisect
import csv
import os
import struct
import threading
import time

import rosbag
import rospy
from graph_probe import Diagnostics, cpu_seconds, node_pid
from occupancy_fusion.msg import IntegratedStamps
from rosgraph_msgs.msg import Clock

# The mappers' diagnostics task of each sensor topic's frames.
TASKS = {"depth": "depth mapping", "disparity": "disparity mapping", "scan": "laser mapping"}
STAMP_TOLERANCE_S = 1e-6  # the mappers keep stamps as double seconds


def header_stamp(raw):
    """The stamp of a serialised message whose first field is a std_msgs/Header (seq, secs, nsecs)."""
    secs, nsecs = struct.unpack_from("<II", raw, 4)
    return secs + nsecs * 1e-9


def busy_and_total_ticks():
    """The machine's CPU ticks (all cores) spent busy, and in all, from /proc/stat."""
    with open("/proc/stat") as stat:
        fields = [int(v) for v in stat.readline().split()[1:]]
    idle = fields[3] + fields[4]  # idle, iowait
    return sum(fields) - idle, sum(fields)


def percentile(values, fraction):
    """The value of rank fraction * (n - 1), nearest rank; None without values."""
    if not values:
        return None
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(fraction * (len(ordered) - 1))))]


def sent_stamps(bag_path, topics):
    """Per topic the header stamps of the bag's messages on it."""
    stamps = {topic: [] for topic in topics}
    with rosbag.Bag(bag_path) as bag:
        for topic, raw, _ in bag.read_messages(topics=topics, raw=True):
            stamps[topic].append(header_stamp(raw[1]))
    return stamps


class Recorder:
    """The grids' arrivals with what each held, the player's clock offset and the arrivals of the
    lag topics' frames."""

    def __init__(self, lag_topics=()):
        """lag_topics: (sensor topic, the topic received here for its frames' arrivals)."""
        self.lock = threading.Lock()
        self.offset = None  # wall - bag time, its smallest sample since settle()
        self.startup_offset = None  # the same before settle(), for the bag's time until then
        self.settled = False
        self.grids = []  # (bag time of arrival, {topic: newest stamp held})
        # sensor topic: {stamp: wall arrival}
        self.frame_arrivals = {topic: {} for topic, _ in lag_topics}
        self.diagnostics = Diagnostics()
        for topic, received in lag_topics:
            rospy.Subscriber(received, rospy.AnyMsg, self.on_frame, callback_args=topic,
                             queue_size=100)
        rospy.Subscriber("/clock", Clock, self.on_clock, queue_size=10)
        rospy.Subscriber("projected_map_stamps", IntegratedStamps, self.on_grid, queue_size=50)
        # The outputs a planner and rviz read, watched so that the MapServer builds them.
        self.outputs = [rospy.Subscriber(topic, rospy.AnyMsg, lambda _: None, queue_size=1)
                        for topic in ("projected_map", "occupied_cells_vis_array")]

    def on_clock(self, message):
        offset = time.time() - message.clock.to_sec()
        with self.lock:
            if not self.settled:
                if self.startup_offset is None or offset < self.startup_offset:
                    self.startup_offset = offset
            elif self.offset is None or offset < self.offset:
                self.offset = offset

    def settle(self):
        """Takes the player's offset from the /clock messages arriving from now on."""
        with self.lock:
            self.settled = True

    def bag_time(self, wall=None):
        """The bag's time at a wall time (now by default)."""
        with self.lock:
            offset = self.offset if self.offset is not None else self.startup_offset
        if offset is None:  # before the first /clock: the ROS clock, rounded to its period
            return rospy.get_rostime().to_sec()
        return (time.time() if wall is None else wall) - offset

    def on_frame(self, message, topic):
        arrival = time.time()
        stamp = header_stamp(message._buff)
        with self.lock:
            self.frame_arrivals[topic].setdefault(stamp, arrival)

    def on_grid(self, message):
        arrival = time.time()
        listed = [(source, stamp.to_sec()) for source, stamp in zip(message.sources, message.stamps)]
        with self.lock:
            self.grids.append((arrival, listed))

    def counts(self, task):
        return self.diagnostics.task(task)


def latencies(sent, grids, topic):
    """Per frame stamp: seconds from the stamp to the arrival of the grid that lists it (the first
    projected_map holding it); None for a frame no grid lists (dropped before integration)."""
    listed = sorted((stamp, arrival) for arrival, frames in grids
                    for source, stamp in frames if source == topic)
    stamps = [stamp for stamp, _ in listed]
    result = {}
    for stamp in sent:
        index = bisect.bisect_left(stamps, stamp - STAMP_TOLERANCE_S)
        found = index < len(stamps) and stamps[index] <= stamp + STAMP_TOLERANCE_S
        result[stamp] = listed[index][1] - stamp if found else None
    return result


def lag_lines(recorder, grids, sent, lag_topics):
    """Per lag topic: the player's lag (the frames' arrival here, in the bag's time, minus their
    stamps) and the mapping's share of the latency (the grid's arrival minus the frame's, both on
    this node's wall clock), over the frames sent in the measured time."""
    lines, all_shares = [], []
    for topic in lag_topics:
        with recorder.lock:
            arrivals = dict(recorder.frame_arrivals[topic])
        grid_of = latencies(sent.get(topic, []), grids, topic)
        lags, shares = [], []
        for stamp in sent.get(topic, []):
            if stamp not in arrivals:
                continue
            lag = recorder.bag_time(arrivals[stamp]) - stamp
            lags.append(lag)
            if grid_of.get(stamp) is not None:
                shares.append(grid_of[stamp] - lag)
        all_shares += shares
        if not lags:
            lines.append("%s: no frame received here" % topic)
            continue
        lines.append("%s: player's lag (stamp to arrival at a plain subscriber) median %.1f ms, "
                     "p99 %.1f ms; mapping's share (arrival to grid) median %s ms, p99 %s ms; "
                     "%d of %d frames received here" % (
                         topic, 1e3 * percentile(lags, 0.5), 1e3 * percentile(lags, 0.99),
                         "-" if not shares else "%.1f" % (1e3 * percentile(shares, 0.5)),
                         "-" if not shares else "%.1f" % (1e3 * percentile(shares, 0.99)),
                         len(lags), len(sent.get(topic, []))))
    if all_shares:
        lines.append("mapping's share, every frame received here: median %.1f ms, p99 %.1f ms" % (
            1e3 * percentile(all_shares, 0.5), 1e3 * percentile(all_shares, 0.99)))
    return lines


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--duration", type=float, required=True, help="s measured")
    parser.add_argument("--warmup", type=float, default=10.0, help="s before measuring")
    parser.add_argument("--window", type=float, default=5.0, help="s per CSV row")
    parser.add_argument("--manager", default="/occupancy_fusion_manager")
    parser.add_argument("--player-pid", type=int, required=True, help="rosbag play's process")
    parser.add_argument("--bag", required=True, help="the bag played (the frames sent)")
    parser.add_argument("--topic", action="append", required=True,
                        help="a sensor topic (resolved name); repeat for each")
    parser.add_argument("--lag-topic", action="append", default=[],
                        help="TOPIC[=PROXY]: a sensor topic whose frames (or PROXY's messages "
                        "of the same stamps, such as its camera_info) are received here too, to "
                        "split its latency into the player's lag and the mapping's share; repeat "
                        "for each")
    parser.add_argument("--csv", required=True)
    parser.add_argument("--summary", required=True)
    args = parser.parse_args(rospy.myargv()[1:])

    rospy.init_node("robot_budget_monitor", disable_signals=True)
    lag_topics = [tuple(entry.split("=", 1)) if "=" in entry else (entry, entry)
                  for entry in args.lag_topic]
    recorder = Recorder(lag_topics)
    manager_pid, player_pid = node_pid(args.manager, "/robot_budget_monitor"), args.player_pid
    cores = os.cpu_count()
    time.sleep(max(0.0, args.warmup - 1.0))
    recorder.settle()
    time.sleep(min(1.0, args.warmup))
    start = time.time()
    ros_start = recorder.bag_time()
    start_counts = {task: recorder.counts(task) for task in TASKS.values()}
    cpu_start = {pid: cpu_seconds(pid) for pid in (manager_pid, player_pid)}
    machine_start = busy_and_total_ticks()
    windows = []
    next_window = start + args.window
    while time.time() < start + args.duration:
        time.sleep(max(0.0, min(next_window, start + args.duration) - time.time()))
        now = time.time()
        windows.append((now, recorder.bag_time(),
                        {pid: cpu_seconds(pid) for pid in (manager_pid, player_pid)}))
        next_window += args.window
    end = time.time()
    ros_end = recorder.bag_time()
    end_counts = {task: recorder.counts(task) for task in TASKS.values()}
    machine_end = busy_and_total_ticks()
    time.sleep(1.0)  # grids holding the last frames of the run
    with recorder.lock:
        arrivals = list(recorder.grids)
    grids = [(recorder.bag_time(arrival), frames) for arrival, frames in arrivals]
    sent = {topic: [s for s in stamps if ros_start <= s < ros_end]
            for topic, stamps in sent_stamps(args.bag, args.topic).items()}

    per_topic = {topic: latencies(stamps, grids, topic) for topic, stamps in sent.items()}
    columns = ["elapsed_s", "manager_cpu_share", "player_cpu_share"]
    for topic in args.topic:
        columns += [topic + " frames", topic + " latency_median_ms", topic + " latency_p99_ms"]
    with open(args.csv, "w", newline="") as out:
        writer = csv.DictWriter(out, fieldnames=columns)
        writer.writeheader()
        previous_time, previous_ros, previous_cpu = start, ros_start, cpu_start
        for now, ros_now, cpu in windows:
            row = {"elapsed_s": "%.1f" % (now - start)}
            for name, pid in (("manager", manager_pid), ("player", player_pid)):
                share = (cpu[pid] - previous_cpu[pid]) / ((now - previous_time) * cores)
                row[name + "_cpu_share"] = "%.3f" % share
            for topic in args.topic:
                values = [v for s, v in per_topic[topic].items()
                          if previous_ros <= s < ros_now and v is not None]
                row[topic + " frames"] = len(values)
                for key, fraction in (("latency_median_ms", 0.5), ("latency_p99_ms", 0.99)):
                    value = percentile(values, fraction)
                    row[topic + " " + key] = "" if value is None else "%.1f" % (1e3 * value)
            writer.writerow(row)
            previous_time, previous_ros, previous_cpu = now, ros_now, cpu

    lines = ["robot budget: %.0f s measured after %.0f s warm-up, %d cores" %
             (end - start, args.warmup, cores)]
    for name, pid in (("mapping manager", manager_pid), ("rosbag play", player_pid)):
        share = (windows[-1][2][pid] - cpu_start[pid]) / ((windows[-1][0] - start) * cores)
        lines.append("%s CPU: %.1f %% of %d cores" % (name, 100.0 * share, cores))
    busy, total = (after - before for after, before in zip(machine_end, machine_start))
    lines.append("machine busy: %.1f %% of %d cores (every process, the measurement's included)"
                 % (100.0 * busy / max(total, 1), cores))
    all_latencies = []
    for topic in args.topic:
        values = [v for v in per_topic[topic].values() if v is not None]
        all_latencies += values
        never = sum(1 for v in per_topic[topic].values() if v is None)
        median, p99 = percentile(values, 0.5), percentile(values, 0.99)
        lines.append("%s: %d frames sent, %d in a published grid, %d never; latency median %s ms,"
                     " p99 %s ms, rate %.1f Hz" % (
                         topic, len(sent[topic]), len(values), never,
                         "-" if median is None else "%.1f" % (1e3 * median),
                         "-" if p99 is None else "%.1f" % (1e3 * p99),
                         len(sent[topic]) / (ros_end - ros_start)))
    for kind, task in TASKS.items():
        before, after = start_counts[task], end_counts[task]
        delta = {key: int(after.get(key, 0)) - int(before.get(key, 0))
                 for key in ("frames received", "frames integrated", "frames dropped")}
        if not after:
            lines.append("%s: not running" % task)
            continue
        dropped = {key: int(after[key]) - int(before.get(key, 0)) for key in after
                   if key.startswith("frames dropped (") and int(after[key]) > int(before.get(key, 0))}
        lines.append("%s: received %d, integrated %d, dropped %d %s; integration ms mean %s, max %s"
                     % (task, delta["frames received"], delta["frames integrated"],
                        delta["frames dropped"], dropped or "",
                        after.get("integration ms (mean)", "-"),
                        after.get("integration ms (max)", "-")))
    lines += lag_lines(recorder, grids, sent, [topic for topic, _ in lag_topics])
    lines.append("all sensors: latency median %.1f ms, p99 %.1f ms" % (
        1e3 * percentile(all_latencies, 0.5), 1e3 * percentile(all_latencies, 0.99))
        if all_latencies else "all sensors: no frame reached a published grid")
    with open(args.summary, "w") as out:
        out.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
