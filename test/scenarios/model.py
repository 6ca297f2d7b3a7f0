"""What the LC board's coils (Model), the LD58A08's outputs and PWM enable registers (LdModel)
and the PDU's relays (Model with on_restart: safe) must be, written from docs/failsafe.md (the
spec), docs/devices/ld58a08.md for the board itself, and the rules of issue 24, not from the
node's code. Each channel's expectation carries the invariant it comes
from, so a mismatch names the invariant that failed.

Invariants (issue 24, "Prove it by randomized scenarios"), with the ids of the one catalog,
docs/invariants.md (the C++ simulation's ids where they mean the same; ids before issue 48 there):
  I1 a write answered success:true is on the board (unless a later event changed it)
  I13 a write answered success:false never reaches the board later
  I2 while the heartbeat is lost, no output with a safe state leaves it without a new command
  I3 a restore keeps a channel a trigger holds safe; I5 what else a restore writes (the last
     confirmed state, a timed run's final level; a PWM run the device drives is not undone,
     "What restore writes")
  I10 after a node stop, every output with a safe state is in it
  I9 on_start: safe puts the safe states on before commands are taken
  I14 no write touches a channel it was not asked to
  I15 a /diagnostics claim "outputs in their safe state" matches the board; I16 each trigger's
     ~failsafe event comes, confirmed as expected; I17 an event names what was written (the
     safe states, the restart's action); I18 on_restart: safe puts the safe states on; I20 the
     share's reads match the board
  I6 a node killed during a flash or timed run and started again under the same roscore takes
     its end for no restart ("A node started during a flash"), as no restart is reported
     without a change
and docs/failsafe.md's "port lost" rule (F14): the node reports the port not open (I19), cannot
write anything meanwhile (a write answers success:false, I13), and once the port is back
compares the outputs at the next poll: a restart (on_restart: restore) when they changed, and
pending safe writes done with a restart event.
"""
import time

NAMES = ["pump", "fan", "lamp", "valve", "out4", "out5", "out6", "out7"]
SAFE = {0: 0, 2: 1, 3: 0}  # pump off, lamp on, valve off; fan and out4-7 hold (bus.yaml)
DEAD_MAN = 3  # valve: command_timeout 1.0 s
BOTH = frozenset((0, 1))

# Known-defect switches (known_defects.txt): each relaxes the model or the drawing exactly where
# an open defect of issue 24 makes the node differ from the spec. Removed once it is fixed.
KNOWN = {
    "restore_after_failsafe": "issue 24 items 1-2: restore writes the last user states, "
                              "forgetting the fail-safe's",
    "share_write_seen_as_restart": "issue 24 item 3: a share write is undone as a restart",
    "span_rewrites_between": "issue 24 item 4: FC15 over a span rewrites (and ends the flash "
                             "of) channels not asked for",
    "share_after_stop": "issue 24 item 5: share jobs queued at stop run after the safe states",
    "safe_claim_survives_pulse": "found by this test: /diagnostics keeps claiming 'outputs in "
                                 "their safe state' after a pulse took one out of it",
}


class Flash:
    """A pulse the board times itself: `state` from about `start`, the opposite after `end`."""

    def __init__(self, state, sent, answered, duration):
        self.state = state
        self.sure_until = sent + duration - 0.15      # still in the pulse
        self.done_after = answered + duration + 0.3   # surely over

    def allowed(self, now):
        if now < self.sure_until:
            return {self.state}
        if now > self.done_after:
            return {1 - self.state}
        return set(BOTH)

    def final(self):
        return 1 - self.state


class Channel:
    def __init__(self):
        self.values = set(BOTH)   # allowed board values now
        self.flash = None         # a running pulse (overrides values while it runs)
        self.why = "unknown"      # the invariant the expectation comes from
        self.settled = True       # false after a pulse until a plain write (failsafe.md);
                                  # None: a restore may have written it
        self.restore = set(BOTH)  # what a restore may write (the last state confirmed)
        self.by_failsafe = False  # that state was written by a fail-safe trigger
        self.held = False         # a trigger holds it safe until commanded again
        self.pending_safe = False  # a safe write failed: written when the device answers
        self.commanded_in_loss = False
        self.relaxed = False      # a known defect leaves its state open (known_defects.txt)
        self.refused = None       # the state a write answered success:false asked for (I13)
        self.lost_answer = False  # a write to a silent device answered success:false


