"""What the LC board's coils must be, written from docs/failsafe.md (the spec) and the rules of
issue 24, not from the node's code. Each channel's expectation carries the invariant it comes
from, so a mismatch names the invariant that failed.

Invariants (issue 24, "Prove it by randomized scenarios"):
  I1 a write answered success:true is on the board (unless a later event changed it)
  I2 a write answered success:false never reaches the board later
  I3 while the heartbeat is lost, no output with a safe state leaves it without a new command
  I4 after a node stop, every output with a safe state is in it
  I5 no write touches a channel it was not asked to
  I6 what /diagnostics and ~failsafe claim matches the board
and docs/failsafe.md's "port lost" row: the node reports the port not open, cannot write
anything meanwhile (a write answers success:false, I2), and once the port is back compares the
outputs at the next poll: a restart (on_restart: restore) when they changed, and pending safe
writes done with a restart event.
"""

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
        self.refused = None       # the state a write answered success:false asked for (I2)
        self.lost_answer = False  # a write to a silent device answered success:false


class Model:
    def __init__(self, known=()):
        self.known = set(known)
        self.ch = [Channel() for _ in NAMES]
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
                self.ch[i].why = "I2 (%s answered success:false: must never reach the board)" % why
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
            self.ch[i].why = "I2 (pulse answered success:false: must never reach the board)"
            self.ch[i].lost_answer = self.unreachable()
            return
        c = self.ch[i]
        c.refused = None
        c.flash = Flash(state, sent, answered, duration)
        c.why = "I5 (pulse answered success:true: it ends by itself unless its channel is written)"
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
                self._set(i, {SAFE[i]}, why)
                c.settled = True
                c.lost_answer = False
            c.restore, c.by_failsafe, c.held, c.commanded_in_loss = {SAFE[i]}, True, hold, False
        if "span_rewrites_between" in self.known and not self.unreachable():
            self._span_may_rewrite(min(channels), max(channels), channels)

    def heartbeat_lost_event(self):
        self.heartbeat_lost = True
        self.failsafe(sorted(SAFE), "I3 (heartbeat lost: safe until commanded again)")

    def heartbeat_back(self):
        self.heartbeat_lost = False
        for c in self.ch:
            c.commanded_in_loss = False

    def restore_values(self, i):
        """What on_restart: restore leaves on channel i (issue 24's rule: the last state the node
        confirmed, user or fail-safe; safe while a trigger holds it)."""
        c = self.ch[i]
        if c.pending_safe or c.held:
            values, why = {SAFE[i]}, "I3 (restore keeps a channel a trigger holds safe)"
        elif not c.settled:
            values, why = set(BOTH), "unknown (pulsed channel: not compared by the node)"
        elif c.by_failsafe:
            values, why = set(c.restore), "I3 (restore writes the state the fail-safe confirmed)"
        else:
            values, why = set(c.restore), "I1 (restore writes the last confirmed state)"
            if c.commanded_in_loss and i in SAFE:
                values.add(SAFE[i])  # the spec does not say whether the loss still holds it
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
            for i in range(len(NAMES)):
                self._set(i, {0}, "power cycle of a silent device: all off")
            return False
        before = [set(self.allowed(i, now)) for i in range(len(NAMES))]
        # settled None: a restore may have written the channel (then the node compares it) or not.
        settled = [self.ch[i].settled if self.ch[i].flash is None else False
                   for i in range(len(NAMES))]
        sure = any(s is True and b == {1} for s, b in zip(settled, before))
        maybe = any(s is not False and 1 in b for s, b in zip(settled, before))
        off = [{0} for _ in NAMES]
        for i in range(len(NAMES)):
            self.ch[i].flash = None
        if sure or maybe:
            restored = [self.restore_values(i) for i in range(len(NAMES))]
            for i, (values, why) in enumerate(restored):
                if not self.ch[i].settled:
                    values = set(BOTH)
                    self.ch[i].settled = None  # the restore may have written it, or not
                self._set(i, values if sure else values | off[i], why)
        else:
            for i in range(len(NAMES)):
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
            for i in range(len(NAMES)):
                values, why = self.restore_values(i)
                self._set(i, values | {0}, why + ", or all off (no restart seen)")
            return None
        return seen

    def node_stopped(self, reached):
        if reached:
            self.failsafe(sorted(SAFE), "I4 (node stopped: safe states)", hold=True)
        self.node_running = False

    def node_started(self, now):
        """on_start: safe; hold channels keep what the board shows (the node reads them)."""
        self.settle_flashes(now)
        self.heartbeat_lost = False
        self.node_running = True
        for i, c in enumerate(self.ch):
            if i not in SAFE:
                # Read at start, never commanded: docs/failsafe.md has restore write "the last
                # states users commanded", issue 24 "the last state the node confirmed". Either
                # way (restored, or left at the power-on state) is accepted until that is settled.
                c.restore, c.by_failsafe, c.held, c.settled = set(c.values) | {0}, False, False, True
        self.failsafe(sorted(SAFE), "on_start: safe", hold=False)
