#!/usr/bin/python3
"""Plots a bag recorded by bus.launch / demo.launch (record:=true) to a PNG: PDU power, voltage,
current and temperature; generic devices' signals, one panel per unit; every device's outputs
in a panel of its own, one labelled row per channel; and the fail-safe's actions (~failsafe)
as marks on the time axis of every panel.

    scripts/plot_bag.py my.bag -o robot.png [--node /my_robot/io_bus]
    scripts/plot_bag.py ~/modbus_rtu_io_bus_*.bag ~/modbus_rtu_sensor_bus_*.bag -o robot.png

The bus nodes are found by their topics' message types (any namespace); --node keeps one.
Several bags (a bag per bus of one robot, or one recording's split files) make one figure on
one time axis: each bus node's panels together, its devices labelled with the node's name.

What the figure shows besides the values (the rules, also in docs/recording.md "Plotting"):
- outage: a series' line is broken, and the stretch shaded grey, where a sample says the value
  is not good (a signal's `valid: false`, an `outputs` message with `stale: true`) or where the
  series has a gap longer than GAP_INTERVALS of its usual intervals (the median time between
  its samples): a PDU read that failed publishes nothing;
- node stopped / restarted: the node published nothing at all (no device topic, no ~failsafe,
  no /diagnostics status of its own) for longer than GAP_INTERVALS of its slowest periodic
  series' usual interval (/diagnostics: 1 s, so 3 s); the stretch is shaded dark across all its
  panels, "node stopped" at its last message, "node restarted" at its first one after. A
  restart quicker than that (respawn) shows in /diagnostics, whose bus counters count from
  the node's start: its `requests` going down marks "node restarted" too;
- PWM: a channel of an `ld58a08` whose `pwm` topic says `running` is drawn hatched over its row
  (the relay switches faster than the polls see), not as plain "on";
- fail-safe labels: identical labels (same device and trigger) less than MERGE_FRACTION of the
  time axis apart are one label with a count ("x3"); the others are set in rows above the top
  panel, each in the lowest row where it overlaps no other label (at most MAX_LABEL_ROWS rows;
  what does not fit is counted in a note, its red marks still drawn); the node's stops and
  restarts are labelled the same way, in black.
"""
import argparse
import collections
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import rosbag  # noqa: E402

# Message type -> what it is, and where the device name sits in its topic.
DEVICE_TOPICS = {
    "modbus_rtu_driver/PduTelemetry": "telemetry",
    "modbus_rtu_driver/DigitalStates": "outputs",  # inputs too; told apart by the topic's leaf
    "modbus_rtu_driver/SignalValues": "signals",
    "modbus_rtu_driver/PwmStates": "pwm",
    "modbus_rtu_driver/PduLimits": "limits",
}
FAILSAFE_TYPE = "modbus_rtu_driver/FailsafeEvent"
DIAGNOSTICS_TYPE = "diagnostic_msgs/DiagnosticArray"
TELEMETRY_ROWS = [("power", "W"), ("voltage", "V"), ("current", "A"), ("temperature", "°C")]
GAP_INTERVALS = 3.0  # a gap longer than this many usual intervals of a series is an outage
MERGE_FRACTION = 0.01  # identical fail-safe labels closer than this part of the axis: one label
MAX_LABEL_ROWS = 6
LABEL_ROW_PT = 11  # points between label rows (7 pt text)
OUTAGE_STYLE = {"color": "0.5", "alpha": 0.25, "linewidth": 0}
SILENCE_STYLE = {"color": "0.2", "alpha": 0.3, "linewidth": 0}
PWM_STYLE = {"facecolor": "none", "edgecolor": "tab:orange", "hatch": "////", "linewidth": 0.8}


