#!/usr/bin/env python3
"""Fails when the project uses something that a fresh machine would not have.

What the project uses:
  - every Python module that its Python files import (ast, top-level names);
  - every executable that its scripts, launch files and tests call (command words of the shell
    scripts, subprocess calls of the Python files, <node>/<test> packages of the launch files);
  - every header outside the repository and the workspace that the compiler read (the build's
    dependency files, *.o.d and depend.make).
Each one is traced to the Debian package that owns it (dpkg -S). The check fails, naming those
packages, unless the package is on scripts/debian_packages.txt, in that list's dependency closure
(apt-cache depends --recurse, no recommends: the scripts install without them), or part of every
Debian root (the Essential packages and apt, as in a minbase root). It also checks that package.xml declares the list.

Usage: check_deps.py WORKSPACE RESULTS_DIR [--without PKG,PKG]   (--without: drop packages from
the list, to show that the check fails on the list as it was before they were added).
"""
import argparse
import ast
import glob
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import junit  # noqa: E402  (scripts/junit.py, the one writer of result files)

REPO = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
# Scripts that install their own tools and run outside the test command (cross_check.sh from
# scripts/cross_packages.txt); callgrind_node.py, a measurement outside scripts/benchmark.sh, needs
# valgrind and says so when it is missing.
NOT_SCANNED = {"scripts/fresh_check.sh", "scripts/cross_check.sh", "bench/callgrind_node.py"}
# package.xml keys (rosdep names) and the Debian packages each one stands for here.
ROSDEP_TO_DEBIAN = {
    "catkin": ["ros-core-dev", "build-essential", "cmake", "pkg-config"],
    "roscpp": ["ros-core-dev"],
    "rospy": ["ros-core-dev"],
    "roslaunch": ["ros-core-dev"],
    "std_msgs": ["ros-core-dev"],
    "std_srvs": ["libstd-srvs-dev", "python3-std-srvs"],
    "diagnostic_msgs": ["python3-diagnostic-msgs"],
    "diagnostic_updater": ["libdiagnostic-updater-dev"],
    "topic_tools": ["libtopic-tools-dev"],
    "message_generation": ["ros-message-generation"],
    "message_runtime": ["ros-core-dev"],
    "rosbag": ["librosbag-dev", "python3-rosbag"],
    "rosbash": ["rosbash"],
    "rostest": ["python3-rostest", "librostest-dev"],
    "rosunit": ["python3-rostest"],
    "gtest": ["libgtest-dev"],
    "libmodbus-dev": ["libmodbus-dev"],
    "yaml-cpp": ["libyaml-cpp-dev"],
    "nlohmann-json-dev": ["nlohmann-json3-dev"],
    "python3-yaml": ["python3-yaml"],
    "python3-matplotlib": ["python3-matplotlib"],
    "python3-pymodbus": ["python3-pymodbus"],
    "python3-hypothesis": ["python3-hypothesis"],
    "iproute2": ["iproute2"],
    "python3-catkin-lint": ["catkin-lint"],
    "clang-format": ["clang-format"],
    "clang-tidy": ["clang-tidy"],
    "git": ["git"],
    "clang": ["clang"],
}
SHELL_SKIP = {
    "if", "then", "else", "elif", "fi", "for", "while", "until", "do", "done", "case", "esac",
    "in", "function", "return", "exit", "local", "export", "set", "unset", "source", ".", "!",
    "exec", "time", "sudo", "env", "eval", "trap", "wait", "kill", "shift", "cd", "echo",
    "printf", "read", "mapfile", "declare", "true", "false", "test", "[", "[[", "{", "}", "break",
    "continue", "command", "builtin", "let", "type", "hash", "ulimit", "umask",
}


def sh(*cmd):
    return subprocess.run(cmd, capture_output=True, text=True, check=False).stdout


def repo_files(pattern):
    return sorted(
        p for p in glob.glob(os.path.join(REPO, pattern), recursive=True)
        if os.path.relpath(p, REPO) not in NOT_SCANNED and "/.git/" not in p)


def python_modules():
    """Top-level names imported by the project's Python files, with the files importing them."""
    used = {}
    for path in repo_files("**/*.py"):
        tree = ast.parse(open(path, encoding="utf-8").read(), path)
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            for n in names:
                used.setdefault(n.split(".")[0], set()).add(os.path.relpath(path, REPO))
    return used


