"""What the monitors of a running mapping graph (soak_monitor.py, robot_budget_monitor.py) read
from the outside: a node's process, a process's CPU time, and the newest diagnostics."""
import os
import threading
import xmlrpc.client

import rosgraph
import rospy
from diagnostic_msgs.msg import DiagnosticArray


def node_pid(node_name, caller):
    """The pid of a running ROS node, asked from the node itself (XML-RPC getPid)."""
    uri = rosgraph.Master(caller).lookupNode(node_name)
    code, _, pid = xmlrpc.client.ServerProxy(uri).getPid(caller)
    if code != 1:
        raise RuntimeError("getPid failed for " + node_name)
    return int(pid)


def descendants(pid):
    """pid and every process below it (rosbag play runs its player as a child)."""
    found = [pid]
    for task in os.listdir("/proc/%d/task" % pid):
        try:
            with open("/proc/%d/task/%s/children" % (pid, task)) as children:
                for child in children.read().split():
                    found += descendants(int(child))
        except OSError:  # the task ended meanwhile
            pass
    return found


def cpu_seconds(pid):
    """User and system CPU time of a process, its threads and its children."""
    total = 0.0
    for process in descendants(pid):
        try:
            with open("/proc/%d/stat" % process) as stat:
                fields = stat.read().rsplit(")", 1)[1].split()
            # utime and stime are fields 14 and 15 of stat(5); fields[0] here is field 3.
            total += (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        except OSError:  # ended meanwhile
            pass
    return total


class Diagnostics:
    """The newest key/value pairs of every diagnostic status that has values, by status name
    ("<node>: <task>")."""

    def __init__(self):
        self.lock = threading.Lock()
        self.latest = {}
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_array, queue_size=20)

    def on_array(self, array):
        with self.lock:
            for status in array.status:
                if status.values:
                    self.latest[status.name] = {kv.key: kv.value for kv in status.values}

    def find(self, node, key):
        """The values of `node`'s status (names start with the nodelet's name) having `key`."""
        with self.lock:
            for name, values in self.latest.items():
                if name.lstrip("/").startswith(node + ":") and key in values:
                    return dict(values)
        return None

    def task(self, task):
        """The values of the status whose name ends in `task`; {} before it reported."""
        with self.lock:
            for name, values in self.latest.items():
                if name.endswith(task):
                    return dict(values)
        return {}