class BagData:
    def __init__(self):
        self.telemetry = collections.defaultdict(list)  # (node, device) -> [(t, msg)]
        self.outputs = collections.defaultdict(list)
        self.signals = collections.defaultdict(list)
        self.pwm = collections.defaultdict(list)
        self.other = collections.defaultdict(list)  # (node, device) -> [t]: inputs, limits
        self.failsafe = []  # (t, node, msg)
        self.diagnostics = collections.defaultdict(list)  # node -> [(t, bus requests or None)]
        self.bag_end = None  # the last bag's end: a node silent until then stopped for good

    def device_nodes(self):
        keys = list(self.telemetry) + list(self.outputs) + list(self.signals) + list(self.pwm)
        return {n for n, _ in keys} | {n for _, n, _ in self.failsafe}

    def nodes(self):
        return sorted(self.device_nodes())

    def empty(self):
        return not (self.telemetry or self.outputs or self.signals or self.failsafe)

    def of_node(self, node):
        """This data's part of one bus node."""
        out = BagData()
        for kind in ("telemetry", "outputs", "signals", "pwm", "other"):
            for key, samples in getattr(self, kind).items():
                if key[0] == node:
                    getattr(out, kind)[key] = samples
        out.failsafe = [e for e in self.failsafe if e[1] == node]
        out.bag_end = self.bag_end
        if node in self.diagnostics:
            out.diagnostics[node] = self.diagnostics[node]
        return out

    def times(self):
        """Every message's time, the node's own /diagnostics included."""
        out = [t for series in (self.telemetry, self.outputs, self.signals, self.pwm)
               for samples in series.values() for t, _ in samples]
        out += [t for samples in self.other.values() for t in samples]
        out += [t for t, _, _ in self.failsafe]
        out += [t for samples in self.diagnostics.values() for t, _ in samples]
        return sorted(out)


def stamp_of(msg, t):
    stamp = getattr(getattr(msg, "header", None), "stamp", None)
    return stamp.to_sec() if stamp and stamp.to_sec() > 0 else t.to_sec()


def load(bag_paths, only_node=None):
    data = BagData()
    for bag_path in bag_paths:
        load_one(bag_path, only_node, data)
    for series in (data.telemetry, data.outputs, data.signals, data.pwm):
        for samples in series.values():
            samples.sort(key=lambda s: s[0])  # split files given in any order
    for samples in data.other.values():
        samples.sort()
    data.failsafe.sort(key=lambda e: e[0])
    ours = data.device_nodes()  # /diagnostics also carries other nodes' statuses
    for node in list(data.diagnostics):
        if node in ours:
            data.diagnostics[node].sort(key=lambda s: s[0])
        else:
            del data.diagnostics[node]
    return data


def bus_requests(status):
    """The bus status's `requests` counter (counts from the node's start), else None."""
    if not status.name.split(": ", 1)[-1].startswith("bus "):
        return None
    for kv in status.values:
        if kv.key == "requests":
            try:
                return int(kv.value)
            except ValueError:
                return None
    return None


def load_one(bag_path, only_node, data):
    with rosbag.Bag(bag_path) as bag:
        if bag.get_message_count():
            data.bag_end = max(data.bag_end or 0.0, bag.get_end_time())
        types = {topic: info.msg_type for topic, info in bag.get_type_and_topic_info().topics.items()}
        wanted = []
        for topic, msg_type in types.items():
            if msg_type == FAILSAFE_TYPE and topic.endswith("/failsafe"):
                wanted.append(topic)
            elif msg_type == DIAGNOSTICS_TYPE:
                wanted.append(topic)
            elif msg_type in DEVICE_TOPICS and topic.count("/") >= 3:
                wanted.append(topic)  # /NODE.../DEVICE/LEAF
        for topic, msg, t in bag.read_messages(topics=wanted):
            if types[topic] == DIAGNOSTICS_TYPE:
                load_diagnostics(msg, t.to_sec(), only_node, data)
                continue
            if types[topic] == FAILSAFE_TYPE:
                node = topic[:-len("/failsafe")]
                if only_node in (None, node):
                    data.failsafe.append((stamp_of(msg, t), node, msg))
                continue
            rest, leaf = topic.rsplit("/", 1)
            node, device = rest.rsplit("/", 1)
            if only_node not in (None, node):
                continue
            kind = DEVICE_TOPICS[types[topic]]
            if kind == "limits" or (kind == "outputs" and leaf != "outputs"):
                data.other[(node, device)].append(t.to_sec())  # the node's life, not plotted
                continue
            getattr(data, kind)[(node, device)].append((stamp_of(msg, t), msg))


