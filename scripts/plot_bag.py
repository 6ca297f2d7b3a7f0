#!/usr/bin/python3
"""Plots a bag recorded by bus.launch / demo.launch (record:=true) to a PNG: PDU power, voltage,
current and temperature over time, and every device's outputs as step lines.

    scripts/plot_bag.py my.bag -o power.png [--node /modbus_bus]
"""
import argparse
import collections
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import rosbag  # noqa: E402


def load(bag_path, node):
    telemetry = collections.defaultdict(list)  # device -> [(t, msg)]
    outputs = collections.defaultdict(list)
    with rosbag.Bag(bag_path) as bag:
        for topic, msg, t in bag.read_messages():
            if not topic.startswith(node + "/"):
                continue
            device, _, leaf = topic[len(node) + 1:].rpartition("/")
            stamp = msg.header.stamp.to_sec() if hasattr(msg, "header") and msg.header.stamp else t.to_sec()
            if leaf == "telemetry":
                telemetry[device].append((stamp, msg))
            elif leaf == "outputs":
                outputs[device].append((stamp, msg))
    return telemetry, outputs


def plot(telemetry, outputs, out_path, title):
    rows = [("power", "W"), ("voltage", "V"), ("current", "A"), ("temperature", "°C")]
    n = len(rows) + (1 if outputs else 0)
    fig, axes = plt.subplots(n, 1, sharex=True, figsize=(10, 2.2 * n), squeeze=False)
    axes = [a[0] for a in axes]
    t0 = min([s[0][0] for s in list(telemetry.values()) + list(outputs.values()) if s], default=0.0)
    for ax, (field, unit) in zip(axes, rows):
        for device, samples in telemetry.items():
            ax.plot([s - t0 for s, _ in samples], [getattr(m, field) for _, m in samples], label=device)
        ax.set_ylabel(f"{field} [{unit}]")
        ax.grid(True, alpha=0.3)
    if telemetry:
        axes[0].legend(loc="upper right")
    if outputs:
        ax = axes[-1]
        level = 0
        ticks, labels = [], []
        for device, samples in sorted(outputs.items()):
            names = samples[-1][1].names or [f"out{i}" for i in range(len(samples[-1][1].states))]
            for ch, name in enumerate(names):
                ts = [s - t0 for s, _ in samples]
                ys = [level + (0.8 if m.states[ch] else 0.0) for _, m in samples if ch < len(m.states)]
                ax.step(ts[:len(ys)], ys, where="post")
                ticks.append(level + 0.4)
                labels.append(f"{device}/{name}")
                level += 1
        ax.set_yticks(ticks)
        ax.set_yticklabels(labels, fontsize=7)
        ax.set_ylabel("outputs")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(out_path, dpi=100)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("bag")
    p.add_argument("-o", "--output", default="telemetry.png")
    p.add_argument("--node", default="/modbus_bus", help="the bus node's namespace")
    args = p.parse_args()
    telemetry, outputs = load(args.bag, args.node.rstrip("/"))
    if not telemetry and not outputs:
        print(f"{args.bag}: no telemetry or outputs under {args.node}/", file=sys.stderr)
        return 1
    plot(telemetry, outputs, args.output, os.path.basename(args.bag))
    print(f"wrote {args.output}: {sum(map(len, telemetry.values()))} telemetry samples, "
          f"{sum(map(len, outputs.values()))} output messages")
    return 0


if __name__ == "__main__":
    sys.exit(main())
