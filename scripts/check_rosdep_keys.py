#!/usr/bin/env python3
"""package.xml's keys against rosdep, offline: every key must resolve to packages on each platform
ROS 1 users build on (Ubuntu focal/jammy/noble, Debian bookworm/trixie), as `rosdep install
--from-paths . --ignore-src` would resolve it. rosdep itself needs the network and a rosdep init,
so the check reads a snapshot of the relevant entries of ros/rosdistro, kept in
test/data/rosdep_snapshot.yaml with the date and the rosdistro commit it was taken from:
  - system keys (rosdep/base.yaml, rosdep/python.yaml): the entry as rosdistro has it;
  - ROS package keys (roscpp, rostest, ...): the repository releasing each in noetic's
    distribution.yaml (ROS-O and Debian's/Ubuntu's own ROS packages provide the same names).
A key missing from the snapshot is not a rosdep key (rosdep stops with "Cannot locate rosdep
definition"). A key resolving to nothing on a platform fails unless the snapshot's
`resolves_to_nothing` names that key and platform with what stands in for it there.

Usage: check_rosdep_keys.py RESULTS_DIR             the check, one JUnit case in RESULTS_DIR
       check_rosdep_keys.py RESULTS_DIR --self-test  the check fails on a package.xml with a
                                                     non-key (xxd) and an unhandled gap
       check_rosdep_keys.py --snapshot ROSDISTRO_DIR COMMIT DATE   rewrites the snapshot from a
                                                     checkout of ros/rosdistro (see take_snapshot)
"""
import argparse
import datetime
import os
import re
import sys
import tempfile
import xml.etree.ElementTree as ET

import yaml

REPO = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
SNAPSHOT = os.path.join(REPO, "test", "data", "rosdep_snapshot.yaml")
PLATFORMS = [("ubuntu", "focal"), ("ubuntu", "jammy"), ("ubuntu", "noble"),
             ("debian", "bookworm"), ("debian", "trixie")]


def package_keys(path):
    root = ET.parse(path).getroot()
    return sorted({el.text.strip() for el in root if el.tag.endswith("depend") and el.text})


def resolve(entry, os_name, codename):
    """rosdep's reading of a base.yaml entry: the packages for (os, codename); [] for nothing
    (a null entry), None when the entry has no rule for the platform at all."""
    if not isinstance(entry, dict) or os_name not in entry:
        return None
    rule = entry[os_name]
    if isinstance(rule, dict) and not any(k in rule for k in ("apt", "pip", "source")):
        if codename not in rule and "*" not in rule:
            return None  # rules for other releases only
        rule = rule[codename] if codename in rule else rule["*"]
    if isinstance(rule, dict):  # installer form: {apt: {packages: [...]}} or {apt: [...]}
        rule = rule.get("apt", rule.get("pip"))
        if isinstance(rule, dict):
            rule = rule.get("packages")
    if rule is None:
        return []
    return [rule] if isinstance(rule, str) else list(rule)


def problems_for(keys, snap):
    problems, notes = [], []
    system, ros = snap["system_keys"], snap["ros_packages"]
    gaps = snap.get("resolves_to_nothing") or {}
    for key in keys:
        if key in ros:
            continue
        if key not in system:
            problems.append(f"'{key}' is not a rosdep key (not in rosdistro's rosdep/*.yaml nor a "
                            f"noetic package): rosdep install stops at it")
            continue
        for os_name, codename in PLATFORMS:
            got = resolve(system[key], os_name, codename)
            where = f"{os_name} {codename}"
            if got:
                continue
            handled = (gaps.get(key) or {}).get(codename)
            if handled:
                notes.append(f"{key} on {where}: resolves to nothing; {handled}")
            else:
                problems.append(f"'{key}' resolves to {'nothing' if got == [] else 'no rule'} on "
                                f"{where} and the snapshot names no stand-in for it")
    return problems, notes


def write_case(results, name, problems):
    os.makedirs(results, exist_ok=True)
    body = f'<testcase classname="rosdep" name="{name}"/>'
    if problems:
        msg = "; ".join(problems).replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")
        body = f'<testcase classname="rosdep" name="{name}"><failure message="{msg}"/></testcase>'
    with open(os.path.join(results, name + ".xml"), "w", encoding="utf-8") as f:
        f.write(f'<testsuite name="rosdep" tests="1">{body}</testsuite>\n')