class Model:
    def __init__(self, known=(), names=NAMES, safe=SAFE, on_restart="restore"):
        self.known = set(known)
        self.names, self.safe, self.on_restart = list(names), dict(safe), on_restart
        self.ch = [Channel() for _ in self.names]
        self.heartbeat_lost = False
        self.silenced = False
        self.port_gone = False  # the simulator stopped: no board, no pty (USB adapter pulled)
        self.node_running = False

    def unreachable(self):
        """Nothing the node writes reaches the board: it is silent, or the port is gone."""
        return self.silenced or self.port_gone

    # --- what the board may show -------------------------------------------------------------
    def allowed(self, i, now):
        c = self.ch[i]
        if c.flash is not None:
            return c.flash.allowed(now)
        return c.values

    def flash_running(self, now):
        return [i for i, c in enumerate(self.ch) if c.flash and now <= c.flash.done_after]

    def settle_flashes(self, now):
        """A pulse that surely ended leaves its final state (still unsettled for the node)."""
        for c in self.ch:
            if c.flash is not None and now > c.flash.done_after:
                c.values, c.flash = {c.flash.final()}, None

    def _set(self, i, values, why):
        c = self.ch[i]
        c.values, c.flash, c.why = set(values), None, why
        c.relaxed = why.startswith("known defect")

    # --- events ------------------------------------------------------------------------------
    def user_write(self, channels, states, ok, why):
        """A service, topic or share write of `channels`; ok: answered success (or seen done)."""
        if not ok:
            for i, s in zip(channels, states):
                self.ch[i].why = "I13 (%s answered success:false: must never reach the board)" % why
                self.ch[i].refused = (s, why)
                self.ch[i].lost_answer = self.unreachable()
            return
        for i, s in zip(channels, states):
            c = self.ch[i]
            c.refused = None
            self._set(i, {s}, "I1 (%s answered success:true)" % why)
            c.settled, c.restore, c.by_failsafe, c.held, c.pending_safe = True, {s}, False, False, False
            c.commanded_in_loss = self.heartbeat_lost
            c.lost_answer = False
        if "span_rewrites_between" in self.known and len(channels) > 1:
            self._span_may_rewrite(min(channels), max(channels), channels)

    def _span_may_rewrite(self, lo, hi, asked):
        for i in range(lo, hi + 1):
            c = self.ch[i]
            if i not in asked and (c.flash is not None or not c.settled):
                c.values = set(BOTH) if c.flash is not None else c.values
                c.flash, c.why, c.relaxed = None, "known defect span_rewrites_between", True

    def pulse(self, i, state, ok, sent, answered, duration):
        if not ok:
            self.ch[i].why = "I13 (pulse answered success:false: must never reach the board)"
            self.ch[i].lost_answer = self.unreachable()
            return
        c = self.ch[i]
        c.refused = None
        c.flash = Flash(state, sent, answered, duration)
        c.why = "I14 (pulse answered success:true: it ends by itself unless its channel is written)"
        c.settled, c.restore, c.by_failsafe, c.held, c.pending_safe = False, set(BOTH), False, False, False
        c.commanded_in_loss = self.heartbeat_lost
        c.lost_answer = False

    def failsafe(self, channels, why, hold=True):
        """Safe states written by a trigger (heartbeat, command timeout, start, stop)."""
        for i in channels:
            c = self.ch[i]
            c.refused = None
            if self.unreachable():
                c.pending_safe = True
                c.why = "%s (safe write pending: the device is silent)" % why
            else:
                self._set(i, {self.safe[i]}, why)
                c.settled = True
                c.lost_answer = False
            c.restore, c.by_failsafe, c.held, c.commanded_in_loss = {self.safe[i]}, True, hold, False
        if "span_rewrites_between" in self.known and not self.unreachable():
            self._span_may_rewrite(min(channels), max(channels), channels)

    def heartbeat_lost_event(self):
        self.heartbeat_lost = True
        self.failsafe(sorted(self.safe), "I2 (heartbeat lost: safe until commanded again)")

    def heartbeat_back(self):
        self.heartbeat_lost = False
        for c in self.ch:
            c.commanded_in_loss = False

    def restore_values(self, i):
        """What on_restart: restore leaves on channel i (issue 24's rule: the last state the node
        confirmed, user or fail-safe; safe while a trigger holds it)."""
        c = self.ch[i]
        if self.on_restart == "safe":
            # docs/failsafe.md, device restart: `safe` writes the safe states; a hold channel is
            # left as the restart left it (the caller has set that in c.values).
            if i in self.safe:
                return {self.safe[i]}, "I18 (on_restart: safe writes the safe state)"
            return set(c.values), "on_restart: safe leaves a hold channel as the restart left it"
        if c.pending_safe or c.held:
            values, why = {self.safe[i]}, "I3 (restore keeps a channel a trigger holds safe)"
        elif not c.settled:
            values, why = set(BOTH), "unknown (pulsed channel: not compared by the node)"
        elif c.by_failsafe:
            values, why = set(c.restore), "I5 (restore writes the state the fail-safe confirmed)"
        else:
            values, why = set(c.restore), "I5 (restore writes the last confirmed state)"
            if c.commanded_in_loss and i in self.safe:
                values.add(self.safe[i])  # the spec does not say whether the loss still holds it
        if c.by_failsafe and "restore_after_failsafe" in self.known:
            values, why = set(BOTH), "known defect restore_after_failsafe"
            c.relaxed = True  # and /diagnostics' claim on it is not checked either
        if c.lost_answer and not (c.pending_safe or c.held):
            # docs/failsafe.md ("What a write computes"): a command whose answer was lost leaves
            # its channel unknown, not restored, until a poll after it (a pulse: after its end),
            # whose level is taken as found; a power cycle in between is not seen on it.
            values, why = set(BOTH), "docs (a command whose answer was lost: unknown until a poll)"
        return values, why

    def restored(self):
        """The device restarted and the node restored it (the board answers)."""
        for i, c in enumerate(self.ch):
            values, why = self.restore_values(i)
            if not c.settled:
                c.settled = None  # the restore may have written it (the node compares it again)
            self._set(i, values, why)
            if c.pending_safe:
                c.pending_safe, c.settled = False, True

    def power_cycle(self, now):
        """Every relay off; returns True when the node must see a restart (a compared output
        changed), None when that is uncertain."""
        self.settle_flashes(now)
        if self.silenced:
            for i in range(len(self.names)):
                self._set(i, {0}, "power cycle of a silent device: all off")
            return False
        before = [set(self.allowed(i, now)) for i in range(len(self.names))]
        # settled None: a restore may have written the channel (then the node compares it) or not.
        settled = [self.ch[i].settled if self.ch[i].flash is None else False
                   for i in range(len(self.names))]
        sure = any(s is True and b == {1} for s, b in zip(settled, before))
        maybe = any(s is not False and 1 in b for s, b in zip(settled, before))
        off = [{0} for _ in self.names]
        for i in range(len(self.names)):
            self.ch[i].flash = None
        if self.on_restart == "safe":
            for i in range(len(self.names)):
                self.ch[i].values = {0}
        if sure or maybe:
            restored = [self.restore_values(i) for i in range(len(self.names))]
            for i, (values, why) in enumerate(restored):
                if not self.ch[i].settled:
                    values = set(BOTH)
                    self.ch[i].settled = None  # the restore may have written it, or not
                self._set(i, values if sure else values | off[i], why)
        else:
            for i in range(len(self.names)):
                self._set(i, {0}, "power cycle with nothing on: all off, no restart seen")
        return True if sure else (None if maybe else False)

    def port_lost(self):
        """The port went away (the simulator stopped with its pty: a USB adapter pulled).
        docs/failsafe.md: the node cannot write anything; a safe write asked for meanwhile
        fails and stays pending. The values kept are the board's when it went: what the node
        saw last, which port_back compares the new board with."""
        self.port_gone = True

    def port_back(self, now):
        """The port is back with a new simulator: a new board, every relay off (a power cycle;
        a silenced board answers again, the silence went with the old simulator).
        docs/failsafe.md: the node reopens the port and compares the outputs at the next poll,
        restart handling if they changed (on_restart: restore); a pending safe write is written
        when the device answers again, then a restart event. A device the node had offline
        answers again: a restart. Returns as power_cycle: True when a restart must be seen,
        None when that is uncertain, False when none needs to be."""
        self.port_gone = False
        pending = any(c.pending_safe for c in self.ch)
        if self.silenced:
            self.power_cycle(now)  # all off, nothing restored yet: the board is silent
            self.silenced = False
            self.restored()        # it answers again after being offline: a restart
            return True
        seen = self.power_cycle(now)
        if pending:
            self.restored()  # the pending safe writes, with on_restart's restore around them
            return True
        if seen is False:
            # Nothing compared was on, but polls that failed as the port went may have put the
            # device offline: then it "answers again after being offline", a restart too
            # (docs/failsafe.md), whose restore may write what a pulse left. Either is accepted.
            for i in range(len(self.names)):
                values, why = self.restore_values(i)
                self._set(i, values | {0}, why + ", or all off (no restart seen)")
            return None
        return seen

    def node_stopped(self, reached):
        if reached:
            self.failsafe(sorted(self.safe), "I10 (node stopped: safe states)", hold=True)
        self.node_running = False

    def node_started(self, now):
        """on_start: safe; hold channels keep what the board shows (the node reads them)."""
        self.settle_flashes(now)
        self.heartbeat_lost = False
        self.node_running = True
        for i, c in enumerate(self.ch):
            if i not in self.safe:
                # Read at start, never commanded: docs/failsafe.md has restore write "the last
                # states users commanded", issue 24 "the last state the node confirmed". Either
                # way (restored, or left at the power-on state) is accepted until that is settled.
                # A flash still running (a killed node's) is resumed before the first poll ("A
                # node started during a flash"): its final level is what a restore writes ("What
                # restore writes"), not the level found during it.
                found = {c.flash.final()} if c.flash is not None else set(c.values)
                c.restore, c.by_failsafe, c.held, c.settled = found | {0}, False, False, True
        self.failsafe(sorted(self.safe), "I9 (on_start: safe)", hold=False)