def load_diagnostics(msg, t, only_node, data):
    """The statuses of a node are named "NODE: ..." (diagnostic_updater, NODE without its
    leading /): one entry per message and node, with its bus's requests counter."""
    found = {}
    for status in msg.status:
        if ": " not in status.name:
            continue
        node = "/" + status.name.split(": ", 1)[0].lstrip("/")
        if only_node not in (None, node):
            continue
        requests = bus_requests(status)
        if node not in found or requests is not None:
            found[node] = requests
    for node, requests in found.items():
        data.diagnostics[node].append((t, requests))


def usual_interval(times):
    """The median time between a series' samples (None for fewer than 3 samples)."""
    steps = [b - a for a, b in zip(times, times[1:]) if b > a]
    return statistics.median(steps) if len(steps) >= 2 else None


def split_at_outages(times, good, end=None):
    """A series cut where it is out: (runs, outages). runs: lists of indices of good samples
    drawn joined; outages: [(from, to)], from the last good sample before a bad sample or a gap
    longer than GAP_INTERVALS usual intervals, to the next good one (or `end`, the node's last
    message, when the series stopped before it)."""
    interval = usual_interval([t for t, ok in zip(times, good) if ok])
    max_gap = GAP_INTERVALS * interval if interval else float("inf")
    runs, outages, current = [], [], []
    last_good = bad_since = None
    for i, (t, ok) in enumerate(zip(times, good)):
        if not ok:
            if bad_since is None:
                bad_since = t
            continue
        if last_good is None and bad_since is not None:
            outages.append((bad_since, t))
        elif last_good is not None and (bad_since is not None or t - last_good > max_gap):
            outages.append((last_good, t))
            runs.append(current)
            current = []
        current.append(i)
        last_good, bad_since = t, None
    if current:
        runs.append(current)
    if times:
        tail_from = last_good if last_good is not None else times[0]
        tail_to = max(times[-1], end if end is not None else times[-1])
        if bad_since is not None or (last_good is not None and tail_to - last_good > max_gap):
            outages.append((tail_from, tail_to))
    return runs, outages


def node_life(data):
    """One node's silences and restarts: (silences, restarts). silences: [(last message before,
    first message after, or None when the bag ended first)] where the node published nothing
    for longer than GAP_INTERVALS of its slowest periodic series' usual interval; restarts: the
    end of each silence, and where its /diagnostics' bus `requests` counter (counted from the
    node's start) went down across no silence: a respawn quicker than the silence rule."""
    periodic = [[t for t, _ in s] for series in (data.telemetry, data.outputs, data.signals)
                for s in series.values()]
    periodic += [[t for t, _ in s] for s in data.diagnostics.values()]
    intervals = [i for i in map(usual_interval, periodic) if i]
    times = data.times()
    silences = []
    if intervals and times:
        max_gap = GAP_INTERVALS * max(intervals)
        silences = [(a, b) for a, b in zip(times, times[1:]) if b - a > max_gap]
        if data.bag_end is not None and data.bag_end - times[-1] > max_gap:
            silences.append((times[-1], None))
    restarts = [b for _, b in silences if b is not None]
    for samples in data.diagnostics.values():
        counts = [(t, r) for t, r in samples if r is not None]
        for (t1, before), (t2, now) in zip(counts, counts[1:]):
            if now < before and not any(t1 <= a and b is not None and b <= t2
                                        for a, b in silences):
                restarts.append(t2)
    return silences, sorted(restarts)