def check(results, package_xml, snapshot_path, name):
    snap = yaml.safe_load(open(snapshot_path, encoding="utf-8"))
    keys = package_keys(package_xml)
    problems, notes = problems_for(keys, snap)
    print(f"rosdep keys: {len(keys)} keys of {os.path.relpath(package_xml, REPO)} on "
          f"{', '.join(c for _, c in PLATFORMS)} (snapshot of rosdistro {snap['rosdistro_commit'][:12]}, "
          f"taken {snap['taken']})")
    for line in notes + problems:
        print("  " + line)
    if results:
        write_case(results, name, problems)
    return problems


def self_test(results):
    """The check can fail: a package.xml with a non-key and a snapshot without the cli11 stand-in."""
    snap = yaml.safe_load(open(SNAPSHOT, encoding="utf-8"))
    snap["resolves_to_nothing"] = {}
    with tempfile.TemporaryDirectory() as tmp:
        xml = os.path.join(tmp, "package.xml")
        with open(xml, "w", encoding="utf-8") as f:
            f.write('<package format="3"><name>x</name><test_depend>xxd</test_depend>'
                    '<build_depend>cli11</build_depend><depend>roscpp</depend></package>')
        bare = os.path.join(tmp, "snapshot.yaml")
        with open(bare, "w", encoding="utf-8") as f:
            yaml.safe_dump(snap, f)
        found = check(None, xml, bare, "")
    wanted = ["'xxd' is not a rosdep key", "'cli11' resolves to nothing on ubuntu focal"]
    problems = [f"the check did not report: {w}" for w in wanted if not any(w in p for p in found)]
    problems += [f"the check reported a real key: {p}" for p in found if "roscpp" in p]
    write_case(results, "rosdep_check_fails_on_bad_keys", problems)
    return problems


def take_snapshot(rosdistro_dir, commit, date):
    """From a checkout of ros/rosdistro at `commit` (for a bare clone: git --git-dir=CLONE archive
    HEAD rosdep noetic | tar -x -C DIR; commit and date: git --git-dir=CLONE log -1 --format='%H %cI')."""
    def show(path):
        return open(os.path.join(rosdistro_dir, path), encoding="utf-8").read()
    entries = {}
    for f in ("rosdep/base.yaml", "rosdep/python.yaml"):
        entries.update(yaml.safe_load(show(f)))
    dist = yaml.safe_load(show("noetic/distribution.yaml"))
    released = {}
    for repo, r in dist["repositories"].items():
        rel = r.get("release") or {}
        for p in rel.get("packages", [repo] if rel else []):
            released[p] = repo
    old = yaml.safe_load(open(SNAPSHOT, encoding="utf-8")) if os.path.exists(SNAPSHOT) else {}
    keys = package_keys(os.path.join(REPO, "package.xml"))
    snap = {
        "taken": datetime.date.today().isoformat(),
        "rosdistro_commit": commit,
        "rosdistro_commit_date": date,
        "system_keys": {k: {os_name: rule for os_name, rule in entries[k].items()
                            if os_name in ("debian", "ubuntu")} for k in keys if k in entries},
        "ros_packages": {k: released[k] for k in keys if k in released and k not in entries},
        "resolves_to_nothing": old.get("resolves_to_nothing", {}),
    }
    header = ("# The rosdep entries (debian, ubuntu) of package.xml's keys, from ros/rosdistro (rosdep/base.yaml,\n"
              "# rosdep/python.yaml; ROS packages: the repository releasing them in noetic's\n"
              "# distribution.yaml). Written by scripts/check_rosdep_keys.py --snapshot; read by\n"
              "# the same script in the test command. resolves_to_nothing: the keys that rosdep\n"
              "# resolves to no package on a platform, and what stands in for them there\n"
              "# (kept by hand across snapshots).\n")
    with open(SNAPSHOT, "w", encoding="utf-8") as f:
        f.write(header + yaml.safe_dump(snap, sort_keys=False, width=100))
    print(f"wrote {SNAPSHOT}: {len(snap['system_keys'])} system keys, "
          f"{len(snap['ros_packages'])} ROS packages, rosdistro {commit[:12]}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("results", nargs="?")
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("--snapshot", nargs=3, metavar=("ROSDISTRO_DIR", "COMMIT", "DATE"))
    args = ap.parse_args()
    if args.snapshot:
        take_snapshot(*args.snapshot)
        return 0
    if not args.results:
        ap.error("RESULTS_DIR needed")
    if args.self_test:
        return 1 if self_test(args.results) else 0
    return 1 if check(args.results, os.path.join(REPO, "package.xml"), SNAPSHOT,
                      "rosdep_keys_resolve") else 0


if __name__ == "__main__":
    sys.exit(main())