def shell_commands(text):
    """Command words of a shell script (a reading good enough for this project's scripts)."""
    words = set()
    for line in text.splitlines():
        line = re.sub(r"(^|\s)#.*", "", line)
        for piece in re.split(r"\|\||&&|[|;&`]|\$\(|\(|\bthen\b|\bdo\b|\belse\b", line):
            tokens = piece.split()
            while tokens and (re.match(r"^[A-Za-z_][A-Za-z0-9_]*=", tokens[0]) or
                              tokens[0] in ("sudo", "exec", "time", "!", "env", "command")):
                tokens.pop(0)
            if tokens and re.match(r"^[A-Za-z][\w.+-]*$", tokens[0]):
                words.add(tokens[0])
    return words - SHELL_SKIP


def python_commands(path):
    """First words of subprocess calls with a literal command."""
    words = set()
    tree = ast.parse(open(path, encoding="utf-8").read(), path)
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call) or not node.args:
            continue
        func = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
        if func not in ("run", "Popen", "call", "check_call", "check_output", "getoutput"):
            continue
        first = node.args[0]
        if isinstance(first, (ast.List, ast.Tuple)) and first.elts:
            first = first.elts[0]
        if isinstance(first, ast.Constant) and isinstance(first.value, str) and first.value:
            words.add(os.path.basename(first.value.split()[0]))
    return words


def executables():
    """name -> (path or None, files calling it). Unknown words are functions or variables."""
    calls = {}
    for path in repo_files("**/*.sh") + repo_files(".ci/run"):
        for w in shell_commands(open(path, encoding="utf-8").read()):
            calls.setdefault(w, set()).add(os.path.relpath(path, REPO))
    for path in repo_files("**/*.py"):
        for w in python_commands(path):
            calls.setdefault(w, set()).add(os.path.relpath(path, REPO))
    for path in repo_files("**/*.cpp") + repo_files("**/*.h"):
        for w in re.findall(r'popen\(\s*"([\w.+-]+)', open(path, encoding="utf-8").read()):
            calls.setdefault(w, set()).add(os.path.relpath(path, REPO))
    found = {}
    own = {os.path.basename(p) for p in repo_files("scripts/*") + repo_files("test/*.py")}
    for w, files in calls.items():
        if w in own:
            continue
        path = shutil.which(w, path="/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin")
        if path:
            found[w] = (path, files)
    return found


def launch_packages():
    """ROS packages that launch and test files start nodes of, other than this one."""
    pkgs = {}
    for path in repo_files("**/*.launch") + repo_files("**/*.test"):
        for el in ET.parse(path).getroot().iter():
            pkg = el.get("pkg")
            if el.tag in ("node", "test") and pkg and "$(" not in pkg and pkg != "modbus_rtu_driver":
                pkgs.setdefault(pkg, set()).add(os.path.relpath(path, REPO))
    return pkgs


def compiler_headers(ws):
    """Headers outside the repository and the workspace that the compiler read."""
    headers = set()
    dep_files = glob.glob(os.path.join(ws, "build", "**", "*.o.d"), recursive=True)
    dep_files += glob.glob(os.path.join(ws, "build", "**", "depend.make"), recursive=True)
    for path in dep_files:
        for token in re.split(r"[\s\\]+", open(path, encoding="utf-8", errors="replace").read()):
            token = token.rstrip(":")
            if token.startswith("/") and not token.startswith((REPO, ws, os.path.realpath(ws))):
                headers.add(os.path.normpath(token))
    return headers, len(dep_files)


def owners(paths):
    """path -> Debian package (None when no package owns it). Symlinks resolved if needed."""
    result = {}
    paths = sorted(paths)
    for i in range(0, len(paths), 200):
        chunk = paths[i:i + 200]
        out = sh("dpkg", "-S", *chunk)
        for line in out.splitlines():
            if ": " not in line or line.startswith("diversion"):
                continue
            pkgs, path = line.split(": ", 1)
            if path in chunk:
                result.setdefault(path, pkgs.split(",")[0].strip().split(":")[0])
    for p in paths:
        if p in result:
            continue
        result[p] = None
        # Merged /usr: dpkg may know /bin/cat as /bin/cat only; a symlink by its target.
        for alias in (os.path.realpath(p), re.sub(r"^/usr/(s?bin|lib)/", r"/\1/", p),
                      re.sub(r"^/(s?bin|lib)/", r"/usr/\1/", p)):
            line = next(iter(sh("dpkg", "-S", alias).splitlines()), "") if alias != p else ""
            if ": " in line:
                result[p] = line.split(": ", 1)[0].split(",")[0].strip().split(":")[0]
                break
    return result


