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
"""
import argparse
import collections
import os
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
}
FAILSAFE_TYPE = "modbus_rtu_driver/FailsafeEvent"
TELEMETRY_ROWS = [("power", "W"), ("voltage", "V"), ("current", "A"), ("temperature", "°C")]


class BagData:
    def __init__(self):
        self.telemetry = collections.defaultdict(list)  # (node, device) -> [(t, msg)]
        self.outputs = collections.defaultdict(list)
        self.signals = collections.defaultdict(list)
        self.failsafe = []  # (t, node, msg)

    def nodes(self):
        keys = list(self.telemetry) + list(self.outputs) + list(self.signals)
        return sorted({n for n, _ in keys} | {n for _, n, _ in self.failsafe})

    def empty(self):
        return not (self.telemetry or self.outputs or self.signals or self.failsafe)

    def of_node(self, node):
        """This data's part of one bus node."""
        out = BagData()
        for kind in ("telemetry", "outputs", "signals"):
            for key, samples in getattr(self, kind).items():
                if key[0] == node:
                    getattr(out, kind)[key] = samples
        out.failsafe = [e for e in self.failsafe if e[1] == node]
        return out


def stamp_of(msg, t):
    stamp = getattr(getattr(msg, "header", None), "stamp", None)
    return stamp.to_sec() if stamp and stamp.to_sec() > 0 else t.to_sec()


def load(bag_paths, only_node=None):
    data = BagData()
    for bag_path in bag_paths:
        load_one(bag_path, only_node, data)
    for series in (data.telemetry, data.outputs, data.signals):
        for samples in series.values():
            samples.sort(key=lambda s: s[0])  # split files given in any order
    data.failsafe.sort(key=lambda e: e[0])
    return data


def load_one(bag_path, only_node, data):
    with rosbag.Bag(bag_path) as bag:
        types = {topic: info.msg_type for topic, info in bag.get_type_and_topic_info().topics.items()}
        wanted = []
        for topic, msg_type in types.items():
            if msg_type == FAILSAFE_TYPE and topic.endswith("/failsafe"):
                wanted.append(topic)
            elif msg_type in DEVICE_TOPICS and topic.count("/") >= 3:
                wanted.append(topic)  # /NODE.../DEVICE/LEAF
        for topic, msg, t in bag.read_messages(topics=wanted):
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
            if kind == "outputs" and leaf != "outputs":
                continue  # the LC board's inputs: not plotted
            getattr(data, kind)[(node, device)].append((stamp_of(msg, t), msg))


def label(node, device, several_nodes):
    return f"{node}/{device}" if several_nodes else device


def panels(data):
    """[(height in inches, draw(ax, t0, several_nodes))] in the order shown: each bus node's
    panels together (a robot's bags: one bus after the other), nodes in name order."""
    return [row for node in data.nodes() for row in node_panels(data.of_node(node))]


def node_panels(data):
    """One bus node's panels: PDU telemetry, signals by unit, each device's outputs."""
    out = []
    if data.telemetry:
        for i, (field, unit) in enumerate(TELEMETRY_ROWS):
            def draw(ax, t0, several, field=field, unit=unit, first=i == 0):
                for (node, device), samples in sorted(data.telemetry.items()):
                    ax.plot([s - t0 for s, _ in samples], [getattr(m, field) for _, m in samples],
                            label=label(node, device, several))
                ax.set_ylabel(f"{field} [{unit}]")
                if first:
                    ax.legend(loc="upper right", fontsize=8)
            out.append((1.6, draw))
    by_unit = collections.defaultdict(list)  # unit -> [(label parts, times, values)]
    for (node, device), samples in sorted(data.signals.items()):
        names = samples[-1][1].names
        units = list(getattr(samples[-1][1], "units", []) or [""] * len(names))
        for i, name in enumerate(names):
            ts = [s for s, m in samples if i < len(m.values) and (i >= len(m.valid) or m.valid[i])]
            vs = [m.values[i] for _, m in samples if i < len(m.values) and (i >= len(m.valid) or m.valid[i])]
            if ts:
                by_unit[units[i] if i < len(units) else ""].append(((node, device, name), ts, vs))
    for unit, lines in sorted(by_unit.items()):
        def draw(ax, t0, several, unit=unit, lines=lines):
            for (node, device, name), ts, vs in lines:
                ax.plot([t - t0 for t in ts], vs, label=f"{label(node, device, several)}/{name}",
                        drawstyle="steps-post" if not unit else "default")
            ax.set_ylabel(f"[{unit}]" if unit else "(no unit)")
            ax.legend(loc="upper right", fontsize=8)
        out.append((1.6, draw))
    for (node, device), samples in sorted(data.outputs.items()):
        names = list(samples[-1][1].names) or [f"out{i}" for i in range(len(samples[-1][1].states))]

        def draw(ax, t0, several, node=node, device=device, samples=samples, names=names):
            ts = [s - t0 for s, _ in samples]
            for ch in range(len(names)):
                ys = [ch + (0.7 if m.states[ch] else 0.0) if ch < len(m.states) else float("nan")
                      for _, m in samples]
                ax.step(ts, ys, where="post", linewidth=1.5)
                ax.fill_between(ts, ch, ys, step="post", alpha=0.25)
            ax.set_yticks([ch + 0.35 for ch in range(len(names))])
            ax.set_yticklabels(names, fontsize=8)
            ax.set_ylim(-0.2, len(names))
            ax.set_ylabel(label(node, device, several), rotation=0, ha="right", va="center")
        out.append((0.35 + 0.22 * len(names), draw))
    return out


def plot(data, out_path, title):
    rows = panels(data)
    if not rows:  # only fail-safe events: an empty time axis with their marks
        rows = [(1.0, lambda ax, t0, several: ax.set_yticks([]))]
    heights = [h for h, _ in rows]
    fig, axes = plt.subplots(len(rows), 1, sharex=True, squeeze=False,
                             figsize=(11, sum(heights) + 1.2),
                             gridspec_kw={"height_ratios": heights})
    axes = [a[0] for a in axes]
    times = [s for series in (data.telemetry, data.outputs, data.signals)
             for samples in series.values() for s, _ in samples] + [t for t, _, _ in data.failsafe]
    t0 = min(times, default=0.0)
    several = len(data.nodes()) > 1
    for ax, (_, draw) in zip(axes, rows):
        draw(ax, t0, several)
        ax.grid(True, alpha=0.3)
        for t, _, _ in data.failsafe:
            ax.axvline(t - t0, color="red", linestyle="--", linewidth=1)
    for t, node, msg in data.failsafe:  # what happened, above the top panel
        axes[0].annotate(f"fail-safe: {label(node, msg.device, several)} {msg.trigger}",
                         xy=(t - t0, 1.0), xycoords=("data", "axes fraction"),
                         xytext=(2, 2), textcoords="offset points", rotation=20,
                         fontsize=7, color="red", va="bottom")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title, y=0.995)
    fig.tight_layout()
    fig.savefig(out_path, dpi=100)


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