# --- the LD58A08 (bus.yaml `pwm`) and the Yespeed PDU (bus.yaml `pdu`) ----------------------
LD_NAMES = ["p0", "p1", "p2", "p3", "p4", "p5", "p6", "p7"]
LD_SAFE = {0: 0, 2: 1, 6: 0}  # p0 off, p2 on (slow channels), p6 off (fast); the others hold
PDU_NAMES = ["r0", "r1", "r2", "r3", "r4", "r5", "r6", "r7"]
PDU_SAFE = {0: 0, 1: 1}       # r0 off, r1 on; r2-r7 hold; on_restart: safe
CONTINUOUS = 0xFFFF           # an enable register's "run continuously" (docs/devices/ld58a08.md)
INF = float("inf")


class Run:
    """An LD58A08 PWM run (docs/failsafe.md, "Timed commands keep their end and final level"):
    a burst or timed fast run is driven by the device until its end, then off; a continuous run
    (duration None) is the device's until it is stopped. `during`: the levels it may show."""

    def __init__(self, during, sent, answered, duration):
        self.during = set(during)
        self.continuous = duration is None
        self.sure_until = INF if self.continuous else sent + duration - 0.15
        self.done_after = INF if self.continuous else answered + duration + 0.3

    def allowed(self, now):
        if now < self.sure_until:
            return set(self.during)
        if now > self.done_after:
            return {0}
        return self.during | {0}

    def final(self):
        return 0