def closure(packages):
    out = sh("apt-cache", "depends", "--recurse", "--no-recommends", "--no-suggests", "--no-conflicts",
             "--no-breaks", "--no-replaces", "--no-enhances", *packages)
    names = set(packages)
    for line in out.splitlines():
        name = line.split(":", 1)[-1].strip() if line.startswith(" ") else line.strip()
        names.add(name.strip("<>").split(":")[0])
    return names


def base_packages():
    """What every Debian root has: the Essential packages and apt (mmdebstrap's minbase)."""
    out = sh("dpkg-query", "-W", "-f", "${Package} ${Essential}\n")
    essential = [l.split()[0] for l in out.splitlines() if l.endswith(" yes")]
    return closure(essential + ["apt"])


def release_codename():
    """This machine's codename, as debian_packages.txt's except:/only: words name it."""
    if os.environ.get("MODBUS_RTU_RELEASE"):
        return os.environ["MODBUS_RTU_RELEASE"]
    try:
        with open("/etc/os-release", encoding="utf-8") as f:
            for line in f:
                if line.startswith("VERSION_CODENAME="):
                    return line.split("=", 1)[1].strip().strip('"')
    except OSError:
        pass
    return "unknown"


def is_stdlib(name):
    """Part of Python itself. sys.stdlib_module_names is Python 3.10+; before it (Debian 11's
    3.9, Ubuntu 20.04's 3.8) a module is Python's own when it is built in or lives in the
    standard library's directory, outside dist-packages."""
    if hasattr(sys, "stdlib_module_names"):
        return name in sys.stdlib_module_names
    if name in sys.builtin_module_names:
        return True
    spec = importlib.util.find_spec(name)
    origin = getattr(spec, "origin", None) or ""
    stdlib = sysconfig.get_paths()["stdlib"]
    return origin.startswith(stdlib) and "-packages" not in origin


def read_list(without, release=None):
    """The list's names (as scripts/common.sh's list_packages reads it): for `release` only those
    installed there; release=None: every name, whatever release it is for."""
    pkgs = []
    with open(os.path.join(REPO, "scripts", "debian_packages.txt"), encoding="utf-8") as f:
        for line in f:
            words = re.sub(r"#.*", "", line).split()
            if not words or words[0] in without:
                continue
            keep = True
            for w in words[1:]:
                if w.startswith("except:") and release is not None:
                    keep = keep and release not in w[len("except:"):].split(",")
                elif w.startswith("only:") and release is not None:
                    keep = keep and release in w[len("only:"):].split(",")
                elif w != "debian-ros" and not w.startswith(("except:", "only:")):
                    raise SystemExit(f"scripts/debian_packages.txt: unknown word '{w}' after {words[0]}")
            if keep:
                pkgs.append(words[0])
    return pkgs


def package_xml_problems(listed):
    """package.xml declares the list: a rosdep key for each package, or, for the packages that
    have no rosdep key, their name on its comment's "no-rosdep-key:" line."""
    text = open(os.path.join(REPO, "package.xml"), encoding="utf-8").read()
    root = ET.fromstring(text)
    keys = {el.text.strip() for el in root if el.tag.endswith("depend") and el.text}
    problems = [f"package.xml: '{k}' has no Debian package in check_deps.py's table"
                for k in sorted(keys - ROSDEP_TO_DEBIAN.keys())]
    no_key = set(next(iter(re.findall(r"no-rosdep-key:([^\n]*)", text)), "").split())
    declared = {d for k in keys for d in ROSDEP_TO_DEBIAN.get(k, [])} | no_key
    problems += [f"package.xml does not declare '{p}' (scripts/debian_packages.txt has it)"
                 for p in listed if p not in declared]
    problems += [f"package.xml declares '{p}' that scripts/debian_packages.txt does not install"
                 for p in sorted(declared - set(listed))]
    return problems