def pwm_runs(samples, end):
    """[(channel, from, to)]: where the device's pwm topic said the channel runs; a run still
    going at the last message ends at `end` (the device's last message)."""
    out = []
    started = {}
    for t, msg in samples:
        for ch in msg.channels:
            if ch.running and ch.channel not in started:
                started[ch.channel] = t
            elif not ch.running and ch.channel in started:
                out.append((ch.channel, started.pop(ch.channel), t))
    for channel, t in started.items():
        out.append((channel, t, max(end, t)))
    return sorted(out)


def label(node, device, several_nodes):
    return f"{node}/{device}" if several_nodes else device


def shade(ax, spans, t0, style, gid):
    for a, b in spans:
        ax.axvspan(a - t0, b - t0, gid=gid, **style)


def panels(data):
    """[(height in inches, draw(ax, t0, several_nodes))] in the order shown: each bus node's
    panels together (a robot's bags: one bus after the other), nodes in name order."""
    return [row for node in data.nodes() for row in node_panels(data.of_node(node))]


def node_panels(data):
    """One bus node's panels: PDU telemetry, signals by unit, each device's outputs. Each panel
    shades the node's silences and its own series' outages, and marks restarts."""
    out = []
    node_times = data.times()
    end = node_times[-1] if node_times else None
    silences, restarts = node_life(data)
    silence_spans = [(a, b if b is not None else max(end, data.bag_end)) for a, b in silences]

    def life(ax, t0):
        shade(ax, silence_spans, t0, SILENCE_STYLE, "node-silent")
        for a, _ in silences:
            ax.axvline(a - t0, color="black", linestyle=":", linewidth=1.2, gid="node-stopped")
        for t in restarts:
            ax.axvline(t - t0, color="black", linestyle="-.", linewidth=1.2, gid="node-restarted")

    if data.telemetry:
        cut = {key: split_at_outages([t for t, _ in s], [True] * len(s), end)
               for key, s in data.telemetry.items()}
        for i, (field, unit) in enumerate(TELEMETRY_ROWS):
            def draw(ax, t0, several, field=field, unit=unit, first=i == 0):
                life(ax, t0)
                for (node, device), samples in sorted(data.telemetry.items()):
                    runs, outages = cut[(node, device)]
                    color = None
                    for n, run in enumerate(runs):
                        line, = ax.plot([samples[j][0] - t0 for j in run],
                                        [getattr(samples[j][1], field) for j in run], color=color,
                                        label=label(node, device, several) if n == 0 else None,
                                        gid="series")
                        color = line.get_color()
                    shade(ax, outages, t0, OUTAGE_STYLE, "outage")
                ax.set_ylabel(f"{field} [{unit}]")
                if first:
                    ax.legend(loc="upper right", fontsize=8)
            out.append((1.6, draw))
    by_unit = collections.defaultdict(list)  # unit -> [(label parts, times, values, good)]
    for (node, device), samples in sorted(data.signals.items()):
        names = samples[-1][1].names
        units = list(getattr(samples[-1][1], "units", []) or [""] * len(names))
        for i, name in enumerate(names):
            kept = [(s, m) for s, m in samples if i < len(m.values)]
            ts = [s for s, _ in kept]
            vs = [m.values[i] for _, m in kept]
            good = [i >= len(m.valid) or m.valid[i] for _, m in kept]
            if any(good):
                by_unit[units[i] if i < len(units) else ""].append(
                    ((node, device, name), ts, vs, good))
    for unit, lines in sorted(by_unit.items()):
        def draw(ax, t0, several, unit=unit, lines=lines):
            life(ax, t0)
            for (node, device, name), ts, vs, good in lines:
                runs, outages = split_at_outages(ts, good, end)
                color = None
                name_shown = f"{label(node, device, several)}/{name}"
                for n, run in enumerate(runs):
                    line, = ax.plot([ts[j] - t0 for j in run], [vs[j] for j in run], color=color,
                                    label=name_shown if n == 0 else None,
                                    drawstyle="steps-post" if not unit else "default", gid="series")
                    color = line.get_color()
                shade(ax, outages, t0, OUTAGE_STYLE, "outage")
            ax.set_ylabel(f"[{unit}]" if unit else "(no unit)")
            ax.legend(loc="upper right", fontsize=8)
        out.append((1.6, draw))
    for (node, device), samples in sorted(data.outputs.items()):
        names = list(samples[-1][1].names) or [f"out{i}" for i in range(len(samples[-1][1].states))]
        pwm = data.pwm.get((node, device), [])
        device_end = max([t for t, _ in samples] + [t for t, _ in pwm])
        runs_pwm = pwm_runs(pwm, device_end)
        runs, outages = split_at_outages([t for t, _ in samples],
                                         [not m.stale for _, m in samples], end)

        def draw(ax, t0, several, node=node, device=device, samples=samples, names=names,
                 runs=runs, outages=outages, runs_pwm=runs_pwm):
            life(ax, t0)
            for ch in range(len(names)):
                color = None
                for run in runs:
                    ts = [samples[j][0] - t0 for j in run]
                    ys = [ch + (0.7 if samples[j][1].states[ch] else 0.0)
                          if ch < len(samples[j][1].states) else float("nan") for j in run]
                    line, = ax.step(ts, ys, where="post", linewidth=1.5, color=color, gid="series")
                    color = line.get_color()
                    ax.fill_between(ts, ch, ys, step="post", alpha=0.25, color=color)
            for ch, a, b in runs_pwm:
                if ch < len(names):
                    ax.fill_between([a - t0, b - t0], ch, ch + 0.7, gid=f"pwm:{ch}", **PWM_STYLE)
            shade(ax, outages, t0, OUTAGE_STYLE, "outage")
            ax.set_yticks([ch + 0.35 for ch in range(len(names))])
            ax.set_yticklabels(names, fontsize=8)
            ax.set_ylim(-0.2, len(names))
            ax.set_ylabel(label(node, device, several), rotation=0, ha="right", va="center")
        out.append((0.35 + 0.22 * len(names), draw))
    return out


