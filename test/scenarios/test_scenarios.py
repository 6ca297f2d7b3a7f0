#!/usr/bin/env python3
"""Randomized fail-safe scenarios (issue 24) on the real node and the simulator, as a rostest.

Three devices on one bus (bus.yaml, sim.yaml): an LC relay board, an LD58A08 and a Yespeed PDU.
The events (machine.py): on the LC board service writes, command topics, the valve's dead man,
pulses, share reads and writes, power cycles and a silenced board; on the LD58A08 `C/set`,
`set_outputs`, `C/command`, `set_pwm` (a burst on channels 0-5, a timed or continuous run on
6-7), `stop_pwm` and power cycles, with or without its power-down save; on the PDU `C/set`,
`set_outputs` and power cycles (on_restart: safe); for all, the bus heartbeat lost and back,
port loss and return (the test stops the simulator: its pty goes away, as an unplugged USB
adapter; a new one comes back on the same link), node stop (SIGINT) and start, and the node
killed (SIGKILL) and started again under the same roscore (its kept timed commands stay). Every
device's outputs (and the LD58A08's enable registers) are checked in the simulator against
model.py (written from docs/failsafe.md) after each step; test/scenarios/KNOWN.md lists the
invariants.

Parameters (scenarios.test passes them): ~seed (0: draw one and print it), ~seconds (budget:
examples start until it is spent), ~steps (steps per example), ~shrink (shrink a failure to its
shortest sequence: slow, every step is real), ~known_defects (comma list, see known_defects.txt;
"none" checks everything). A failure names the invariant, prints the seed and the sequence;
`scripts/scenarios.sh --seed N` replays it."""
import os
import random
import sys
import time
import unittest

import rospy
import rostest
from hypothesis import HealthCheck, Phase, settings
from hypothesis import seed as hypothesis_seed
from hypothesis.errors import Flaky
from hypothesis.reporting import with_reporter
from hypothesis.stateful import run_state_machine_as_test

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import harness  # noqa: E402
import machine  # noqa: E402
from model import KNOWN  # noqa: E402


def known_defects(param):
    if param == "none":
        return ()
    if param:
        names = [n.strip() for n in param.split(",") if n.strip()]
    else:
        with open(os.path.join(HERE, "known_defects.txt")) as f:
            names = [line.split("#")[0].strip() for line in f]
        names = [n for n in names if n]
    unknown = [n for n in names if n not in KNOWN]
    if unknown:
        raise ValueError("known_defects: %s not one of %s" % (unknown, sorted(KNOWN)))
    return tuple(names)


def log(text):
    """Progress lines: the test's stdout (kept in the JUnit result) and $SCENARIOS_LOG, where
    scripts/scenarios.sh reads them while rostest runs."""
    print(text, flush=True)
    path = os.environ.get("SCENARIOS_LOG")
    if path:
        with open(path, "a") as f:
            f.write(str(text) + "\n")


class ScenarioTest(unittest.TestCase):
    def test_random_scenarios(self):
        rospy.init_node("test_scenarios")
        run_seed = int(rospy.get_param("~seed", 0)) or random.SystemRandom().randrange(1, 2**31)
        seconds = float(rospy.get_param("~seconds", 60))
        steps = int(rospy.get_param("~steps", 12))
        shrink = bool(rospy.get_param("~shrink", False))
        machine.Run.known = known_defects(rospy.get_param("~known_defects", ""))
        machine.Run.harness = harness.Harness(rospy.get_param("~sim_config"),
                                              rospy.get_param("~sim_control"),
                                              rospy.get_param("~port"),
                                              rospy.get_param("~log_dir"),
                                              os.path.join(HERE, "bus.yaml"))
        machine.Run.deadline = time.time() + seconds
        machine.Run.log = log
        log("SCENARIOS seed %d, budget %.0f s, %d steps per example, known defects: %s"
              % (run_seed, seconds, steps, ", ".join(machine.Run.known) or "none"))
        phases = [Phase.explicit, Phase.generate] + ([Phase.shrink] if shrink else [])
        # Examples take 20-60 s; the budget ends the run (later examples are invalid and
        # cheap), this only bounds it.
        config = settings(max_examples=int(seconds / 10) + 2, stateful_step_count=steps, deadline=None,
                          database=None, phases=phases, print_blob=True,
                          suppress_health_check=list(HealthCheck))
        hypothesis_seed(run_seed)(machine.Scenario)
        started = time.time()
        failure = None
        reported = []  # Hypothesis's "Falsifying example" (the steps), for the failure message

        def report(text):
            reported.append(str(text))
            log(text)

        try:
            with with_reporter(report):
                run_state_machine_as_test(machine.Scenario, settings=config)
        except Flaky as e:
            # Examples drawn after the budget are invalid (initialize), which Hypothesis may
            # call inconsistent with a valid example of the same start: the end of the run,
            # unless an invariant failed (and a replay did not repeat it).
            if machine.Run.failures or time.time() < machine.Run.deadline:
                failure = e
                if harness.errors:  # what the first run raised (a replay did not repeat it)
                    log("  last error of a step before the replay: %s" % harness.errors[-1])
                    reported.append("last error of a step: %s" % harness.errors[-1])
        except Exception as e:  # the invariant that failed, reported with the seed below
            failure = e
        finally:
            if failure is not None:
                # What the node logged tells why an awaited event did not come (a CI run under
                # load once waited 30 s for a restart event that a replay then saw in 3 s).
                reported.append("the node's output, last lines:\n" + machine.Run.harness.node_tail())
            if machine.Run.harness.node is not None:
                machine.Run.harness.stop_node()
            machine.Run.harness.stop_simulator()
        for note in getattr(failure, "__notes__", []):  # Hypothesis's listing of the steps
            log(note)
        log("SCENARIOS seed %d: %d examples, %d steps in %.0f s, %s"
              % (run_seed, machine.Run.examples, machine.Run.steps, time.time() - started,
                 "FAILED: %s" % failure if failure else "no invariant failed"))
        if failure is not None:
            replay = "scripts/scenarios.sh --seed %d --steps %d --known %s" % (
                run_seed, steps, ",".join(machine.Run.known) or "none")
            self.fail("seed %d (replay: %s): %s: %s\n%s\n%s"
                      % (run_seed, replay, type(failure).__name__, failure,
                         "\n".join(machine.Run.failures),
                         "\n".join(reported + list(getattr(failure, "__notes__", [])))))


if __name__ == "__main__":
    rostest.rosrun("modbus_rtu_driver", "scenarios", ScenarioTest)