class LdModel(Model):
    """The LD58A08's outputs with their PWM runs. Per channel, besides Model's: `kind` (None, a
    node's "timed" run, a "continuous" run, or "device": a run the node takes for the device's,
    not compared and not restored until a plain write), `stored` (what power-down save would
    start again: True, False, None = unknown) and `enable` (allowed enable register values, or
    None when not checked) with `enable_why`."""

    def __init__(self, known=()):
        super().__init__(known, LD_NAMES, LD_SAFE, "restore")
        for c in self.ch:
            c.kind, c.stored, c.enable, c.enable_why = None, False, {0}, "power-on: PWM off"

    def node_started(self, now):
        super().node_started(now)
        for i, c in enumerate(self.ch):
            if i not in self.safe and c.kind is None and c.flash is None:
                # docs/failsafe.md, "One intent per channel": where the node has commanded
                # nothing, the intent is the state it found at its first good poll (restored
                # after a power cycle). (Model accepts either on the LC board, older wording.)
                c.restore = set(c.values)

    def enable_allowed(self, i, now):
        c = self.ch[i]
        if c.kind == "timed" and c.flash is not None and now > c.flash.done_after:
            return {0}, "I1 (a timed PWM run ends by itself: enable 0 after its end)"
        return c.enable, c.enable_why

    def _stops_run(self, i, now, why):
        """A write that the node makes over a run (docs/devices/ld58a08.md, "Outputs and PWM":
        every output write stops the channel's PWM first when it runs)."""
        c = self.ch[i]
        running = c.flash is not None and (c.flash.continuous or now < c.flash.sure_until)
        if c.kind == "device" or (c.flash is not None and not running):
            c.stored = None  # an ended run's registers stay stored: the node need not stop it
        elif running:
            c.stored = False
        c.kind = None
        c.enable, c.enable_why = {0}, why

    def user_write(self, channels, states, ok, why):
        if ok:
            for i in channels:
                self._stops_run(i, time.time(), "I1 (%s: an output write stops the channel's "
                                "PWM first, docs/devices/ld58a08.md)" % why)
        super().user_write(channels, states, ok, why)

    def set_pwm(self, i, ok, during, sent, answered, duration, why):
        c = self.ch[i]
        if not ok:
            c.why = "I13 (%s answered success:false: must never reach the board)" % why
            c.lost_answer = self.unreachable()
            return
        c.refused = None
        c.flash = Run(during, sent, answered, duration)
        c.kind = "continuous" if duration is None else "timed"
        c.why = "I1 (%s answered success:true: the device drives the run)" % why
        # docs/failsafe.md: a PWM command ends a hold (precedence 2, docs/failsafe.md F18); restore writes the final
        # level of a timed command; a continuous run is the device's (not compared).
        c.settled, c.restore, c.by_failsafe, c.held, c.pending_safe = False, {0}, False, False, False
        c.commanded_in_loss = self.heartbeat_lost
        c.lost_answer = False
        c.stored = True
        if duration is None:
            c.enable, c.enable_why = {CONTINUOUS}, "I1 (%s: a continuous run until stopped)" % why
        else:
            c.enable, c.enable_why = None, "counting down"

    def stop_pwm(self, i, ok, why):
        """docs/failsafe.md: a stop the device confirmed ends the run at once; the next poll that
        reads the channel's PWM registers gives its level, taken as commanded (taken())."""
        c = self.ch[i]
        if not ok:
            c.why = "I13 (%s answered success:false)" % why
            return
        c.refused = None
        self._set(i, set(BOTH), "docs (after a stop the level is the device's until a poll reads it)")
        c.kind, c.stored = None, False
        c.enable, c.enable_why = {0}, "I1 (%s answered success:true: enable 0)" % why
        c.settled, c.by_failsafe, c.held, c.pending_safe = False, False, False, False
        c.commanded_in_loss = self.heartbeat_lost

    def taken(self, i, level):
        """The level a stop left, read by the node's polls since (its intent from then on)."""
        c = self.ch[i]
        self._set(i, {level}, "I1 (the level a confirmed stop_pwm left, taken as commanded)")
        c.restore, c.settled = {level}, True

    def failsafe(self, channels, why, hold=True):
        # docs/failsafe.md's table: "each output: safe state". Whether the node's safe write
        # stops a running PWM first (as its output writes do) is not said: the level is checked
        # (I2/I10), the enable register and what power-down save keeps are not (open question).
        for i in channels:
            c = self.ch[i]
            if c.flash is not None or c.kind is not None:
                c.stored = None
                c.enable, c.enable_why = None, "open question: does a safe write stop a PWM run?"
            if not self.unreachable():
                c.kind = None
        super().failsafe(channels, why, hold)

    def settle_flashes(self, now):
        for c in self.ch:
            if c.kind == "timed" and c.flash is not None and now > c.flash.done_after:
                # "A poll after the end that shows the final level ends the command there"
                c.kind, c.settled, c.restore = None, True, {0}
                c.enable, c.enable_why = {0}, "I1 (a timed PWM run ended: enable 0)"
        super().settle_flashes(now)

    def restore_values(self, i):
        c = self.ch[i]
        if not (c.pending_safe or c.held):
            if c.kind == "timed":
                # "What restore writes": the final level of a timed command (not started again).
                return {0}, "I5 (restore writes a timed PWM run's final level, off)"
            if c.kind in ("device", "continuous") and c.flash is not None:
                # "A restore does not write a channel the device reports running a PWM that is
                # no timed command of the node's" (continuous runs, found runs, saved runs).
                return set(c.flash.during), "I5 (a restore does not undo a PWM run the device drives)"
        return super().restore_values(i)

    def power_cycle(self, now, save=False):
        """Every output off, PWM registers cleared, or with power-down save on (`save`) the
        registers as last written run again (docs/devices/ld58a08.md, "Power cycle")."""
        self.settle_flashes(now)
        before = [(c.kind, c.flash, c.stored) for c in self.ch]
        seen = super().power_cycle(now)
        for i, (kind, flash, stored) in enumerate(before):
            c = self.ch[i]
            if c.held or c.pending_safe:
                if save and stored is not False:
                    # precedence 1 (docs/failsafe.md F17): a held channel the poll shows otherwise (a PWM run someone
                    # else started) is written safe again. Whether that stops the run: open.
                    c.stored, c.enable, c.enable_why = None, None, "held channel under a saved run"
                elif not save:
                    c.stored, c.enable, c.enable_why = False, {0}, "power cycle: PWM off"
                continue
            # A kind whose run a write since dropped (_set clears c.flash) has no run to start
            # again: only a channel with its run still recorded is a continuous run here.
            if save and stored is True and kind == "continuous" and flash is not None:
                c.flash, c.kind = Run(flash.during, now, now, None), "continuous"
                c.values, c.why = set(flash.during), "I5 (a saved continuous run runs again; a " \
                    "restore does not undo a PWM run the device drives)"
                c.enable, c.enable_why = {CONTINUOUS}, "I5 (a restore does not stop a saved run)"
                c.settled = False
            elif save and stored is not False:
                # A saved burst or timed run starts again: the device's ("a run that a
                # power-down save restarts ends at a level that is the device's doing").
                c.flash, c.kind = Run(BOTH, now, now, None), "device"
                c.values, c.why = set(BOTH), "I5 (a run power-down save started again: the device's)"
                c.enable, c.enable_why, c.settled = None, "a saved run", False
            else:
                if not save:
                    c.stored = False
                c.enable, c.enable_why = {0}, "power cycle: PWM registers off (no save)"
                if kind == "continuous" and flash is not None:
                    # "a continuous PWM run the node started is started again by a restore when
                    # the read just before the restore shows it stopped" (docs/failsafe.md,
                    # "What restore writes"): at the poll that reads its registers (up to 8
                    # polls), so either until then; a node started since (a SIGKILL) did not
                    # start it and leaves it off.
                    c.flash, c.kind = Run(flash.during | {0}, now, now, None), "continuous"
                    c.values, c.why, c.settled = flash.during | {0}, "I5 (a restore starts the " \
                        "node's continuous run again)", False
                    c.stored = None
                    c.enable, c.enable_why = {0, CONTINUOUS}, "I5 (off after the power cycle, " \
                        "then started again by the restore)"
                elif kind == "device":
                    # A run the node took for the device's is not started again; the device's
                    # until a plain write.
                    c.flash, c.kind = Run({0}, now, now, None), "device"
                    c.values, c.why, c.settled = {0}, "I5 (a PWM run a restart ended stays off)", False
                elif kind == "timed":
                    c.kind, c.settled, c.restore = None, True, {0}
                    self._set(i, {0}, "I5 (restore writes a timed run's final level, off)")
        return seen