def failsafe_labels(data, several):
    """[(time, text)] of the fail-safe labels: identical ones (same node, device, trigger) less
    than MERGE_FRACTION of the time axis apart merged into one, with the count."""
    times = data.times()
    window = MERGE_FRACTION * (times[-1] - times[0]) if times else 0.0
    out = []  # [time, text, count]
    for t, node, msg in data.failsafe:
        text = f"fail-safe: {label(node, msg.device, several)} {msg.trigger}"
        for entry in reversed(out):
            if entry[1] == text and t - entry[0] <= window:
                entry[2] += 1
                break
        else:
            out.append([t, text, 1])
    return [(t, text if n == 1 else f"{text} x{n}", "red") for t, text, n in out]


def life_labels(data, several):
    """[(time, text, colour)]: each node's stops and restarts, labelled as the fail-safe's are."""
    out = []
    for node in data.nodes():
        silences, restarts = node_life(data.of_node(node))
        name = f"{node} " if several else "node "
        out += [(a, name + "stopped", "black") for a, _ in silences]
        out += [(t, name + "restarted", "black") for t in restarts]
    return out


def place_labels(fig, ax, labels, t0):
    """Sets the labels [(time, text, colour)] above `ax` in rows: each in the lowest row where
    its box, as rendered, overlaps no label placed before. Returns (annotations, left out)."""
    renderer = fig.canvas.get_renderer()
    placed = []  # (row, bbox)
    annotations, left_out = [], []
    for t, text, color in labels:
        for row in range(MAX_LABEL_ROWS):
            a = ax.annotate(text, xy=(t - t0, 1.0), xycoords=("data", "axes fraction"),
                            xytext=(2, 2 + LABEL_ROW_PT * row), textcoords="offset points",
                            fontsize=7, color=color, va="bottom",
                            gid="failsafe-label" if color == "red" else "life-label")
            box = a.get_window_extent(renderer).padded(1)
            if not any(box.overlaps(other) for _, other in placed):
                placed.append((row, box))
                annotations.append(a)
                break
            a.remove()
        else:
            left_out.append((t, text, color))
    return annotations, left_out