def write_case(results, name, problems):
    os.makedirs(results, exist_ok=True)
    junit.write_suite(os.path.join(results, name + ".xml"), "dependencies",
                      [(name, "; ".join(problems), None)])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("ws")
    ap.add_argument("results")
    ap.add_argument("--without", default="")
    ap.add_argument("--name", default="dependencies_installed")
    ap.add_argument("--expect-missing", default="",
                    help="PKG,PKG: pass only if dropping these from the list fails the check, naming them")
    ap.add_argument("--raw", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.expect_missing:
        return expect_failure(args, {p for p in args.expect_missing.split(",") if p})
    without = {p for p in args.without.split(",") if p}
    listed = read_list(without, release_codename())
    allowed = closure(listed) | base_packages()

    uses = []  # (what, owning package or None, who uses it)
    modules = python_modules()
    own_modules = {os.path.splitext(os.path.basename(p))[0] for p in repo_files("**/*.py")}
    own_modules.add("modbus_rtu_driver")
    for name, files in sorted(modules.items()):
        if is_stdlib(name) or name in own_modules:
            continue
        spec = importlib.util.find_spec(name)
        origin = spec and (spec.origin if spec.origin not in (None, "namespace") else
                           next(iter(spec.submodule_search_locations or []), None))
        if not origin:
            uses.append((f"python module {name}", None, files))
        elif not origin.startswith((REPO, args.ws)):
            uses.append((f"python module {name}", origin, files))
    called = executables()
    for name, (path, files) in sorted(called.items()):
        uses.append((f"executable {name}", path, files))
    for pkg, files in sorted(launch_packages().items()):
        path = sh("rospack", "find", pkg).strip()
        uses.append((f"ROS package {pkg}", path or None, files))
    headers, n_dep_files = compiler_headers(args.ws)
    for h in headers:
        uses.append((f"header {h}", h, {"the build"}))

    owner = owners({p for _, p, _ in uses if p})
    # package.xml against every name of the list, whatever release it is for, less those only
    # one release's scripts need (g++-9: bullseye's stand-in for Ubuntu 20.04's compiler).
    everywhere = set(read_list(set(), "every-release"))
    problems = package_xml_problems([p for p in read_list(set()) if p in everywhere])
    missing = {}
    for what, path, files in uses:
        pkg = owner.get(path) if path else None
        if pkg is None:
            problems.append(f"{what} (used by {', '.join(sorted(files))}) is not installed from a Debian package")
        elif pkg not in allowed:
            missing.setdefault(pkg, []).append(f"{what} (used by {', '.join(sorted(files))})")
    for pkg, whats in sorted(missing.items()):
        problems.append(f"{pkg} is not installed by the scripts; needed for: " + "; ".join(whats[:3]) +
                        (f" and {len(whats) - 3} more" if len(whats) > 3 else ""))
    if n_dep_files == 0:
        problems.append(f"no compiler dependency files under {args.ws}/build: build first")

    print(f"dependency check: {len(modules)} python modules, {len(called)} executables, "
          f"{len(headers)} headers from {n_dep_files} dependency files; "
          f"{len(listed)} listed packages, {len(allowed)} in their closure")
    for p in problems:
        print("  " + p)
    if not args.raw:
        write_case(args.results, args.name, problems)
    missing_names = sorted(missing)
    print("missing packages: " + (", ".join(missing_names) if missing_names else "none"))
    return 1 if problems else 0


def expect_failure(args, without):
    """The check itself can fail: dropping packages from the list must make it name them."""
    out = subprocess.run([sys.executable, os.path.realpath(__file__), args.ws, "/tmp/.check_deps_unused",
                          "--without", ",".join(sorted(without)), "--raw"],
                         capture_output=True, text=True, check=False)
    line = next((l for l in out.stdout.splitlines() if l.startswith("missing packages: ")), "")
    named = set(line[len("missing packages: "):].split(", "))
    unnamed = sorted(without - named)
    print(f"without {', '.join(sorted(without))}: exit {out.returncode}, {line}")
    problems = [] if out.returncode == 1 and not unnamed else [
        f"dropping {', '.join(unnamed) or 'packages'} from the list did not fail the check"]
    write_case(args.results, args.name, problems)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
