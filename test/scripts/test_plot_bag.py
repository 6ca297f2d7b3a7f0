#!/usr/bin/env python3
"""scripts/plot_bag.py on bags written here with rosbag's python API (issue 33 item 3): what the
figure draws, read back from its artists. Fail-safe labels that cluster do not overlap as
rendered; an outage (a gap, a `valid: false` signal, a `stale` outputs message) breaks the
line and is shaded; a node's stop and restart are marked; a running PWM is hatched, not "on".
The rules are in plot_bag.py's docstring and docs/recording.md "Plotting"."""
import importlib.util
import os
import pathlib
import shutil
import sys
import tempfile
import types
import unittest

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.text import Annotation  # noqa: E402
import rosbag
import rospy  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from modbus_rtu_driver.msg import (DigitalStates, FailsafeEvent, PduTelemetry, PwmChannel,
                                   PwmStates, SignalValues)

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "plot_bag.py"
T0 = 1000.0  # the bag's first second
NODE = "/robot/io_bus"


def load_script():
    spec = importlib.util.spec_from_file_location("plot_bag", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def stamped(msg, t):
    msg.header.stamp = rospy.Time.from_sec(t)
    return msg


def diagnostics(t, requests, node=NODE):
    status = DiagnosticStatus(name=node.lstrip("/") + ": bus /dev/ttyUSB0", message="link up",
                              values=[KeyValue("requests", str(requests))])
    device = DiagnosticStatus(name=node.lstrip("/") + ": device relays", message="online")
    other = DiagnosticStatus(name="some_other_node: bus", message="ok",
                             values=[KeyValue("requests", "1")])
    return stamped(DiagnosticArray(status=[status, device, other]), t)


def times(start, end, rate):
    n = int(round((end - start) * rate))
    return [start + i / rate for i in range(n)]


def x_extent(span):
    """An axvspan's x range: a Rectangle since matplotlib 3.9 (Debian 13), a Polygon before."""
    if hasattr(span, "get_width"):
        return span.get_x(), span.get_x() + span.get_width()
    xs = [x for x, _ in span.get_xy()]
    return min(xs), max(xs)


class PlotBagTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.plot_bag = load_script()

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="modbus_rtu_plot_bag_")
        self.bag_path = os.path.join(self.dir, "robot.bag")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def write(self, messages):
        """messages: [(t, topic, msg)]"""
        with rosbag.Bag(self.bag_path, "w") as bag:
            for t, topic, msg in sorted(messages, key=lambda m: m[0]):
                bag.write(topic, msg, rospy.Time.from_sec(t))

    def draw(self):
        data = self.plot_bag.load([self.bag_path])
        drawn = self.plot_bag.plot(data, os.path.join(self.dir, "robot.png"), "robot.bag")
        if drawn is None:  # a plot_bag.py that returns nothing (before issue 33): its figure
            fig = plt.gcf()
            drawn = types.SimpleNamespace(
                fig=fig, axes=fig.axes, left_out=[],
                t0=min(t for _, _, t in rosbag.Bag(self.bag_path).read_messages()).to_sec(),
                labels=[a for a in fig.axes[0].get_children() if isinstance(a, Annotation)])
        return drawn

    @staticmethod
    def artists(ax, gid):
        return [a for a in ax.get_children() if a.get_gid() == gid]

    def spans(self, ax, gid, drawn):
        """(from, to) in bag time of the axvspans with this gid."""
        out = []
        for a in self.artists(ax, gid):
            x0, x1 = x_extent(a)
            out.append((round(x0 + drawn.t0, 3), round(x1 + drawn.t0, 3)))
        return sorted(out)

    def assert_line_broken(self, ax, start, end, drawn):
        """No line of the panel joins a point at or before `start` to one at or after `end`."""
        lines = self.artists(ax, "series") or ax.get_lines()
        self.assertTrue(lines)
        for line in lines:
            xs = [x + drawn.t0 for x in line.get_xdata()]
            for a, b in zip(xs, xs[1:]):
                self.assertFalse(a <= start + 1e-6 and b >= end - 1e-6,
                                 "a line runs on from %.2f to %.2f across the outage" % (a, b))

    def relay_outputs(self, t, states, stale=False):
        return stamped(DigitalStates(states=states, names=["pump", "valve", "lamp", "fan"],
                                     stale=stale), t)

    def test_clustered_failsafe_labels_do_not_overlap(self):
        msgs = [(t, NODE + "/relays/outputs", self.relay_outputs(t, [False] * 4))
                for t in times(T0, T0 + 30, 5)]
        # A heartbeat loss on four boards at once, the same board's command timeout twice at
        # the same moment, and one more a little later: the labels cluster at 10 s.
        for i, device in enumerate(["relays", "pwm_board", "pdu", "climate"]):
            msgs.append((T0 + 10 + 0.01 * i, NODE + "/failsafe",
                         stamped(FailsafeEvent(device=device, trigger="heartbeat"),
                                 T0 + 10 + 0.01 * i)))
        for dt in (0.05, 0.06):
            msgs.append((T0 + 10 + dt, NODE + "/failsafe",
                         stamped(FailsafeEvent(device="relays", trigger="command_timeout"),
                                 T0 + 10 + dt)))
        msgs.append((T0 + 10.5, NODE + "/failsafe",
                     stamped(FailsafeEvent(device="relays", trigger="restart"), T0 + 10.5)))
        self.write(msgs)
        drawn = self.draw()
        renderer = drawn.fig.canvas.get_renderer()
        texts = [a.get_text() for a in drawn.labels]
        boxes = [a.get_window_extent(renderer) for a in drawn.labels]
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                self.assertFalse(boxes[i].overlaps(boxes[j]),
                                 "%r overlaps %r" % (texts[i], texts[j]))
        self.assertEqual(len(texts), 6, texts)  # the twin command_timeout labels merged
        self.assertIn("fail-safe: relays command_timeout x2", texts)
        self.assertEqual(drawn.left_out, [])
        # Every label inside the figure (the rows made room above the top panel).
        figure_box = drawn.fig.bbox
        for box, text in zip(boxes, texts):
            self.assertLessEqual(box.y1, figure_box.y1 + 0.5, text)

    def test_an_outage_breaks_the_line_and_is_shaded(self):
        msgs = []
        # PDU telemetry at 2 Hz, none from 10 s to 20 s (failed reads publish nothing).
        for t in times(T0, T0 + 10, 2) + times(T0 + 20, T0 + 30, 2):
            msgs.append((t, NODE + "/pdu/telemetry",
                         stamped(PduTelemetry(voltage=230.0, power=100.0), t)))
        # A signal at 2 Hz, `valid: false` from 5 s to 8 s.
        for t in times(T0, T0 + 30, 2):
            good = not (T0 + 5 <= t < T0 + 8)
            msgs.append((t, NODE + "/climate/signals", stamped(SignalValues(
                names=["temperature"], values=[21.5], valid=[good], units=["C"]), t)))
        # Outputs at 5 Hz, the board offline (one stale message, then nothing) 12 s to 16 s.
        for t in times(T0, T0 + 30, 5):
            if T0 + 12 < t < T0 + 16:
                continue
            msgs.append((t, NODE + "/relays/outputs",
                         self.relay_outputs(t, [True, False, False, False], stale=t == T0 + 12)))
        for t in times(T0, T0 + 30, 1):
            msgs.append((t, "/diagnostics", diagnostics(t, int((t - T0) * 10))))
        self.write(msgs)
        drawn = self.draw()
        power, climate, relays = drawn.axes[0], drawn.axes[4], drawn.axes[5]
        self.assertEqual(power.get_ylabel(), "power [W]")
        self.assertEqual(climate.get_ylabel(), "[C]")
        self.assertEqual(relays.get_ylabel(), "relays")
        # Telemetry: the last sample before the gap at 9.5 s, the first after at 20 s.
        self.assert_line_broken(power, T0 + 9.5, T0 + 20, drawn)
        self.assertEqual(self.spans(power, "outage", drawn), [(T0 + 9.5, T0 + 20)])
        # The signal: good at 4.5 s, bad 5-7.5 s, good again at 8 s.
        self.assert_line_broken(climate, T0 + 4.5, T0 + 8, drawn)
        self.assertEqual(self.spans(climate, "outage", drawn), [(T0 + 4.5, T0 + 8)])
        # Outputs: good at 11.8 s, stale at 12 s, good again at 16 s.
        self.assert_line_broken(relays, T0 + 11.8, T0 + 16, drawn)
        self.assertEqual(self.spans(relays, "outage", drawn), [(T0 + 11.8, T0 + 16)])
        # /diagnostics went on: the node did not stop.
        for ax in drawn.axes:
            self.assertEqual(self.artists(ax, "node-stopped"), [])
            self.assertEqual(self.artists(ax, "node-restarted"), [])

    def test_node_stop_and_restart_are_marked(self):
        msgs = []
        # Up 0-10 s, dead 10-18 s (nothing at all, /diagnostics neither), respawned at 18 s;
        # a second, quick respawn at 25 s shows only in the bus counter going down.
        for t in times(T0, T0 + 10, 5) + times(T0 + 18, T0 + 30, 5):
            msgs.append((t, NODE + "/relays/outputs", self.relay_outputs(t, [False] * 4)))
        for t in times(T0, T0 + 10, 1) + times(T0 + 18, T0 + 30, 1):
            since = T0 + 25 if t >= T0 + 25 else (T0 + 18 if t >= T0 + 18 else T0)
            msgs.append((t, "/diagnostics", diagnostics(t, int((t - since) * 10) + 1)))
        self.write(msgs)
        drawn = self.draw()
        ax = drawn.axes[0]
        stopped = [line.get_xdata()[0] + drawn.t0 for line in self.artists(ax, "node-stopped")]
        restarted = sorted(line.get_xdata()[0] + drawn.t0
                           for line in self.artists(ax, "node-restarted"))
        self.assertEqual([round(t, 3) for t in stopped], [T0 + 9.8])  # its last message
        self.assertEqual([round(t, 3) for t in restarted], [T0 + 18, T0 + 25])
        self.assertEqual(self.spans(ax, "node-silent", drawn), [(T0 + 9.8, T0 + 18)])
        self.assert_line_broken(ax, T0 + 9.8, T0 + 18, drawn)
        self.assertEqual(sorted(a.get_text() for a in drawn.labels),
                         ["node restarted", "node restarted", "node stopped"])

    def test_a_node_that_stopped_for_good(self):
        msgs = [(t, NODE + "/relays/outputs", self.relay_outputs(t, [False] * 4))
                for t in times(T0, T0 + 10, 5)]
        msgs += [(t, "/diagnostics", diagnostics(t, int((t - T0) * 10)))
                 for t in times(T0, T0 + 10, 1)]
        # The recorder ran on (another node's message) for 10 s more.
        msgs.append((T0 + 20, "/diagnostics", diagnostics(T0 + 20, 5, node="/other")))
        self.write(msgs)
        drawn = self.draw()
        ax = drawn.axes[0]
        self.assertEqual(len(self.artists(ax, "node-stopped")), 1)
        self.assertEqual(self.artists(ax, "node-restarted"), [])
        self.assertEqual(self.spans(ax, "node-silent", drawn), [(T0 + 9.8, T0 + 20)])

    def test_a_running_pwm_is_hatched_not_on(self):
        msgs = []
        for t in times(T0, T0 + 30, 5):
            # Channel 1 on as a plain output all along; channel 2 runs a PWM 5-15 s (the polls
            # see it on and off).
            pwm_on = T0 + 5 <= t < T0 + 15
            msgs.append((t, NODE + "/pwm_board/outputs", self.relay_outputs(
                t, [False, True, pwm_on and int(t * 5) % 2 == 0, False])))
        for t, running in ((T0, False), (T0 + 5, True), (T0 + 15, False)):
            channels = [PwmChannel(channel=c, running=running and c == 2) for c in range(4)]
            msgs.append((t, NODE + "/pwm_board/pwm", stamped(PwmStates(channels=channels), t)))
        self.write(msgs)
        drawn = self.draw()
        ax = drawn.axes[0]
        hatched = self.artists(ax, "pwm:2")
        self.assertEqual(len(hatched), 1)
        self.assertTrue(hatched[0].get_hatch())
        xs = [x + drawn.t0 for path in hatched[0].get_paths() for x, _ in path.vertices]
        self.assertAlmostEqual(min(xs), T0 + 5)
        self.assertAlmostEqual(max(xs), T0 + 15)
        ys = [y for path in hatched[0].get_paths() for _, y in path.vertices]
        self.assertGreaterEqual(min(ys), 2.0)  # channel 2's row only
        self.assertLessEqual(max(ys), 2.7)
        for ch in (0, 1, 3):  # plain on (channel 1) and off are not hatched
            self.assertEqual(self.artists(ax, "pwm:%d" % ch), [])


if __name__ == "__main__":
    # rosunit writes the JUnit file the test command counts (--gtest_output=xml:PATH).
    if any(a.startswith("--gtest_output") for a in sys.argv):
        import rosunit
        rosunit.unitrun("modbus_rtu_driver", "plot_bag", PlotBagTest)
    else:
        unittest.main()
