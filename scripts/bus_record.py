#!/usr/bin/python3
"""rosbag record for one bus node: bus.launch's recorder (record:=true).

    bus_record.py NAME PREFIX [rosbag record options...]

Records the telemetry, limits, outputs, inputs, pwm and signals topics of the node NAME's
devices, its ~failsafe, and /diagnostics; nothing of another bus node, even one with the same
name in another namespace (a robot with /left/modbus_bus and /right/modbus_bus). rosbag's
--regex sees full topic names only and a launch file cannot know its namespace, so this runs as
a node beside the bus node: roslaunch gives it the namespace (ROS_NAMESPACE), and the node's full
name anchors the regex.

PREFIX (empty = ~/modbus_rtu) gets _<the node's full name with / as _> and is rosbag's -o, which
adds the date: ~/modbus_rtu_robot_io_bus_2026-12-04-05-00-00.bag. So each bus's bags have a name
of their own even when two recorders are given one prefix and start in the same second.
"""
import os
import re
import sys

# Under the node: DEVICE/telemetry, ..., and the node's own failsafe.
TOPICS = "(.*/(telemetry|limits|outputs|inputs|pwm|signals)|failsafe)"


def node_name(name, namespace):
    """The bus node's full name: NAME resolved in NAMESPACE ("/robot", "" or "/")."""
    if name.startswith("/"):
        namespace = ""
    parts = [p for p in namespace.split("/") + name.split("/") if p]
    return "/" + "/".join(parts)


def record_command(name, prefix, options, namespace, home):
    node = node_name(name, namespace)
    prefix = (prefix or os.path.join(home, "modbus_rtu")) + node.replace("/", "_")
    regex = "^" + re.escape(node) + "/" + TOPICS + "$"
    return ["rosrun", "rosbag", "record", "-o", prefix] + options + \
        ["--regex", regex, "^/diagnostics$"]


def main(argv):
    if len(argv) < 2 or not argv[0]:
        print("usage: bus_record.py NAME PREFIX [rosbag record options...]", file=sys.stderr)
        return 2
    command = record_command(argv[0], argv[1], argv[2:], os.environ.get("ROS_NAMESPACE", ""),
                             os.path.expanduser("~"))
    print("bus_record.py: " + " ".join(command), flush=True)
    os.execvp(command[0], command)
    return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