class Drawn:
    """What plot() drew, for tests: the figure, its time origin, the panels' axes and the
    fail-safe annotations (their artists carry gids: series, outage, node-silent, node-stopped,
    node-restarted, pwm:CHANNEL, failsafe-label)."""

    def __init__(self, fig, t0, axes, labels, left_out):
        self.fig, self.t0, self.axes, self.labels, self.left_out = fig, t0, axes, labels, left_out


def plot(data, out_path, title):
    rows = panels(data)
    if not rows:  # only fail-safe events: an empty time axis with their marks
        rows = [(1.0, lambda ax, t0, several: ax.set_yticks([]))]
    heights = [h for h, _ in rows]
    several = len(data.nodes()) > 1
    labels = sorted(failsafe_labels(data, several) + life_labels(data, several))
    fig, axes = plt.subplots(len(rows), 1, sharex=True, squeeze=False,
                             figsize=(11, sum(heights) + 1.2),
                             gridspec_kw={"height_ratios": heights})
    axes = [a[0] for a in axes]
    t0 = min(data.times(), default=0.0)
    for ax, (_, draw) in zip(axes, rows):
        draw(ax, t0, several)
        ax.grid(True, alpha=0.3)
        for t, _, _ in data.failsafe:
            ax.axvline(t - t0, color="red", linestyle="--", linewidth=1, gid="failsafe")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title, y=0.995)
    fig.tight_layout()  # the axes' final width first: the labels are placed on it
    annotations, left_out = place_labels(fig, axes[0], labels, t0)
    if left_out:
        axes[0].set_title(f"{len(left_out)} more labels not shown (their marks are drawn)",
                          loc="right", fontsize=7, color="red")
    if annotations:  # room above the top panel for the rows of labels, same widths
        rows_used = 1 + max(round((a.xyann[1] - 2) / LABEL_ROW_PT) for a in annotations)
        top = fig.subplotpars.top - (rows_used * LABEL_ROW_PT + 10) / 72.0 / fig.get_figheight()
        fig.subplots_adjust(top=top)
    fig.savefig(out_path, dpi=100)
    return Drawn(fig, t0, axes, annotations, left_out)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("bags", nargs="+", metavar="bag",
                   help="one or more bags (several: one figure, e.g. a bag per bus of a robot)")
    p.add_argument("-o", "--output", default="telemetry.png")
    p.add_argument("--node", help="only this bus node (e.g. /my_robot/io_bus); default: every one in the bags")
    args = p.parse_args()
    data = load(args.bags, args.node.rstrip("/") if args.node else None)
    if data.empty():
        where = f" under {args.node}/" if args.node else ""
        print(f"{', '.join(args.bags)}: no bus node's telemetry, outputs, signals or fail-safe "
              f"events{where}", file=sys.stderr)
        return 1
    plot(data, args.output, ", ".join(os.path.basename(b) for b in args.bags))
    print(f"wrote {args.output}: bus node(s) {', '.join(data.nodes())}; "
          f"{sum(map(len, data.telemetry.values()))} telemetry samples, "
          f"{sum(map(len, data.outputs.values()))} output messages, "
          f"{sum(map(len, data.signals.values()))} signal messages, "
          f"{len(data.failsafe)} fail-safe events")
    return 0


if __name__ == "__main__":
    sys.exit(main())
