"""The Hypothesis state machine: random sequences of what a robot meets, run on the real node
and the simulator; after each step the board (the simulator's coils) is checked against the
model (model.py) and the node's claims against the board. While the port is gone (the
simulator stopped) there is no board: the steps then check the node's answers, and the board is
checked again once a new simulator is there."""
import signal
import time

import hypothesis.strategies as st
from hypothesis import assume
from hypothesis.control import current_build_context
from hypothesis.stateful import RuleBasedStateMachine, initialize, precondition, rule
from std_msgs.msg import Bool
from std_srvs.srv import SetBool
import rospy

from modbus_rtu_driver.srv import Pulse, SetOutputs, SetPwm, StopPwm

import harness
from harness import DEV, LD_BOARD, LD_DEV, NS, PDU_BOARD, PDU_DEV, Timeout, wait_until
from model import BOTH, DEAD_MAN, LD_NAMES, NAMES, PDU_NAMES, PDU_SAFE, LdModel, Model
from mbap_client import MbapClient, ModbusError, write_coil_pdu  # test/mbap_client.py

CHANNELS = st.integers(0, 7)
NOT_DEAD_MAN = st.sampled_from([i for i in range(8) if i != DEAD_MAN])
# What may meet the node while its port is gone (port_lost_and_back); "heartbeat" toggles it.
WHILE_PORT_GONE = ["set", "set_outputs", "command", "pulse", "share_write", "share_read",
                   "heartbeat"]


class InvariantFailed(AssertionError):
    pass


class Run:
    """What one run shares between its examples: the harness, the budget, the counters."""
    harness = None
    known = ()
    deadline = 0.0
    steps = 0
    examples = 0
    failures = []  # every invariant failure, also one a replay did not repeat (Flaky)
    log = print


def fail(invariant, text):
    message = "%s: %s" % (invariant, text)
    Run.failures.append("example %d, step %d: %s" % (Run.examples, Run.steps, message))
    Run.log("  INVARIANT FAILED " + message)
    raise InvariantFailed(message)


