#!/usr/bin/env python3
"""`rosdep install` itself on package.xml, offline, for each platform ROS 1 users build on.

rosdep (Debian's python3-rosdep2) runs with a sources list written into a fresh folder, never
/etc/ros or ~/.ros (ROSDEP_SOURCE_PATH, ROS_HOME and HOME point into it), whose sources are the
repository's snapshot in test/data/rosdep/ (file:// URLs), laid out as a Debian system with
python3-rosdep2 has them:
  10-debian.list   debian.yaml, tag debian: Debian's own rosdep list (the ROS packages Debian
                   ships itself: roscpp -> libroscpp-dev, ...), from python3-rosdep2;
  20-default.list  base.yaml, python.yaml: ros/rosdistro's rosdep/*.yaml entries;
  and as the rosdistro index (ROSDISTRO_INDEX_URL) index.yaml with noetic/distribution.yaml,
  which gives the ROS packages' ros-noetic-* names on Ubuntu 20.04.
Then, after `rosdep update --rosdistro noetic` from those sources:
  ubuntu:focal, debian:bullseye, debian:bookworm, debian:trixie:
      rosdep install --simulate --from-paths PKGDIR --ignore-src --os=OS:CODENAME
                     [--rosdistro noetic]
      (--rosdistro noetic on focal only: on Debian the ROS packages come from Debian's list)
  ubuntu:jammy, ubuntu:noble: rosdistro has no rules there for the ROS packages (Ubuntu's own
      universe packages provide them), so each system key (a key of `rosdep keys` that is not a
      package noetic releases) must resolve: rosdep resolve KEY --os=ubuntu:CODENAME
Any failure names the platform and rosdep's message (which names the key).

Usage: check_rosdep.py RESULTS_DIR [--work DIR] [--pkgdir DIR]  the check of package.xml (or of
                                                             DIR's); one JUnit case per platform
       check_rosdep.py RESULTS_DIR --self-test [--work DIR]  the check fails on package.xml with
                                                             the cli11 key it had until issue 33
       check_rosdep.py --snapshot ROSDISTRO_GIT_DIR DEBIAN_YAML   rewrites test/data/rosdep/ from
              a clone of ros/rosdistro (its HEAD) and python3-rosdep2's debian.yaml
              (/usr/share/python3-rosdep2/debian.yaml), keeping the entries of package.xml's keys
              and of EXTRA_KEYS
--work DIR: where the sources list and rosdep's cache go (a fresh folder inside it, removed
after); default a temporary folder.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import yaml

REPO = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
DATA = os.path.join(REPO, "test", "data", "rosdep")
JUNIT = os.path.join(REPO, "scripts", "junit.py")
INSTALL_PLATFORMS = [("ubuntu", "focal"), ("debian", "bullseye"), ("debian", "bookworm"),
                     ("debian", "trixie")]
RESOLVE_PLATFORMS = [("ubuntu", "jammy"), ("ubuntu", "noble")]
# Keys kept in the snapshot beyond package.xml's: the self-test's package.xml carries cli11, and
# must fail as it does against the real rosdistro ("not available" on focal), not for a key the
# snapshot left out.
EXTRA_KEYS = ["cli11"]
# The self-test's key and what rosdep says about it (rosdep 0.22.1, rosdistro 8468e88).
OLD_KEY = "<build_depend>cli11</build_depend>"
OLD_KEY_MESSAGE = '[cli11] defined as "not available" for OS version [focal]'


def package_keys(path):
    root = ET.parse(path).getroot()
    return sorted({el.text.strip() for el in root if el.tag.endswith("depend") and el.text})


def ros_packages():
    """The package names noetic releases (snapshot's noetic/distribution.yaml)."""
    dist = yaml.safe_load(open(os.path.join(DATA, "noetic", "distribution.yaml"), encoding="utf-8"))
    names = set()
    for repo, entry in dist["repositories"].items():
        release = entry.get("release") or {}
        if release:
            names.update(release.get("packages", [repo]))
    return names


class Rosdep:
    """rosdep with sources and cache of its own in `folder`, the snapshot as its sources."""

    def __init__(self, folder):
        self.folder = folder
        sources = os.path.join(folder, "sources.list.d")
        os.makedirs(sources)
        os.makedirs(os.path.join(folder, "home"))
        with open(os.path.join(sources, "10-debian.list"), "w", encoding="utf-8") as f:
            f.write(f"yaml file://{DATA}/debian.yaml debian\n")
        with open(os.path.join(sources, "20-default.list"), "w", encoding="utf-8") as f:
            f.write(f"yaml file://{DATA}/base.yaml\nyaml file://{DATA}/python.yaml\n")
        self.env = {
            "PATH": "/usr/bin:/bin",
            "HOME": os.path.join(folder, "home"),
            "ROS_HOME": os.path.join(folder, "ros_home"),
            "ROSDEP_SOURCE_PATH": sources,
            "ROSDISTRO_INDEX_URL": f"file://{DATA}/index.yaml",
            "ROS_PYTHON_VERSION": "3",
            "LANG": "C.UTF-8",
        }

    def command(self, *args):
        p = subprocess.run(["/usr/bin/rosdep", *args], env=self.env, capture_output=True,
                           text=True, timeout=300)
        return p.returncode, (p.stdout + p.stderr).strip()


def key_lines(out):
    """rosdep's lines that name a key ("pkg: [key] defined as ...", "ERROR: no rosdep rule for
    'key'") first, so that the JUnit message's first line names it; then the rest."""
    lines = [line.strip() for line in out.splitlines() if line.strip()]
    named = [line for line in lines if re.search(r"\[[^]]+\]|rule for '", line)
             and not line.startswith("#")]
    text = " ".join(named + [line for line in lines if line not in named])
    if "Cannot locate rosdep definition" in text or "no rosdep rule for" in text:
        text += (" (not in test/data/rosdep: if rosdistro has the key, retake the snapshot with "
                 "scripts/check_rosdep.py --snapshot)")
    return text


def indent(text):
    return "\n".join("    " + line for line in text.splitlines())


def check(pkgdir, work):
    """Returns [(case name, failure message or "")] and prints what rosdep said."""
    cases = []
    os.makedirs(work, exist_ok=True)
    folder = tempfile.mkdtemp(prefix="rosdep.", dir=work)
    try:
        rosdep = Rosdep(folder)
        rc, out = rosdep.command("update", "--rosdistro", "noetic", "--include-eol-distros")
        print(f"$ rosdep update --rosdistro noetic --include-eol-distros   (exit {rc})\n"
              + indent(out))
        if rc != 0:
            return [("rosdep_update", f"rosdep update from the snapshot failed: {out}")]
        for os_name, codename in INSTALL_PLATFORMS:
            args = ["install", "--simulate", "--from-paths", pkgdir, "--ignore-src",
                    f"--os={os_name}:{codename}"]
            if os_name == "ubuntu":
                args += ["--rosdistro", "noetic"]
            rc, out = rosdep.command(*args)
            print(f"$ rosdep {' '.join(args)}   (exit {rc})\n{indent(out)}")
            cases.append((f"rosdep_install_{codename}", "" if rc == 0 else
                          f"{os_name}:{codename}: {key_lines(out)} "
                          f"(rosdep install --simulate, exit {rc})"))
        rc, out = rosdep.command("keys", "--from-paths", pkgdir, "--ignore-src")
        if rc != 0:
            return cases + [("rosdep_keys", f"rosdep keys failed: {out}")]
        ros = ros_packages()
        system = sorted(set(out.split()) - ros)
        print(f"system keys (rosdep keys minus the packages noetic releases): {' '.join(system)}")
        for os_name, codename in RESOLVE_PLATFORMS:
            failed, resolved = [], []
            for key in system:
                rc, out = rosdep.command("resolve", key, f"--os={os_name}:{codename}")
                if rc != 0:
                    failed.append(f"{key}: {key_lines(out).splitlines()[0][:300]}")
                else:
                    packages = out.split()[1:] if out.startswith("#") else out.split()  # "#apt"
                    resolved.append(f"{key} -> {' '.join(packages)}")
            print(f"$ rosdep resolve KEY --os={os_name}:{codename}   for each of the {len(system)} "
                  f"system keys: {len(failed)} failed\n" + indent("\n".join(failed or resolved)))
            cases.append((f"rosdep_resolve_system_keys_{codename}", "" if not failed else
                          f"{os_name}:{codename}: " + "; ".join(failed)))
        return cases
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def write_cases(results, file_name, cases):
    os.makedirs(results, exist_ok=True)
    subprocess.run([sys.executable, JUNIT, os.path.join(results, file_name + ".xml"), "rosdep"] +
                   [f"{name}={msg}" if msg else name for name, msg in cases], check=True)


def self_test(work):
    """The check fails on package.xml with the cli11 key, naming it and focal."""
    os.makedirs(work, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="rosdep_selftest.", dir=work) as tmp:
        pkgdir = os.path.join(tmp, "modbus_rtu_driver")
        os.makedirs(pkgdir)
        text = open(os.path.join(REPO, "package.xml"), encoding="utf-8").read()
        text = re.sub(r"(\n\s*<build_depend>message_generation</build_depend>)",
                      r"\1\n  " + OLD_KEY, text, count=1)
        if OLD_KEY not in text:
            return [("rosdep_fails_on_cli11_key", "could not add the cli11 key to package.xml")]
        with open(os.path.join(pkgdir, "package.xml"), "w", encoding="utf-8") as f:
            f.write(text)
        cases = check(pkgdir, work)
    focal = dict(cases).get("rosdep_install_focal")
    if focal is None:
        problem = f"the check did not get to focal: {cases}"
    elif not focal:
        problem = "rosdep install --simulate passed on focal with the cli11 key"
    elif OLD_KEY_MESSAGE not in focal:
        problem = f"focal failed without rosdep's message {OLD_KEY_MESSAGE}: {focal}"
    else:
        problem = ""
    others = [name for name, msg in cases if msg and name != "rosdep_install_focal"]
    if not problem and others:
        problem = f"the cli11 key failed elsewhere too, where it should resolve: {others}"
    print("self-test: " + (problem or f"OK: the check fails on focal with: {OLD_KEY_MESSAGE}"))
    return [("rosdep_fails_on_cli11_key", problem)]


def take_snapshot(rosdistro_git, debian_yaml):
    def show(path):
        return subprocess.run(["git", "--git-dir", rosdistro_git, "show", f"HEAD:{path}"],
                              check=True, capture_output=True, text=True).stdout
    commit, date = subprocess.run(["git", "--git-dir", rosdistro_git, "log", "-1",
                                   "--format=%H %cI"], check=True, capture_output=True,
                                  text=True).stdout.split()
    keys = sorted(set(package_keys(os.path.join(REPO, "package.xml"))) | set(EXTRA_KEYS))
    source = f"ros/rosdistro {commit} ({date})"
    os.makedirs(os.path.join(DATA, "noetic"), exist_ok=True)

    def write(name, header, data):
        with open(os.path.join(DATA, name), "w", encoding="utf-8") as f:
            f.write("".join(f"# {line}\n" for line in header) +
                    yaml.safe_dump(data, sort_keys=True, width=100))

    rule = ("The entries of package.xml's keys (and EXTRA_KEYS) only; rewritten by "
            "scripts/check_rosdep.py --snapshot.")
    for name in ("base.yaml", "python.yaml"):
        entries = yaml.safe_load(show(f"rosdep/{name}"))
        write(name, [f"rosdep/{name} of {source}.", rule],
              {k: v for k, v in entries.items() if k in keys})
    dist = yaml.safe_load(show("noetic/distribution.yaml"))
    repos = {}
    for repo, entry in dist["repositories"].items():
        release = entry.get("release") or {}
        if release and set(release.get("packages", [repo])) & set(keys):
            repos[repo] = entry
    write("noetic/distribution.yaml",
          [f"noetic/distribution.yaml of {source}.",
           "The repositories releasing package.xml's keys only; rewritten by "
           "scripts/check_rosdep.py --snapshot."],
          {k: v for k, v in dist.items() if k != "repositories"} | {"repositories": repos})
    index = yaml.safe_load(show("index-v4.yaml"))
    noetic = {k: v for k, v in index["distributions"]["noetic"].items()
              if k != "distribution_cache"}  # no cache: rosdistro reads distribution.yaml
    write("index.yaml", [f"index-v4.yaml of {source}, noetic only, without its cache URL.",
                         "Rewritten by scripts/check_rosdep.py --snapshot."],
          {k: v for k, v in index.items() if k != "distributions"} |
          {"distributions": {"noetic": noetic}})
    version = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-rosdep2"],
                             capture_output=True, text=True).stdout or "unknown version"
    entries = yaml.safe_load(open(debian_yaml, encoding="utf-8"))
    write("debian.yaml", [f"Debian's own rosdep list: {debian_yaml} of python3-rosdep2 {version},",
                          "the ROS packages Debian ships itself. " + rule],
          {k: v for k, v in entries.items() if k in keys})
    print(f"wrote {DATA}: {source}, {len(keys)} keys, {len(repos)} noetic repositories, "
          f"Debian's list of python3-rosdep2 {version}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("results", nargs="?")
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("--work", default=None)
    ap.add_argument("--pkgdir", default=REPO, help="the package to check (default: this one)")
    ap.add_argument("--snapshot", nargs=2, metavar=("ROSDISTRO_GIT_DIR", "DEBIAN_YAML"))
    args = ap.parse_args()
    if args.snapshot:
        take_snapshot(*args.snapshot)
        return 0
    if not args.results:
        ap.error("RESULTS_DIR needed")
    if not os.access("/usr/bin/rosdep", os.X_OK):
        cases = [("rosdep_self_test" if args.self_test else "rosdep_install",
                  "/usr/bin/rosdep missing (python3-rosdep2, scripts/debian_packages.txt)")]
        write_cases(args.results, "rosdep_self_test" if args.self_test else "rosdep", cases)
        print(cases[0][1])
        return 1
    work = args.work or tempfile.mkdtemp(prefix="check_rosdep.")
    try:
        if args.self_test:
            cases = self_test(work)
            write_cases(args.results, "rosdep_self_test", cases)
        else:
            cases = check(os.path.abspath(args.pkgdir), work)
            write_cases(args.results, "rosdep", cases)
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)
    failed = [name for name, msg in cases if msg]
    print(f"rosdep: {len(cases) - len(failed)} of {len(cases)} passed"
          + (f"; failed: {' '.join(failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
