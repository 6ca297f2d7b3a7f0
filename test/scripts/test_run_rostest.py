#!/usr/bin/env python3
"""test/run_rostest.py: the launch file's required 'dir' gets a new folder and its '*_port'
args distinct ports that are free when chosen; any other required arg is refused by name."""
import pathlib
import socket
import sys
import tempfile
import unittest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
import run_rostest  # noqa: E402  (test/run_rostest.py)

LAUNCH = """<launch>
  <arg name="dir"/>
  <arg name="share_port"/>
  <arg name="sim_port"/>
  <arg name="node_prefix" default=""/>
  <arg name="fixed" value="1"/>
  <group><arg name="inner"/></group>
</launch>"""


class RunRostestTest(unittest.TestCase):
    def launch_file(self, text):
        f = tempfile.NamedTemporaryFile("w", suffix=".test", delete=False)
        f.write(text)
        f.close()
        self.addCleanup(pathlib.Path(f.name).unlink)
        return f.name

    def test_fills_dir_and_free_distinct_ports(self):
        args, folders = run_rostest.launch_args(self.launch_file(LAUNCH))
        self.addCleanup(lambda: [pathlib.Path(f).rmdir() for f in folders])
        values = dict(a.split(":=") for a in args)
        self.assertEqual(sorted(values), ["dir", "share_port", "sim_port"])
        self.assertTrue(pathlib.Path(values["dir"]).is_dir())
        ports = [int(values["share_port"]), int(values["sim_port"])]
        self.assertNotEqual(ports[0], ports[1])
        for port in ports:  # still free: a server can bind it
            with socket.socket() as s:
                s.bind(("127.0.0.1", port))

    def test_a_busy_port_is_never_chosen(self):
        with socket.socket() as busy:
            busy.bind(("127.0.0.1", 0))
            busy.listen()
            for _ in range(20):
                args, _ = run_rostest.launch_args(self.launch_file(
                    '<launch><arg name="a_port"/><arg name="b_port"/></launch>'))
                self.assertNotIn(f"a_port:={busy.getsockname()[1]}", args)
                self.assertNotIn(f"b_port:={busy.getsockname()[1]}", args)

    def test_other_required_args_are_refused_by_name(self):
        with self.assertRaises(SystemExit) as e:
            run_rostest.launch_args(self.launch_file('<launch><arg name="config"/></launch>'))
        self.assertIn("config", str(e.exception))


if __name__ == "__main__":
    if any(a.startswith("--gtest_output") for a in sys.argv):
        import rosunit
        rosunit.unitrun("modbus_rtu_driver", "run_rostest", RunRostestTest)
    else:
        unittest.main()