class Scenario(RuleBasedStateMachine):
    def __init__(self):
        super().__init__()
        self.h = Run.harness
        self.m = Model(Run.known)
        self.ld = LdModel(Run.known)  # the LD58A08 (bus.yaml `pwm`)
        self.pdu = Model(Run.known, PDU_NAMES, PDU_SAFE, on_restart="safe")
        # (device, board address, model, names) of every device the board checks compare
        self.devices = [(DEV, harness.BOARD, self.m, NAMES), (LD_DEV, LD_BOARD, self.ld, LD_NAMES),
                        (PDU_DEV, PDU_BOARD, self.pdu, PDU_NAMES)]
        self.started = False

    def share(self):
        """A connection of its own for each request to the LC board through the node's share
        (as a client that reconnects: the node stops and starts under it)."""
        return MbapClient(self.h.share_port, int(harness.BOARD))

    def note(self, text):
        Run.log("  [%6.1f] %s" % (time.time() % 1000, text))

    # --- start of an example: a powered-up board with random outputs, the node started -------
    @initialize(coils=st.lists(st.integers(0, 1), min_size=8, max_size=8),
                ld_coils=st.lists(st.integers(0, 1), min_size=8, max_size=8),
                pdu_coils=st.lists(st.integers(0, 1), min_size=8, max_size=8))
    def start(self, coils, ld_coils, pdu_coils):
        # The budget is spent: the examples left are invalid and cost nothing (not in the
        # final replay of a failure, which must run as it did).
        if not current_build_context().is_final:
            assume(time.time() < Run.deadline)
        Run.examples += 1
        self.note("example %d: board %s, LD58A08 %s, PDU %s, node starts (on_start: safe)"
                  % (Run.examples, coils, ld_coils, pdu_coils))
        self.h.stop_node()
        self.h.forget_kept_state()  # each example is a robot of its own
        self.h.start_simulator()  # an earlier example may have ended with the port gone
        self.h.beating.set()
        self.h.sim.silence(harness.BOARD, False)
        self.h.sim.set(LD_BOARD, "holding_register", 0xFA, 0)  # power-down save off
        self.h.sim.power_cycle()  # every device: LD58A08 PWM registers cleared
        for (_, board, model, _), values in zip(self.devices, (coils, ld_coils, pdu_coils)):
            self.h.sim.set(board, "coil", 0, *values)
            for i, v in enumerate(values):
                model.ch[i].values, model.ch[i].why = {v}, "the board as the example set it"
        since = len(self.h.events)
        self.h.start_node()
        self.started = True
        self.node_started(since)
        self.heartbeat_at_start(since)
        self.check("node start")

    def models(self):
        return [model for _, _, model, _ in self.devices]

    def node_started(self, since):
        """Every device's on_start: safe (docs/failsafe.md: confirmed before the services)."""
        for model in self.models():
            model.node_started(time.time())
        for dev, _, _, _ in self.devices:
            self.expect_event("start", since, confirmed=True, dev=dev)

    def heartbeat_at_start(self, since):
        """The node counts the heartbeat's timeout from its start: on a loaded machine its
        subscription may connect too late, and the heartbeat is lost before a step ran. That is
        the node doing its job; the model takes it as a loss and a return."""
        beats = self.h.beats
        wait_until(lambda: self.h.beats >= beats + 3 and self.h.alive.get_num_connections() > 0,
                   10, "heartbeats published to the node")
        if any(e.trigger == "heartbeat" and e.device == DEV for e in self.h.events[since:]):
            self.note("heartbeat lost at start (the node's subscription connected late)")
            for model in self.models():
                model.heartbeat_lost_event()
                model.heartbeat_back()

    def teardown(self):
        if self.started:
            self.h.stop_node()
            self.h.start_simulator()
            self.h.beating.set()
            self.h.sim.silence(harness.BOARD, False)

    # --- checks ------------------------------------------------------------------------------
    def board_mismatch(self):
        """[(device, model, names, channel, board value, allowed, why)] where a device's coils
        (or an LD58A08 enable register, "enN") differ from its model."""
        now = time.time()
        bad, boards = [], {}
        for dev, board, model, names in self.devices:
            coils = boards[dev] = self.h.coils(board)
            bad += [(dev, model, names[i], coils[i], sorted(model.allowed(i, now)),
                     model.ch[i].why, i) for i in range(8) if coils[i] not in model.allowed(i, now)]
        for i in range(8):
            allowed, why = self.ld.enable_allowed(i, now)
            if allowed is not None:
                value = self.h.enable(i)
                if value not in allowed:
                    bad.append((LD_DEV, None, "en%d" % i, value, sorted(allowed), why, i))
        return boards, bad

    def check(self, step):
        """The board matches the model (bounded wait for the node's writes to land), and still
        does after two more polls (nothing undoes it)."""
        Run.steps += 1
        if self.m.port_gone:
            return  # no board to compare: the next check after the port is back does
        for phase in ("settle", "stable"):
            try:
                wait_until(lambda: not self.board_mismatch()[1], 4.0, "the board to match")
            except Timeout:
                boards, bad = self.board_mismatch()
                if not bad:  # it matched just after the deadline
                    continue
                text = "; ".join("%s/%s is %d, expected %s by %s%s" % (
                    dev, name, v, allowed, why, self.refused_text(model, i, v) if model else "")
                    for dev, model, name, v, allowed, why, i in bad)
                dev, model, _, value, _, why, i = bad[0]
                refused = model.ch[i].refused if model else None
                invariant = "I13" if refused and refused[0] == value else why.split(" ")[0]
                fail(invariant, "after %s (%s): boards %s: %s" % (step, phase, boards, text))
            if phase == "settle" and self.m.node_running and not self.m.port_gone:
                if not self.m.silenced:
                    self.h.wait_polls(2)
                self.h.wait_polls(2, dev=LD_DEV)
                self.h.wait_polls(2, dev=PDU_DEV)
        for model in self.models():
            model.settle_flashes(time.time())
        if self.m.node_running:
            self.check_diagnostics(step)

    @staticmethod
    def refused_text(model, i, value):
        refused = model.ch[i].refused
        if refused and refused[0] == value:
            return " (I13: %s answered success:false earlier)" % refused[1]
        return ""

    def check_diagnostics(self, step):
        """I15: a device status claiming 'outputs in their safe state' must be true on the board."""
        if self.m.flash_running(time.time()):
            return
        if self.m.unreachable():
            return  # nothing to confirm on a silent board or a lost port; the status says so
        status = self.h.fresh_diagnostics()
        claim = status.message.split("outputs in their safe state", 1)
        if len(claim) < 2 or "NOT confirmed" in claim[1]:
            return  # no claim, or one that says it is not confirmed
        # "outputs in their safe state after heartbeat (...): pump off, lamp on, valve off"
        named = claim[1].split("): ", 1)[-1].split(";")[0]
        claimed = {}
        for item in named.split(", "):
            words = item.split()
            if len(words) == 2 and words[0] in NAMES and words[1] in ("on", "off"):
                claimed[NAMES.index(words[0])] = int(words[1] == "on")
        coils = self.h.coils()
        pulse_known = "safe_claim_survives_pulse" in self.m.known
        wrong = [NAMES[i] for i, s in claimed.items() if coils[i] != s and not self.m.ch[i].relaxed
                 and not (pulse_known and not self.m.ch[i].settled)]
        if wrong:
            fail("I15", "after %s: /diagnostics says %r but %s not safe on the board %s"
                 % (step, status.message, ", ".join(wrong), coils))

    def expect_event(self, trigger, since, confirmed, timeout=10.0, dev=DEV):
        try:
            e = self.h.event(trigger, since, timeout, dev)
        except Timeout as t:
            fail("I16", str(t))
        if e.confirmed != confirmed:
            fail("I16", "%s event confirmed=%s, expected %s: %s" % (trigger, e.confirmed,
                                                                  confirmed, e.message))
        return e

    def refused_while_port_gone(self, what, ok):
        """docs/failsafe.md, port lost: the node cannot write anything, so no write may answer
        success while the port is gone (there is no board to confirm it)."""
        if ok and self.m.port_gone:
            fail("I1", "%s answered success:true while the port is gone (no board)" % what)

    # --- service writes, topics, pulses ------------------------------------------------------
    @precondition(lambda self: self.m.node_running)
    @rule(ch=CHANNELS, state=st.integers(0, 1))
    def set_one(self, ch, state):
        res = rospy.ServiceProxy(NS + DEV + "/" + NAMES[ch] + "/set", SetBool)(bool(state))
        self.note("%s/set %d -> %s %s" % (NAMES[ch], state, res.success, res.message))
        self.refused_while_port_gone("%s/set %d" % (NAMES[ch], state), res.success)
        self.m.user_write([ch], [state], res.success, "%s/set %d" % (NAMES[ch], state))
        self.check("set %s %d" % (NAMES[ch], state))

    @precondition(lambda self: self.m.node_running)
    @rule(chs=st.lists(CHANNELS, min_size=2, max_size=3, unique=True),
          states=st.lists(st.integers(0, 1), min_size=3, max_size=3))
    def set_outputs(self, chs, states):
        chs, states = sorted(chs), states[:len(chs)]
        port_gone = self.m.port_gone
        before = None if port_gone else self.h.sim.stats(harness.BOARD)["changes"]
        res = rospy.ServiceProxy(NS + DEV + "/set_outputs", SetOutputs)(chs, [bool(s) for s in states])
        self.note("set_outputs %s %s -> %s %s" % (chs, states, res.success, res.message))
        self.refused_while_port_gone("set_outputs %s %s" % (chs, states), res.success)
        self.m.user_write(chs, states, res.success, "set_outputs %s %s" % (chs, states))
        self.check("set_outputs %s %s" % (chs, states))
        if port_gone:
            return
        changes = self.h.sim.stats(harness.BOARD)["changes"] - before
        if changes > len(chs) and not self.m.flash_running(time.time()):
            fail("I14", "set_outputs of %d channels made %d changes on the board" % (len(chs), changes))

    @precondition(lambda self: self.m.node_running and not self.m.silenced)
    @rule(ch=NOT_DEAD_MAN, state=st.integers(0, 1))
    def command(self, ch, state):
        # No answer tells when a topic command is done: a pulse still running on the channel
        # could end after the board showed the command. Let it end first.
        if self.m.port_gone:
            return self.command_while_port_gone(ch, state)
        flash = self.m.ch[ch].flash
        if flash is not None:
            wait_until(lambda: time.time() > flash.done_after, 10, "the pulse on the channel to end")
            self.m.settle_flashes(time.time())
        self.h.commands[NAMES[ch]].publish(Bool(bool(state)))
        self.note("%s/command %d" % (NAMES[ch], state))
        try:  # fire and forget: done when the board shows it
            wait_until(lambda: self.h.coils()[ch] == state, 5.0, "%s/command on the board" % NAMES[ch])
            ok = True
        except Timeout:
            ok = False
        self.m.user_write([ch], [state], True, "%s/command %d" % (NAMES[ch], state))
        if not ok:
            fail("I1", "%s/command %d never reached the board" % (NAMES[ch], state))
        self.check("command %s %d" % (NAMES[ch], state))

    def command_while_port_gone(self, ch, state):
        """A topic command while the port is gone is refused unsent (docs/share.md's `writes
        refused unsent`): it must never reach the board later (I13)."""
        before = self.h.refused_unsent()
        self.h.commands[NAMES[ch]].publish(Bool(bool(state)))
        self.note("%s/command %d (port gone)" % (NAMES[ch], state))
        try:
            wait_until(lambda: self.h.refused_unsent() > before, 10,
                       "the command refused unsent (/diagnostics of %s)" % DEV)
        except Timeout as t:
            fail("I13", "%s/command %d while the port is gone: %s" % (NAMES[ch], state, t))
        self.m.user_write([ch], [state], False, "%s/command %d" % (NAMES[ch], state))
        self.check("command %s %d" % (NAMES[ch], state))

    @precondition(lambda self: self.m.node_running and not self.m.unreachable())
    @rule()
    def dead_man(self):
        """The valve turned on by its command topic and left: off after command_timeout."""
        since = len(self.h.events)
        self.h.commands[NAMES[DEAD_MAN]].publish(Bool(True))
        self.note("valve/command 1, then nothing (command_timeout 1.0 s)")
        e = self.expect_event("command_timeout", since, confirmed=True)
        if list(e.channels) != [NAMES[DEAD_MAN]] or list(e.states) != [False]:
            fail("I17", "command_timeout event wrote %s %s, expected valve off" % (e.channels, e.states))
        self.m.user_write([DEAD_MAN], [1], True, "valve/command 1")
        self.m.failsafe([DEAD_MAN], "I2 (command timeout: valve safe until commanded again)")
        self.check("dead man valve")

    @precondition(lambda self: self.m.node_running)
    @rule(ch=CHANNELS, state=st.integers(0, 1), tenths=st.integers(15, 40))
    def pulse(self, ch, state, tenths):
        sent = time.time()
        res = rospy.ServiceProxy(NS + DEV + "/pulse", Pulse)(ch, bool(state), tenths / 10.0)
        answered = time.time()
        self.note("pulse %s %d %.1f s -> %s %s" % (NAMES[ch], state, tenths / 10.0, res.success,
                                                   res.message))
        self.refused_while_port_gone("pulse %s %d" % (NAMES[ch], state), res.success)
        self.m.pulse(ch, state, res.success, sent, answered, tenths / 10.0)
        self.check("pulse %s %d" % (NAMES[ch], state))

    @precondition(lambda self: self.m.node_running)
    @rule(ch=st.integers(1, 6), state=st.integers(0, 1), tenths=st.integers(20, 40),
          states=st.lists(st.integers(0, 1), min_size=2, max_size=2))
    def pulse_then_neighbours(self, ch, state, tenths, states):
        """A lamp flashing while the outputs beside it are switched in one set_outputs."""
        self.pulse(ch, state, tenths)
        self.set_outputs([ch - 1, ch + 1], states + [0])

    # --- the share ---------------------------------------------------------------------------
    @precondition(lambda self: self.m.node_running)
    @rule()
    def share_read(self):
        try:
            with self.share() as client:
                coils = client.read_coils(0, 8)
        except ModbusError as e:
            self.note("share FC01 -> %s" % e)
            if not self.m.unreachable():
                fail("I20", "share FC01 of an answering board failed: %s" % e)
            if self.m.port_gone and e.code != 0x0A:
                fail("I20", "share FC01 while the port is gone: %s, docs/share.md says "
                     "exception 0A (gateway path unavailable)" % e)
            return
        now = time.time()
        self.note("share FC01 -> %s" % coils)
        if self.m.port_gone:
            fail("I20", "the share read %s while the port is gone (no board)" % coils)
        self.m.settle_flashes(now)
        bad = [NAMES[i] for i in range(8) if coils[i] not in self.m.allowed(i, now)
               and self.m.ch[i].flash is None]
        if bad:
            fail("I20", "the share read %s, the model says %s for %s" % (
                coils, [sorted(self.m.allowed(i, now)) for i in range(8)], bad))
        self.check("share read")

    @precondition(lambda self: self.m.node_running
                  and "share_write_seen_as_restart" not in self.m.known)
    @rule(ch=CHANNELS, state=st.integers(0, 1))
    def share_write(self, ch, state):
        try:
            with self.share() as client:
                client.write_coil(ch, state)
            ok, text = True, "ok"
        except ModbusError as e:
            ok, text = False, str(e)
        self.note("share FC05 %s %d -> %s" % (NAMES[ch], state, text))
        self.refused_while_port_gone("share FC05 %s %d" % (NAMES[ch], state), ok)
        self.m.user_write([ch], [state], ok, "share FC05 %s %d" % (NAMES[ch], state))
        self.check("share write %s %d" % (NAMES[ch], state))

    # --- heartbeat, power, silence, node stop and start --------------------------------------
    @precondition(lambda self: self.m.node_running and self.h.beating.is_set())
    @rule()
    def heartbeat_lost(self):
        since = len(self.h.events)
        self.h.beating.clear()
        self.note("heartbeat stops")
        for dev, _, model, names in self.devices:
            e = self.expect_event("heartbeat", since, confirmed=not model.unreachable(),
                                  timeout=15.0, dev=dev)
            wrong = [(c, s) for c, s in zip(e.channels, e.states)
                     if names.index(c) not in model.safe or model.safe[names.index(c)] != int(s)]
            if wrong:
                fail("I17", "heartbeat event of %s wrote %s, not the safe states" % (dev, wrong))
        for model in self.models():
            model.heartbeat_lost_event()
        self.check("heartbeat lost")

    @precondition(lambda self: self.m.node_running and not self.h.beating.is_set())
    @rule()
    def heartbeat_back(self):
        beats = self.h.beats
        self.h.beating.set()
        self.note("heartbeat back")
        # The node shows no sign of a heartbeat back: a few messages on a connected topic.
        wait_until(lambda: self.h.beats >= beats + 3 and self.h.alive.get_num_connections() > 0,
                   5, "heartbeats published to the node")
        if not self.m.unreachable():
            self.h.wait_polls(3)
        for model in self.models():
            model.heartbeat_back()
        self.check("heartbeat back")

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule()
    def power_cycle(self):
        since = len(self.h.events)
        self.h.sim.power_cycle(harness.BOARD)  # the LC board alone (its own supply)
        seen = self.m.power_cycle(time.time())
        self.note("power cycle (restart to be seen: %s)" % seen)
        if seen:
            e = self.expect_event("restart", since, confirmed=True)
            if e.action != "restore":
                fail("I17", "restart event with action %r, on_restart is restore" % e.action)
        self.check("power cycle")

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule()
    def silence_toggle(self):
        since = len(self.h.events)
        if not self.m.silenced:
            self.h.sim.silence(harness.BOARD, True)
            self.m.silenced = True
            self.note("board silenced")
            wait_until(lambda: self.h.diag and self.h.diag[1].message.startswith("offline"), 20,
                       "/diagnostics to say the board is offline")
        else:
            self.h.sim.silence(harness.BOARD, False)
            self.m.silenced = False
            self.note("board answers again")
            self.expect_event("restart", since, confirmed=True, timeout=15.0)
            self.m.restored()
        self.check("silence toggled")

    @precondition(lambda self: self.m.node_running and not self.m.unreachable())
    @rule(burst=st.booleans())
    def restart_node(self, burst):
        sockets = []  # the burst's clients, each with its FC05 sent and its answer not read
        before = None
        if burst and "share_after_stop" not in self.m.known:
            def before():
                for _ in range(5):
                    sockets.append(self.share())
                    sockets[-1].send(write_coil_pdu(0, True))
        code = self.h.stop_node(signal.SIGINT, before)
        for s in sockets:
            s.close()
        self.note("node stopped (SIGINT%s), exit %s" % (", after 5 share writes of pump on" if sockets else "", code))
        if burst and sockets:
            self.m.ch[0].values = set(BOTH)  # the share writes may have run before the stop
        for model in self.models():
            model.node_stopped(reached=True)
        if code != 0:
            fail("I10", "the node exited with %s on SIGINT:\n%s" % (code, self.h.output[-2000:]))
        self.check("node stop")
        # Flashes end before the next start (a flash ending under a new node is a restart).
        # (LD58A08 timed runs too; a continuous run goes on: the next node finds it running.)
        wait_until(lambda: not self.m.flash_running(time.time()) and not self.ld_timed_running(),
                   10, "running pulses and timed PWM runs to end")
        self.h.beating.set()
        since = len(self.h.events)
        self.h.start_node()
        self.note("node started")
        self.node_started(since)
        self.heartbeat_at_start(since)
        self.check("node start")

    # --- the port: lost (USB adapter pulled) and back ----------------------------------------
    @precondition(lambda self: self.m.node_running)
    @rule(data=st.data())
    def port_lost_and_back(self, data):
        """The port goes away, up to 4 events meet the node meanwhile (writes, commands,
        pulses, share requests, the heartbeat lost or back), and it comes back. One rule, so
        that every loss is followed by a return within the example (two rules drawn uniformly
        among a dozen left most examples ending with the port gone)."""
        self.port_lost(data.draw(st.one_of(st.none(), st.tuples(CHANNELS, st.integers(0, 1))),
                                 label="write at once"))
        for event in data.draw(st.lists(st.sampled_from(WHILE_PORT_GONE), max_size=4),
                               label="while the port is gone"):
            if event == "set":
                self.set_one(*data.draw(st.tuples(CHANNELS, st.integers(0, 1)), label="set"))
            elif event == "set_outputs":
                self.set_outputs(data.draw(st.lists(CHANNELS, min_size=2, max_size=3, unique=True),
                                           label="channels"),
                                 data.draw(st.lists(st.integers(0, 1), min_size=3, max_size=3),
                                           label="states"))
            elif event == "command":
                self.command(data.draw(NOT_DEAD_MAN, label="channel"),
                             data.draw(st.integers(0, 1), label="state"))
            elif event == "pulse":
                self.pulse(data.draw(CHANNELS, label="channel"),
                           data.draw(st.integers(0, 1), label="state"),
                           data.draw(st.integers(15, 40), label="tenths"))
            elif event == "share_write":
                if "share_write_seen_as_restart" in self.m.known:
                    continue
                self.share_write(data.draw(CHANNELS, label="channel"),
                                 data.draw(st.integers(0, 1), label="state"))
            elif event == "share_read":
                self.share_read()
            elif self.h.beating.is_set():
                self.heartbeat_lost()
            else:
                self.heartbeat_back()
        self.port_back()

    def port_lost(self, write):
        """The simulator stops: its pty and link go away, as an unplugged USB adapter
        (test/rostest/test_recoveries.py test_4). The node must say "port not open" on the bus's
        /diagnostics; a write tried at once must fail and never reach the board later."""
        self.h.stop_simulator()
        for model in self.models():
            model.port_lost()
        self.note("port lost (simulator stopped)")
        try:
            status = self.h.fresh_bus_status(lambda s: s.message.startswith("port not open"),
                                             20, "the bus's /diagnostics to say port not open")
        except Timeout as t:
            fail("I19", "after the port went away: %s; last bus status: %s"
                 % (t, self.h.bus_diag[1].message if self.h.bus_diag else None))
        self.note("bus: %s" % status.message)
        if write is not None:
            self.set_one(*write)
        else:
            self.check("port lost")

    def port_back(self):
        """A new simulator on the same link and control socket: a new board, every output off.
        The node reopens the port (docs/failsafe.md: with backoff) and compares the outputs at
        the next poll: a restart if they changed (or safe writes were pending), restored."""
        since = len(self.h.events)
        pending = any(c.pending_safe for c in self.m.ch)
        self.h.start_simulator()
        now = time.time()
        seen = self.m.port_back(now)
        others = [(dev, model, model.port_back(now)) for dev, _, model, _ in self.devices[1:]]
        self.note("port back (new simulator, board all off; restart to be seen: %s)" % seen)
        try:
            self.h.fresh_bus_status(lambda s: not s.message.startswith("port not open"), 40,
                                    "the bus's /diagnostics to say the port is open again")
        except Timeout as t:
            fail("I19", "the node did not reopen the port: %s; last bus status: %s"
                 % (t, self.h.bus_diag[1].message if self.h.bus_diag else None))
        if seen:
            e = self.expect_event("restart", since, confirmed=True, timeout=30.0)
            self.note("restart event: %s" % e.message)
            # A pending safe write is done when the device answers again (docs/failsafe.md); when
            # no output it compares changed, the node sees no restart and writes just that.
            allowed = ("restore", "safe") if pending else ("restore",)
            if e.action not in allowed:
                fail("I17", "restart event with action %r, on_restart is restore" % e.action)
        else:
            self.h.wait_polls(3, timeout=30.0)
        for dev, model, seen_there in others:
            if seen_there:
                e = self.expect_event("restart", since, confirmed=True, timeout=30.0, dev=dev)
                self.note("restart event of %s: %s" % (dev, e.message))
            else:
                self.h.wait_polls(3, timeout=30.0, dev=dev)
        self.check("port back")

    # --- the LD58A08: outputs and PWM (docs/devices/ld58a08.md); the PDU's relays -------------
    def ld_timed_running(self):
        """LD58A08 channels whose timed run (burst, timed fast run) may still go."""
        now = time.time()
        return [i for i, c in enumerate(self.ld.ch)
                if c.kind == "timed" and c.flash is not None and now <= c.flash.done_after]

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule(ch=CHANNELS, state=st.integers(0, 1))
    def ld_set(self, ch, state):
        self.output_set("pwm", LD_DEV, LD_NAMES[ch], self.ld, ch, state)

    def output_set(self, label, dev, name, model, ch, state):
        """`C/set` on one output of the LD58A08 or the PDU, checked against its model."""
        what = "%s %s/set %d" % (label, name, state)
        res = rospy.ServiceProxy(NS + dev + "/" + name + "/set", SetBool)(bool(state))
        self.note("%s -> %s %s" % (what, res.success, res.message))
        model.user_write([ch], [state], res.success, what)
        self.check(what)

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule(ch=CHANNELS, state=st.integers(0, 1))
    def ld_command(self, ch, state):
        """Fire and forget: done when the board shows the level with the channel's PWM off
        (docs/devices/ld58a08.md: C/command stops the channel's PWM first)."""
        what = "pwm %s/command %d" % (LD_NAMES[ch], state)
        self.h.ld_commands[LD_NAMES[ch]].publish(Bool(bool(state)))
        self.note(what)
        try:
            wait_until(lambda: self.h.coils(LD_BOARD)[ch] == state and self.h.enable(ch) == 0,
                       5.0, what + " on the board")
            ok = True
        except Timeout:
            ok = False
        self.ld.user_write([ch], [state], True, what)
        if not ok:
            fail("I1", "%s never reached the board (level %d, enable %d)"
                 % (what, self.h.coils(LD_BOARD)[ch], self.h.enable(ch)))
        self.check(what)

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule(ch=CHANNELS, period=st.integers(2, 5), on=st.integers(1, 4), pulses=st.integers(2, 6),
          duty=st.sampled_from([0, 50, 100]), tenths=st.one_of(st.just(0), st.integers(10, 30)))
    def ld_set_pwm(self, ch, period, on, pulses, duty, tenths):
        """A burst on a slow channel (0-5), a timed or continuous run on a fast one (6-7)."""
        if ch < 6:
            on = min(on, period - 1)
            req = dict(channel=ch, period=period / 10.0, on_time=on / 10.0, pulses=pulses)
            what = "set_pwm %s burst %d x %.1f s (on %.1f s)" % (LD_NAMES[ch], pulses,
                                                                   period / 10.0, on / 10.0)
            during, duration = set(BOTH), pulses * period / 10.0
        else:
            req = dict(channel=ch, frequency=1000.0, duty_cycle=float(duty),
                       duration=tenths / 10.0)
            what = "set_pwm %s 1 kHz %d %% %s" % (LD_NAMES[ch], duty, "for %.1f s" % (tenths / 10.0)
                                                 if tenths else "continuous")
            # A wave the poll cannot sample: any level while it toggles (docs/failsafe.md).
            during = {0} if duty == 0 else {1} if duty == 100 else set(BOTH)
            duration = tenths / 10.0 if tenths else None
        sent = time.time()
        res = rospy.ServiceProxy(NS + LD_DEV + "/set_pwm", SetPwm)(**req)
        answered = time.time()
        self.note("%s -> %s %s" % (what, res.success, res.message))
        self.ld.set_pwm(ch, res.success, during, sent, answered, duration, what)
        self.check(what)

    @precondition(lambda self: self.m.node_running and not self.m.port_gone
                  and self.h.beating.is_set())
    @rule(fast=st.booleans())
    def pwm_then_heartbeat_lost(self, fast):
        """A PWM run on a channel with a safe state when the heartbeat goes. docs/failsafe.md's
        table, heartbeat lost: "safe state until commanded again" on each output (I2)."""
        if fast:
            self.ld_set_pwm(6, 2, 1, 2, 100, 0)  # p6 (safe off) on continuously
        else:
            self.ld_set_pwm(0, 5, 2, 6, 0, 0)  # p0 (safe off): 6 x 0.5 s
        self.heartbeat_lost()

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule(ch=CHANNELS)
    def ld_stop_pwm(self, ch):
        what = "stop_pwm %s" % LD_NAMES[ch]
        res = rospy.ServiceProxy(NS + LD_DEV + "/stop_pwm", StopPwm)(ch)
        self.note("%s -> %s %s" % (what, res.success, res.message))
        self.ld.stop_pwm(ch, res.success, what)
        if res.success:
            # docs/failsafe.md: the next poll that reads the channel's PWM registers takes its
            # level as commanded; a poll reads one channel's, all 8 within 8 polls (ld58a08.md).
            self.h.wait_polls(9, timeout=10.0, dev=LD_DEV)
            self.ld.taken(ch, self.h.coils(LD_BOARD)[ch])
        self.check(what)

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule(pdu=st.booleans(), chs=st.lists(CHANNELS, min_size=2, max_size=3, unique=True),
          states=st.lists(st.integers(0, 1), min_size=3, max_size=3))
    def other_set_outputs(self, pdu, chs, states):
        """`set_outputs` on the LD58A08 (each requested channel's PWM stopped first) or the
        PDU; channels between requested ones are not written."""
        dev, model = (PDU_DEV, self.pdu) if pdu else (LD_DEV, self.ld)
        chs, states = sorted(chs), states[:len(chs)]
        what = "%s set_outputs %s %s" % (dev, chs, states)
        res = rospy.ServiceProxy(NS + dev + "/set_outputs", SetOutputs)(chs, [bool(x) for x in states])
        self.note("%s -> %s %s" % (what, res.success, res.message))
        model.user_write(chs, states, res.success, what)
        self.check(what)

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule(ch=CHANNELS, state=st.integers(0, 1))
    def pdu_set(self, ch, state):
        self.output_set("pdu", PDU_DEV, PDU_NAMES[ch], self.pdu, ch, state)

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule(save=st.booleans())
    def ld_power_cycle(self, save):
        """The LD58A08 alone off and on; with `save`, its power-down save on for that cycle
        (0x00FA, written through the simulator's control socket): the PWM registers as last
        written run again (docs/devices/ld58a08.md, "Power cycle")."""
        since = len(self.h.events)
        if save:
            # A node's timed run that a save starts again before its end: whether the node takes
            # the rerun for its own command (restore writes its final level) or the device's
            # is not said by docs/failsafe.md (open question): not drawn, the runs end first.
            wait_until(lambda: not self.ld_timed_running(), 10, "the LD58A08's timed runs to end")
            self.ld.settle_flashes(time.time())
            self.h.sim.set(LD_BOARD, "holding_register", 0xFA, 1)
        self.h.sim.power_cycle(LD_BOARD)
        if save:
            self.h.sim.set(LD_BOARD, "holding_register", 0xFA, 0)
        seen = self.ld.power_cycle(time.time(), save)
        self.note("LD58A08 power cycle%s (restart to be seen: %s)"
                  % (" with power-down save" if save else "", seen))
        if seen:
            e = self.expect_event("restart", since, confirmed=True, dev=LD_DEV)
            if e.action != "restore":
                fail("I17", "LD58A08 restart event with action %r, on_restart is restore" % e.action)
        self.check("LD58A08 power cycle")

    @precondition(lambda self: self.m.node_running and not self.m.port_gone)
    @rule()
    def pdu_power_cycle(self):
        since = len(self.h.events)
        self.h.sim.power_cycle(PDU_BOARD)
        seen = self.pdu.power_cycle(time.time())
        self.note("PDU power cycle (restart to be seen: %s)" % seen)
        if seen:
            e = self.expect_event("restart", since, confirmed=True, dev=PDU_DEV)
            if e.action != "safe":
                fail("I17", "PDU restart event with action %r, on_restart is safe" % e.action)
        self.check("PDU power cycle")

    # --- the node killed (SIGKILL) and started again under the same roscore -----------------
    @precondition(lambda self: self.m.node_running and not self.m.unreachable())
    @rule(before=st.sampled_from(["nothing", "flash", "burst", "fast run", "continuous run"]),
          ch=st.integers(0, 3))
    def kill_and_restart(self, before, ch):
        """docs/failsafe.md, "node killed": no code runs, the boards keep their outputs (flashes
        and PWM runs go on); the next node's on_start: safe puts them safe. "A node started
        during a flash": the killed node's kept timed commands stay on the parameter server (the
        per-example reset is not called here) and the next node resumes them, so a flash's or
        timed run's end is not taken for a restart (I6). `before`: a timed command started
        just before the kill on a channel without a safe state (the next node's on_start: safe
        would end it on a safe one), so that its end comes under the next node."""
        # 6 s each: the next node starts 2-3 s after the kill, so the end comes under it.
        if before == "flash":
            self.pulse([1, 4, 5, 7][ch], ch % 2, 60)
        elif before == "burst":
            self.ld_set_pwm([1, 3, 4, 5][ch], 10, 5, 6, 0, 0)  # 6 x 1.0 s, on 0.5 s
        elif before in ("fast run", "continuous run"):
            self.ld_set_pwm(7, 2, 1, 2, [50, 100, 100, 100][ch], 60 if before == "fast run" else 0)
        now = time.time()
        running = ([NAMES[i] for i in self.m.flash_running(now)]
                   + [LD_NAMES[i] for i in self.ld_timed_running()])
        code = self.h.stop_node(signal.SIGKILL)
        self.note("node killed (SIGKILL), exit %s; timed commands running: %s"
                  % (code, ", ".join(running) or "none"))
        for model in self.models():
            model.node_running = False
        self.check("node killed")  # nothing wrote: the boards as they were
        self.h.publishers_disconnected()
        self.h.beating.set()
        since = len(self.h.events)
        self.h.start_node()
        self.note("node started again (same roscore, its kept timed commands)")
        self.node_started(since)
        self.heartbeat_at_start(since)
        self.check("node start after SIGKILL")
        ends = [c.flash.done_after for model in (self.m, self.ld) for c in model.ch
                if c.flash is not None and not getattr(c.flash, "continuous", False)]
        if ends:
            wait_until(lambda: time.time() > max(ends), 15,
                       "the timed commands running at the kill to end")
            self.h.wait_polls(3)
            self.h.wait_polls(9, timeout=10.0, dev=LD_DEV)
        restarts = [e for e in self.h.events[since:] if e.trigger == "restart"]
        if restarts:
            fail("I6", "after a SIGKILL and a new node (timed commands running at the kill: %s), "
                 "restart events with no restart: %s" % (", ".join(running) or "none",
                                                         "; ".join("%s: %s" % (e.device, e.message)
                                                                   for e in restarts)))
        self.check("timed commands of the killed node ended")
