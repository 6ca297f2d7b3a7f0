// What each output channel should show, and why (failsafe/channel_intents.h), on a manual
// clock: restart detection, what restore and the safe writes write, holds, owed writes, timed
// commands and the dead man. Each test names the line of docs/failsafe.md it checks; the
// "item N" tests are issue #32's reproductions, made at the module's level.
#include <gtest/gtest.h>

#include <algorithm>

#include "device_fixtures.h"
#include "modbus_rtu_driver/devices/lc_relay8.h"
#include "modbus_rtu_driver/devices/ld58a08.h"
#include "modbus_rtu_driver/failsafe/channel_intents.h"

using namespace modbus_rtu_driver;
using namespace std::chrono_literals;
using Verdict = ChannelIntents::Verdict;

namespace {

FailsafeConfig relays(OnRestart policy) {
  FailsafeConfig c;  // pump, valve, lamp, fan
  c.safe_state = {SafeState::kOff, SafeState::kOff, SafeState::kOn, SafeState::kLeave};
  c.on_restart = policy;
  return c;
}

Verdict poll(ChannelIntents& t, const std::vector<bool>& outputs, bool was_offline = false,
             std::vector<uint8_t>* changed = nullptr) {
  t.pollStarting();  // as the adapter does before every poll
  return t.observePoll(outputs, {}, was_offline, changed);
}

std::vector<bool> statesOf(const OutputTargets& t, size_t n) {
  std::vector<bool> s(n, false);
  for (size_t i = 0; i < t.channels.size(); ++i) s[t.channels[i]] = t.states[i];
  return s;
}

}  // namespace

// "a poll shows outputs that changed with no command in between (a power cycle drops relays)"
TEST(ChannelIntents, APollThatDiffersWithNoCommandIsARestart) {
  ManualClock clock;
  ChannelIntents t(FailsafeConfig{}, 4, clock);
  std::vector<uint8_t> changed;
  EXPECT_EQ(poll(t, {true, false, true, false}), Verdict::kNormal);  // found at start
  EXPECT_EQ(poll(t, {true, false, true, false}), Verdict::kNormal);
  t.commanded({1}, {true}, CommandSource::kUser);
  EXPECT_EQ(poll(t, {true, true, true, false}), Verdict::kNormal);
  EXPECT_EQ(poll(t, {false, false, false, false}, false, &changed), Verdict::kOutputsChanged);
  EXPECT_EQ(changed, (std::vector<uint8_t>{0, 1, 2}));
  EXPECT_EQ(poll(t, {false, false, false, false}, true), Verdict::kCameBack);
}

// Item 7: "restore writes the last state the node confirmed on each channel", and the states it
// found at its start (a fan kept on from the previous node).
TEST(ChannelIntents, Item7RestorePutsBackWhatTheNodeFoundAtItsStart) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, true});  // the fan is on, from before the node started
  t.commanded({0}, {true}, CommandSource::kUser);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kOutputsChanged);  // power cycle
  const OutputTargets r = t.afterPollTargets(Verdict::kOutputsChanged);
  EXPECT_EQ(r.channels, (std::vector<uint8_t>{0, 1, 2, 3}));
  EXPECT_EQ(r.states, (std::vector<bool>{true, false, false, true}));
}

// Item 1: a failed dead-man write is owed on its channel only.
TEST(ChannelIntents, Item1AFailedDeadManWriteIsOwedOnItsChannelOnly) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kLeave), 4, clock);
  poll(t, {false, false, false, false});
  t.commanded({0, 1, 2}, {true, true, false}, CommandSource::kUser);
  const auto since = clock.now();
  t.hold({0}, Trigger::kCommandTimeout);
  const OutputTargets held = t.heldTargets({0});
  EXPECT_EQ(held.channels, (std::vector<uint8_t>{0}));
  t.owe(held, since);  // the board was silent
  clock.advance(2s);
  // It answers again: pump off only; valve and lamp stay as commanded.
  const OutputTargets w = t.afterPollTargets(poll(t, {true, true, false, false}, true));
  EXPECT_EQ(w.channels, (std::vector<uint8_t>{0}));
  EXPECT_EQ(w.states, (std::vector<bool>{false}));
  // With on_restart: restore: the pump off over the restore of the others.
  ChannelIntents r(relays(OnRestart::kRestore), 4, clock);
  poll(r, {false, false, false, false});
  r.commanded({0, 1, 2}, {true, true, false}, CommandSource::kUser);
  r.hold({0}, Trigger::kCommandTimeout);
  r.owe(r.heldTargets({0}), clock.now());
  EXPECT_EQ(statesOf(r.afterPollTargets(Verdict::kCameBack), 4),
            (std::vector<bool>{false, true, false, false}));
}

// Item 2: a later dead-man write that succeeds pays its own channel, not the heartbeat's.
TEST(ChannelIntents, Item2ADeadManWritePaysOnlyItsOwnChannel) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kLeave), 4, clock);
  poll(t, {false, false, false, false});
  t.commanded({0, 2}, {true, false}, CommandSource::kUser);
  const auto lost = clock.now();
  t.hold({}, Trigger::kHeartbeat);  // the heartbeat is lost while the board is silent
  t.owe(t.heldTargets({}), lost);
  clock.advance(1s);
  t.commanded({0}, {false}, CommandSource::kSafe);  // a dead-man write on the pump succeeds
  const OutputTargets owed = t.owed();
  EXPECT_EQ(owed.channels, (std::vector<uint8_t>{1, 2}));  // valve off, lamp on still owed
  EXPECT_EQ(owed.states, (std::vector<bool>{false, true}));
  EXPECT_TRUE(t.anyHeld());
}

// Item 3: "the newest command wins": a safe write owed from before a confirmed command is not
// written over it.
TEST(ChannelIntents, Item3AnOwedSafeWriteDoesNotUndoANewerCommand) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});
  t.commanded({0}, {true}, CommandSource::kUser);
  const auto lost = clock.now();
  t.hold({}, Trigger::kHeartbeat);
  t.owe(t.heldTargets({}), lost);
  clock.advance(30ms);
  t.commanded({0}, {true}, CommandSource::kUser);  // pump/set true answers success
  EXPECT_FALSE(t.held(0));
  const OutputTargets w = t.afterPollTargets(Verdict::kCameBack);
  EXPECT_TRUE(statesOf(w, 4)[0]) << "the restart write switched the pump off again";
  // The same for a share client's FC05 during the heartbeat loss.
  t.commanded({1}, {true}, CommandSource::kShare);
  EXPECT_TRUE(statesOf(t.afterPollTargets(Verdict::kCameBack), 4)[1]);
  // A safe write that fails after the command was confirmed owes nothing on that channel.
  t.owe(OutputTargets{{0}, {false}}, lost);
  const OutputTargets owed = t.owed();
  EXPECT_EQ(std::count(owed.channels.begin(), owed.channels.end(), 0), 0);
}

// Item 4: "a timed command a restart interrupted is not started again: restore writes its final
// level" (LC flash-close on out4 that was on before it).
TEST(ChannelIntents, Item4RestoreWritesAFlashsFinalLevelNotTheStateBeforeIt) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});
  t.commanded({3}, {true}, CommandSource::kUser);
  t.timed(TimedIntent{3, true, false, 6.0}, CommandSource::kTimed);  // flash-close 6 s
  clock.advance(1s);
  EXPECT_EQ(poll(t, {false, false, false, true}), Verdict::kNormal);
  clock.advance(1s);
  // Silent for 2.5 s, then back: the restore writes out4 off (the flash's end), not on.
  const OutputTargets w = t.afterPollTargets(poll(t, {false, false, false, true}, true));
  EXPECT_EQ(statesOf(w, 4)[3], false);
  EXPECT_EQ(std::count(w.channels.begin(), w.channels.end(), 3), 1);
}

// docs/ros_api.md: a read back does not confirm a write whose answer was lost on a channel a
// flash may still drive (its level may be the flash's); from its end plus the slack on, it does.
TEST(ChannelIntents, AFlashMayRunUntilItsEndPlusTheSlack) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kLeave), 4, clock);
  poll(t, {false, false, false, false});
  EXPECT_EQ(t.timedMayRun(), (std::vector<bool>{false, false, false, false}));
  t.timed(TimedIntent{3, false, true, 2.0}, CommandSource::kTimed);  // flash-open 2 s
  EXPECT_EQ(t.timedMayRun(), (std::vector<bool>{false, false, false, true}));
  clock.advance(2s + 500ms);  // the end plus 0.5 s: the slack is 0.5 s + 2 % of 2 s
  EXPECT_TRUE(t.timedMayRun()[3]);
  clock.advance(100ms);
  EXPECT_FALSE(t.timedMayRun()[3]);
  t.commanded({1}, {true}, CommandSource::kUser);  // a plain level is no timed command
  EXPECT_FALSE(t.timedMayRun()[1]);
}

// Item 4 (LD58A08): out0 on, a 3-pulse burst that ends off, then a power cycle.
TEST(ChannelIntents, Item4RestoreAfterAPwmBurstWritesItsFinalLevel) {
  ManualClock clock;
  FailsafeConfig config;
  config.on_restart = OnRestart::kRestore;
  ChannelIntents t(config, 8, clock);
  poll(t, std::vector<bool>(8, false));
  t.commanded({0}, {true}, CommandSource::kUser);
  PwmSettings s;
  s.channel = 0;
  s.period = 1.0;
  s.on_time = 0.5;
  s.pulses = 3;
  t.timed(Ld58a08(devtest::config("ld58a08", 2)).pwmIntent(s), CommandSource::kTimed);
  clock.advance(1500ms);
  EXPECT_EQ(poll(t, std::vector<bool>(8, false)), Verdict::kNormal);  // toggling: any level
  clock.advance(5s);
  EXPECT_EQ(poll(t, std::vector<bool>(8, false)), Verdict::kNormal);  // ended off
  const OutputTargets w = t.afterPollTargets(Verdict::kCameBack);
  EXPECT_FALSE(statesOf(w, 8)[0]);
}

// Item 5: a share client's FC16 flash is decoded per device type: its end is not a restart.
TEST(ChannelIntents, Item5AShareFlashThroughRegistersEndsWithoutARestart) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kSafe), 8, clock);
  poll(t, std::vector<bool>(8, false));
  DeviceConfig dc;
  dc.address = 8;
  const LcRelay8 board(dc);
  const Request flash = Request::writeMultipleRegisters(8, LcRelay8::flashRegister(0),
                                                        {LcRelay8::kFlashClose, 20});  // 2.0 s
  const std::vector<TimedIntent> decoded = board.timedWrittenBy(flash);
  ASSERT_EQ(decoded.size(), 1u);
  t.timed(decoded[0], CommandSource::kShare);
  std::vector<bool> on(8, false);
  on[0] = true;
  clock.advance(1s);
  EXPECT_EQ(poll(t, on), Verdict::kNormal);
  clock.advance(1500ms);  // the flash ended
  EXPECT_EQ(poll(t, std::vector<bool>(8, false)), Verdict::kNormal);
  clock.advance(10s);
  EXPECT_EQ(poll(t, std::vector<bool>(8, false)), Verdict::kNormal);
  // An LD58A08 PWM started through its registers is the device's to drive.
  Ld58a08 ld(dc);
  const auto pwm = ld.timedWrittenBy(
      Request::writeMultipleRegisters(8, Ld58a08::pwmRegister(2), {10, 5, 0xFFFF}));
  ASSERT_EQ(pwm.size(), 1u);
  EXPECT_EQ(pwm[0].channel, 2);
  EXPECT_LT(pwm[0].seconds, 0);
}

// "a channel that a heartbeat loss or command timeout put safe stays safe on every restore until
// it is commanded again"
TEST(ChannelIntents, ARestoreKeepsHeldChannelsSafeUntilCommandedAgain) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  t.commanded({0, 1, 2, 3}, {true, true, false, true}, CommandSource::kUser);
  t.hold({}, Trigger::kHeartbeat);
  EXPECT_EQ(statesOf(t.afterPollTargets(Verdict::kCameBack), 4),
            (std::vector<bool>{false, false, true, true}));
  t.commanded({2}, {true}, CommandSource::kRestore);  // the fail-safe's own: still held
  EXPECT_TRUE(t.anyHeld());
  t.commanded({0, 1, 2}, {true, true, false}, CommandSource::kUser);  // commanded again
  EXPECT_FALSE(t.anyHeld());
  EXPECT_EQ(statesOf(t.afterPollTargets(Verdict::kCameBack), 4),
            (std::vector<bool>{true, true, false, true}));
}

// "what any other write changed (a flash or PWM through registers) is taken as commanded at the
// next poll: no restart is seen, nothing is reverted, and a later restore writes them again"
TEST(ChannelIntents, AnUndecodedRegisterWriteIsTakenAsCommandedAtTheNextPoll) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});
  t.hold({1}, Trigger::kHeartbeat);
  t.adoptChangesNextPoll(CommandSource::kShare);
  std::vector<uint8_t> changed;
  EXPECT_EQ(poll(t, {false, true, false, false}, false, &changed), Verdict::kNormal);
  EXPECT_TRUE(changed.empty());
  EXPECT_TRUE(t.tookAdoptedWrite());
  EXPECT_FALSE(t.anyHeld());
  EXPECT_TRUE(statesOf(t.afterPollTargets(Verdict::kCameBack), 4)[1]);
  // Only the next poll: a later change with no write is a restart again.
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kOutputsChanged);
}

// Found by the scenario test (seed 1268616613): a poll that a write ran inside is not compared.
TEST(ChannelIntents, APollThatAWriteRanInsideIsNotCompared) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 2, clock);
  poll(t, {false, true});
  t.pollStarting();
  t.commanded({1}, {false}, CommandSource::kShare);  // between the poll's reads and its end
  EXPECT_EQ(t.observePoll({false, true}, {}, false, nullptr), Verdict::kNormal);
  EXPECT_EQ(poll(t, {false, false}), Verdict::kNormal);
}

// "Channels that the device switches by itself (a running PWM, an LC flash) are not compared"
// until the run ends; a poll near a timed command's end may show either level.
TEST(ChannelIntents, TimedChannelsAreComparedWithTheirLevelAndEnd) {
  ManualClock clock;
  ChannelIntents t(FailsafeConfig{}, 2, clock);
  poll(t, {false, false});
  t.timed(TimedIntent{0, true, false, 10.0}, CommandSource::kTimed);
  clock.advance(5s);
  EXPECT_EQ(poll(t, {true, false}), Verdict::kNormal);
  EXPECT_EQ(poll(t, {false, false}), Verdict::kOutputsChanged);  // off halfway: power cycle
  t.timed(TimedIntent{0, true, false, 10.0}, CommandSource::kTimed);
  clock.advance(9800ms);  // within the end's slack: either level
  EXPECT_EQ(poll(t, {false, false}), Verdict::kNormal);
  clock.advance(60s);
  EXPECT_EQ(poll(t, {false, false}), Verdict::kNormal);
  EXPECT_EQ(poll(t, {true, false}), Verdict::kOutputsChanged);  // settled off: on is a change
  // A continuous PWM run: any level, as long as it runs.
  t.timed(TimedIntent{1, std::nullopt, false, -1.0}, CommandSource::kTimed);
  EXPECT_EQ(poll(t, {true, true}), Verdict::kNormal);
  EXPECT_EQ(poll(t, {true, false}), Verdict::kNormal);
}

TEST(ChannelIntents, AfterPollEachOnRestartPolicy) {
  const auto after = [](OnRestart policy) {
    ManualClock clock;
    FailsafeConfig config;
    config.safe_state = {SafeState::kOff, SafeState::kOn};
    config.on_restart = policy;
    ChannelIntents t(config, 2, clock);
    t.commanded({0, 1}, {true, false}, CommandSource::kUser);
    return t.afterPollTargets(Verdict::kOutputsChanged).states;
  };
  EXPECT_EQ(after(OnRestart::kRestore), (std::vector<bool>{true, false}));
  EXPECT_EQ(after(OnRestart::kSafe), (std::vector<bool>{false, true}));
  EXPECT_TRUE(after(OnRestart::kLeave).empty());
}

// With on_restart: leave a restart is counted once: the changed levels are taken as they are.
TEST(ChannelIntents, LeaveCountsOneRestartNotOneEveryPoll) {
  ManualClock clock;
  ChannelIntents t(FailsafeConfig{}, 2, clock);
  poll(t, {true, true});
  EXPECT_EQ(poll(t, {false, true}), Verdict::kOutputsChanged);
  EXPECT_EQ(poll(t, {false, true}), Verdict::kNormal);
}

TEST(ChannelIntents, TheDeadMansDeadlineOnAManualClock) {
  ManualClock clock;
  FailsafeConfig c;
  c.safe_state = {SafeState::kOff, SafeState::kOff};
  c.command_timeout = {1.0, 0.0};
  ChannelIntents t(c, 2, clock);
  t.commandReceived(0, true);
  t.commandReceived(1, true);  // no timeout on channel 1
  clock.advance(999ms);
  EXPECT_TRUE(t.expiredCommands().empty());
  t.commandReceived(0, true);  // renewed
  clock.advance(999ms);
  EXPECT_TRUE(t.expiredCommands().empty());
  clock.advance(1ms);
  EXPECT_EQ(t.expiredCommands(), (std::vector<uint8_t>{0}));
  EXPECT_TRUE(t.expiredCommands().empty());  // once
  t.commandReceived(0, true);
  t.commandReceived(0, false);  // off ends it
  clock.advance(5s);
  EXPECT_TRUE(t.expiredCommands().empty());
}

// Item 6: "the next node ... resumes them before its first poll": a node killed during a flash
// hands its running timed commands to the next one, which does not take the end for a restart.
TEST(ChannelIntents, Item6TheNextNodeResumesAKilledNodesFlash) {
  ManualClock clock;
  ChannelIntents killed(relays(OnRestart::kSafe), 4, clock);
  poll(killed, {false, false, false, false});
  killed.commanded({0}, {true}, CommandSource::kUser);
  killed.timed(TimedIntent{3, true, false, 5.0}, CommandSource::kTimed);  // flash-close 5 s
  clock.advance(1s);
  const std::vector<TimedIntent> running = killed.runningTimed();
  ASSERT_EQ(running.size(), 1u);
  EXPECT_EQ(running[0].channel, 3);
  EXPECT_NEAR(running[0].seconds, 4.0, 1e-9);

  ChannelIntents next(relays(OnRestart::kSafe), 4, clock);
  next.resumeTimed(running);
  EXPECT_EQ(poll(next, {true, false, false, true}), Verdict::kNormal);  // during the flash
  clock.advance(5s);
  EXPECT_EQ(poll(next, {true, false, false, false}), Verdict::kNormal);  // its end
  EXPECT_TRUE(next.runningTimed().empty());
  // Without the handover the same end is a restart: what the node could not tell apart.
  ManualClock clock2;
  ChannelIntents blind(relays(OnRestart::kSafe), 4, clock2);
  poll(blind, {true, false, false, true});
  clock2.advance(5s);
  EXPECT_EQ(poll(blind, {true, false, false, false}), Verdict::kOutputsChanged);
}

// docs/failsafe.md line 76: once its safe write is confirmed, a hold writes a held channel safe
// again when a poll shows it otherwise, whatever on_restart says (leave included); not before
// its safe write was confirmed (that write is still on its way).
TEST(ChannelIntents, AHoldPutsItsChannelBackWhateverOnRestartSays) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kLeave), 4, clock);
  poll(t, {true, true, true, false});
  t.hold({}, Trigger::kHeartbeat);
  EXPECT_EQ(poll(t, {true, true, true, false}), Verdict::kNormal);
  EXPECT_TRUE(t.heldNotSafe().empty());  // its safe write has not run yet
  t.commanded({0, 1, 2}, {false, false, true}, CommandSource::kSafe);
  EXPECT_EQ(poll(t, {false, false, true, false}), Verdict::kNormal);
  EXPECT_TRUE(t.heldNotSafe().empty());
  // A power cycle drops every relay: the lamp (safe on) shows off.
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kOutputsChanged);
  EXPECT_EQ(t.heldNotSafe(), (std::vector<uint8_t>{2}));
  const OutputTargets w = t.afterPollTargets(Verdict::kOutputsChanged);
  EXPECT_EQ(w.channels, (std::vector<uint8_t>{2}));
  EXPECT_EQ(w.states, (std::vector<bool>{true}));
  // Commanded again: no longer held, nothing written back.
  t.commanded({2}, {false}, CommandSource::kUser);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kNormal);
  EXPECT_TRUE(t.heldNotSafe().empty());
  EXPECT_TRUE(t.afterPollTargets(Verdict::kNormal).empty());
}

// docs/failsafe.md, precedence 1: once a hold's safe write is confirmed, a poll that shows the
// held channel otherwise writes it safe again, also when the level comes from a command whose
// answer was lost (taken as found: no command, so the hold stands). Found in stop 40's search.
TEST(ChannelIntents, ALostCommandsLevelOnAHeldChannelIsWrittenSafeAgain) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kLeave), 4, clock);
  poll(t, {true, true, true, false});
  t.hold({}, Trigger::kHeartbeat);
  t.commanded({0, 1, 2}, {false, false, true}, CommandSource::kSafe);
  EXPECT_EQ(poll(t, {false, false, true, false}), Verdict::kNormal);
  // A command on the lamp whose answer was lost: unknown until the next poll, which shows it off.
  t.adoptNextPoll(2, CommandSource::kFound);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kNormal);  // taken as found
  EXPECT_EQ(t.heldNotSafe(), (std::vector<uint8_t>{2}));
  const OutputTargets w = t.afterPollTargets(Verdict::kNormal);
  EXPECT_EQ(w.channels, (std::vector<uint8_t>{2}));
  EXPECT_EQ(w.states, (std::vector<bool>{true}));
}

// docs/failsafe.md line 92: a timed command whose answer was lost is not compared (and not
// restored) until its end plus the slack; the first poll after it gives the channel's level.
TEST(ChannelIntents, ALostAnswersTimedCommandIsUnknownUntilItsEnd) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});
  t.adoptNextPoll(1, CommandSource::kFound, 3.0);
  clock.advance(1s);
  EXPECT_EQ(poll(t, {false, true, false, false}), Verdict::kNormal);  // it may run
  EXPECT_EQ(t.afterPollTargets(Verdict::kCameBack).channels,
            (std::vector<uint8_t>{0, 2, 3}));  // channel 1 is not restored while unknown
  clock.advance(3s);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kNormal);  // taken as found
  EXPECT_EQ(poll(t, {false, true, false, false}), Verdict::kOutputsChanged);
}

// docs/failsafe.md, "Restart detection needs polls": a PWM run the device reports that is no
// timed command of the node's (a power-down save restarted it after a power cycle) is not
// compared until a plain write settles the channel, also after the device reports it ended.
TEST(ChannelIntents, ARunTheDeviceReportsIsNotComparedUntilAPlainWrite) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kSafe), 4, clock);
  poll(t, {false, false, false, false});
  clock.advance(1s);
  // A power cycle; the saved run shows its on phase before its registers are read.
  EXPECT_EQ(poll(t, {false, false, false, true}), Verdict::kOutputsChanged);
  t.pollStarting();
  EXPECT_EQ(
      t.observePoll({false, false, false, false}, {false, false, false, true}, false, nullptr),
      Verdict::kNormal);  // its registers read: the device runs it
  clock.advance(5s);
  t.pollStarting();
  EXPECT_EQ(
      t.observePoll({false, false, false, false}, {false, false, false, false}, false, nullptr),
      Verdict::kNormal);  // the run ended off: the device's doing, not a restart
  EXPECT_EQ(poll(t, {false, false, false, true}), Verdict::kNormal);
  t.commanded({3}, {false}, CommandSource::kUser);  // a plain write settles it
  EXPECT_EQ(poll(t, {false, false, false, true}), Verdict::kOutputsChanged);
}

// The same rule for a run the read just before a restore finds (docs line 88 leaves it out of
// the restore): the channel stays the device's after the run ends, not compared until written.
TEST(ChannelIntents, ARunFoundBeforeARestoreStaysTheDevicesAfterItEnds) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});
  t.commanded({3}, {true}, CommandSource::kUser);
  clock.advance(1s);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kOutputsChanged);  // power cycle
  t.observeRuns({false, false, false, true});  // a saved run restarted on channel 3
  EXPECT_EQ(t.afterPollTargets(Verdict::kOutputsChanged, {false, false, false, true}).channels,
            (std::vector<uint8_t>{0, 1, 2}));
  clock.advance(5s);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kNormal);  // it ended off
}

// docs/failsafe.md F31: a PWM write whose answer was lost may have started its run: a client's
// coil write over it before the run's end plus the slack finds it running (runsUnderAdoption),
// and a read cannot confirm a plain write there (timedMayRun). Stop 57's I5 case.
TEST(ChannelIntents, APwmWriteWhoseAnswerWasLostCountsAsARunUntilItsEnd) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});
  t.adoptRunNextPoll(3, CommandSource::kFound, 0.4, 0.9);  // a 0.4 s burst, answer lost
  EXPECT_EQ(t.lostRunsUnderAdoption(), (std::vector<bool>{false, false, false, true}));
  EXPECT_FALSE(t.runsUnderAdoption(true)[3]) << "no run the node knows";
  EXPECT_TRUE(t.timedMayRun()[3]);
  clock.advance(500ms);
  EXPECT_TRUE(t.lostRunsUnderAdoption()[3]) << "its end passed, not its slack (0.5 s + 2 %)";
  clock.advance(410ms);
  EXPECT_FALSE(t.lostRunsUnderAdoption()[3]);
  t.adoptRunNextPoll(2, CommandSource::kFound, -1.0, 0.0);  // a continuous run, answer lost
  clock.advance(1h);
  EXPECT_TRUE(t.lostRunsUnderAdoption()[2]) << "a continuous one for good (until a read)";
}

// docs/failsafe.md line 92: a plain write whose answer was lost on a channel where a flash
// still runs (heard or not: either level may show until the flash ends) is decided by the
// first poll after the flash's end plus the slack, not by a poll during the flash.
TEST(ChannelIntents, ALostWriteOverARunningFlashIsDecidedAfterTheFlashEnds) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kLeave), 4, clock);
  poll(t, {false, false, false, false});
  t.timed(TimedIntent{0, true, false, 1.5}, CommandSource::kTimed);  // flash-close 1.5 s
  clock.advance(300ms);
  t.adoptNextPoll(0, CommandSource::kFound);  // `set on` whose answer was lost (not heard)
  clock.advance(1s);
  EXPECT_EQ(poll(t, {true, false, false, false}), Verdict::kNormal);  // the flash, still on
  clock.advance(1s);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kNormal);  // it ended: found off
  EXPECT_EQ(poll(t, {true, false, false, false}), Verdict::kOutputsChanged);
}

// The same with two lost writes in a row over the flash (stop 42, case
// open_30min_restart_without_cause: a raw FC15 and then `set on` to a silent board): the second
// one must not forget that the flash may still run, whichever of them the board heard.
TEST(ChannelIntents, TwoLostWritesOverARunningFlashAreDecidedAfterTheFlashEnds) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kLeave), 4, clock);
  poll(t, {false, false, false, false});
  t.timed(TimedIntent{0, true, false, 1.8}, CommandSource::kTimed);  // flash-close 1.8 s
  clock.advance(200ms);
  t.adoptNextPoll(0, CommandSource::kShare);  // a client's FC15, answer lost (not heard)
  clock.advance(250ms);
  t.adoptNextPoll(0, CommandSource::kFound);  // `set on`, answer lost (not heard)
  clock.advance(900ms);
  EXPECT_EQ(poll(t, {true, false, false, false}), Verdict::kNormal);  // the flash, still on
  clock.advance(600ms);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kNormal);  // it ended (1.95 s)
  clock.advance(700ms);
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kNormal);  // found off
  EXPECT_EQ(poll(t, {true, false, false, false}), Verdict::kOutputsChanged);
}

// docs/failsafe.md, "A command whose answer was lost": a write sent while a timed command still
// ran waits for the first poll after that end plus the slack, also when the node learns that
// its answer was lost only after the end (the write's timeout and its read back's took longer
// than the flash had left). Stop 43, case lost_write_learned_after_flash_end_waits_for_slack:
// a poll inside the slack took the level the write set as found, a power cycle then showed as
// that channel's change, and the restore put the write's level back.
TEST(ChannelIntents, AWriteSentDuringAFlashWaitsForItsSlackWhenItsLossIsLearnedAfterTheEnd) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});
  t.timed(TimedIntent{0, true, false, 2.0}, CommandSource::kTimed);  // flash-close 2 s
  clock.advance(2100ms);  // the write went out at 1.65 s; its loss is known now, after the end
  t.adoptNextPoll(0, CommandSource::kFound);  // `set on`, no answer (the board did it)
  EXPECT_EQ(t.pollStarting(), (std::vector<uint8_t>{})) << "still within 0.5 s + 2 % of the end";
  clock.advance(300ms);
  EXPECT_EQ(poll(t, {true, false, false, false}), Verdict::kNormal);  // either level may show
  clock.advance(300ms);  // past 2 s + 0.54 s: the deciding poll, after a power cycle
  EXPECT_EQ(t.pollStarting(), (std::vector<uint8_t>{0}));
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kNormal) << "taken as found";
  EXPECT_EQ(t.expected(0, clock.now()).kind, Expectation::Kind::kLevel);
  EXPECT_FALSE(t.expected(0, clock.now()).level);
}

// docs/failsafe.md, "A command whose answer was lost": a poll names the channels whose deciding
// read is due (the device reads those first: an LD58A08's PWM registers), not before the end
// plus the slack, and no more once a poll that read them decided.
TEST(ChannelIntents, APollNamesTheChannelsWhoseDecidingReadIsDue) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kLeave), 4, clock);
  poll(t, {false, false, false, false});
  t.timed(TimedIntent{1, true, false, 1.0}, CommandSource::kTimed);
  clock.advance(100ms);
  t.adoptNextPoll(1, CommandSource::kShare);  // answer lost over the running flash
  t.adoptNextPoll(3, CommandSource::kShare);  // answer lost, nothing running
  EXPECT_EQ(t.pollStarting(), (std::vector<uint8_t>{3}));
  // A poll that did not read channel 3's state (read_now false) leaves it waiting.
  EXPECT_EQ(
      t.observePoll({false, true, false, false}, {}, false, nullptr, {true, true, true, false}),
      Verdict::kNormal);
  clock.advance(1500ms);  // past 1.1 s + 0.5 s + 2 %
  EXPECT_EQ(t.pollStarting(), (std::vector<uint8_t>{1, 3}));
  EXPECT_EQ(t.observePoll({false, false, false, true}, {}, false, nullptr), Verdict::kNormal);
  EXPECT_EQ(t.pollStarting(), (std::vector<uint8_t>{}));
}

// docs/failsafe.md line 67: a client's decoded stop on a held channel that a poll showed
// otherwise (a power cycle; its safe write again not yet done) changed nothing when the next
// poll shows the same level: no command, the hold stays and writes the safe state again.
// Stop 42: the level before was taken from the intent (the safe state), so the stop was taken
// as the client's command and ended the hold.
TEST(ChannelIntents, AStopThatLeavesAHeldChannelAsAPollShowedItKeepsTheHold) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, true, false});
  t.hold({2}, Trigger::kHeartbeat);
  t.commanded({2}, {true}, CommandSource::kSafe);  // the lamp's safe state (on), confirmed
  clock.advance(100ms);
  poll(t, {false, false, false, false});  // a power cycle: the lamp off
  EXPECT_EQ(t.heldNotSafe(), (std::vector<uint8_t>{2}));
  t.adoptChangeNextPoll(2, CommandSource::kShare);  // a client's PWM stop there, confirmed
  clock.advance(100ms);
  poll(t, {false, false, false, false});
  EXPECT_TRUE(t.held(2));
  EXPECT_EQ(t.heldNotSafe(), (std::vector<uint8_t>{2}));
}

// docs/failsafe.md, "Timed commands keep their end": a stop the device confirmed ends the run at
// once, so the next poll gives the channel's level as commanded, before the run's planned end
// (stop 39: a burst stopped by stop_pwm was left out of a restore until its end plus slack).
TEST(ChannelIntents, AConfirmedStopIsTakenAtTheNextPollNotAtTheRunsEnd) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});
  t.timed(TimedIntent{1, std::nullopt, false, 5.0}, CommandSource::kTimed);  // a 5 s burst
  clock.advance(200ms);
  t.stoppedNextPoll(1, CommandSource::kTimed);  // stop_pwm, confirmed
  clock.advance(200ms);
  EXPECT_EQ(poll(t, {false, true, false, false}), Verdict::kNormal);           // the coil: on
  EXPECT_EQ(poll(t, {false, false, false, false}), Verdict::kOutputsChanged);  // power cycle
  const OutputTargets r = t.afterPollTargets(Verdict::kOutputsChanged);
  EXPECT_EQ(statesOf(r, 4)[1], true);  // restored on, 4.6 s before the burst would have ended
  EXPECT_NE(std::find(r.channels.begin(), r.channels.end(), 1), r.channels.end());
}

// docs/failsafe.md, "Restart detection needs polls": a poll during which a write ran is not
// compared, but a run it read is still the device's report (an LD58A08's registers are read one
// channel per poll: that poll may be the only one that sees a power-down save's run).
TEST(ChannelIntents, ARunReadByAPollAWriteRanDuringStillMakesTheChannelTheDevices) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});  // found: all off
  clock.advance(500ms);
  t.pollStarting();
  t.writeRan();  // a queued write ran between this poll's transactions
  const std::vector<bool> runs{true, false, false, false}, read{true, true, true, true};
  EXPECT_EQ(t.observePoll({true, false, false, false}, runs, false, nullptr, read),
            Verdict::kNormal);
  clock.advance(5s);  // the run ended on; its level is the device's doing, not a restart
  t.pollStarting();
  EXPECT_EQ(t.observePoll({true, false, false, false}, {}, false, nullptr, read), Verdict::kNormal);
}

// docs/failsafe.md "Restart detection needs polls" and "What restore writes" (#32 item 7): a
// continuous run the node started, read stopped with no stop carried, is a restart; a restore
// starts it again with the write that started it, unless the read just before shows it running
// (a power-down save restarted it) or the channel is held. A run the node did not start (a
// client's coil write kept one going) is the device's: its end is no restart.
TEST(ChannelIntents, TheNodesContinuousRunReadStoppedIsARestartAndARestoreStartsItAgain) {
  ManualClock clock;
  FailsafeConfig config;
  config.safe_state = std::vector<SafeState>(8, SafeState::kLeave);
  config.safe_state[6] = SafeState::kOff;
  config.on_restart = OnRestart::kRestore;
  ChannelIntents t(config, 8, clock);
  const std::vector<bool> none(8, false);
  std::vector<bool> fan_runs = none;
  fan_runs[6] = true;
  t.pollStarting();
  t.observePoll(none, none, false, nullptr, std::vector<bool>(8, true));
  PwmSettings fan;
  fan.channel = 6;
  fan.frequency = 500;
  fan.duty_cycle = 40;
  fan.duration = 0;  // continuous
  const TimedIntent run = Ld58a08(devtest::config("ld58a08", 2)).pwmIntent(fan);
  ASSERT_TRUE(run.restart.has_value());
  t.timed(run, CommandSource::kTimed);
  clock.advance(1s);
  std::vector<bool> read6 = none;
  read6[6] = true;
  std::vector<uint8_t> changed;
  t.pollStarting();
  EXPECT_EQ(t.observePoll(none, fan_runs, false, &changed, read6), Verdict::kNormal);
  // A poll that does not read channel 6's registers says nothing of it.
  clock.advance(1s);
  t.pollStarting();
  EXPECT_EQ(t.observePoll(none, none, false, &changed, none), Verdict::kNormal);
  // One that reads them stopped: a restart on channel 6.
  clock.advance(1s);
  t.pollStarting();
  EXPECT_EQ(t.observePoll(none, none, false, &changed, read6), Verdict::kOutputsChanged);
  EXPECT_EQ(changed, (std::vector<uint8_t>{6}));
  // The restore starts it again with its write; not when the read before shows it running.
  const auto again = t.runsToStartAgain(Verdict::kOutputsChanged, none);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].channel, 6);
  // `if (!...) FAIL()`, not ASSERT_TRUE: clang-tidy 19 sees that FAIL() returns, not ASSERT_TRUE.
  const auto& restart = again[0].restart;
  if (!restart) FAIL() << "no restart request";
  EXPECT_EQ(restart->values, (std::vector<uint16_t>{500, 40, 65535}));
  EXPECT_FALSE(restart->repeatable);
  EXPECT_TRUE(t.runsToStartAgain(Verdict::kOutputsChanged, fan_runs).empty());
  EXPECT_TRUE(t.runsToStartAgain(Verdict::kNormal, none).empty());
  const OutputTargets levels = t.afterPollTargets(Verdict::kOutputsChanged, none);
  EXPECT_EQ(std::count(levels.channels.begin(), levels.channels.end(), 6), 0)
      << "a run is started again, never written as a level";
  // A held channel is not started again.
  t.hold({6}, Trigger::kHeartbeat);
  EXPECT_TRUE(t.runsToStartAgain(Verdict::kOutputsChanged, none).empty());
}

TEST(ChannelIntents, UnderLeaveAStoppedContinuousRunCountsOnceAndAKeptRunsEndIsNoRestart) {
  ManualClock clock;
  FailsafeConfig config;
  config.on_restart = OnRestart::kLeave;
  ChannelIntents t(config, 8, clock);
  const std::vector<bool> none(8, false), all(8, true);
  std::vector<bool> runs = none;
  runs[6] = runs[7] = true;
  t.pollStarting();
  t.observePoll(none, runs, false, nullptr, all);
  PwmSettings fan;
  fan.channel = 6;
  fan.frequency = 500;
  fan.duty_cycle = 40;
  t.timed(Ld58a08(devtest::config("ld58a08", 2)).pwmIntent(fan), CommandSource::kTimed);
  // Channel 7: a client's coil write kept a run going (no settings the node knows).
  TimedIntent kept;
  kept.channel = 7;
  kept.after = true;
  t.timed(kept, CommandSource::kShare);
  clock.advance(1s);
  std::vector<uint8_t> changed;
  t.pollStarting();
  EXPECT_EQ(t.observePoll(none, none, false, &changed, all), Verdict::kOutputsChanged);
  EXPECT_EQ(changed, (std::vector<uint8_t>{6}));
  EXPECT_TRUE(t.runsToStartAgain(Verdict::kOutputsChanged, none).empty()) << "leave";
  clock.advance(1s);
  t.pollStarting();
  EXPECT_EQ(t.observePoll(none, none, false, &changed, all), Verdict::kNormal)
      << "taken as it is: the next poll does not count it again";
}

// docs/failsafe.md F37: a run read at a poll is the device's until a plain write, also after it
// ended, and also when a later read of that poll failed (stop 58's case
// run_read_by_a_poll_whose_outputs_read_failed): a restore leaves the channel.
TEST(ChannelIntents, ARunReadByAPollWhoseLaterReadFailedIsTheDevices) {
  ManualClock clock;
  ChannelIntents t(relays(OnRestart::kRestore), 4, clock);
  poll(t, {false, false, false, false});  // found, nothing runs
  t.pollStarting();
  t.observeRunsOfFailedPoll({false, true, false, false});  // channel 1 read running, then a failure
  const OutputTargets w = t.afterPollTargets(poll(t, {true, false, false, false}));  // a restart
  EXPECT_EQ(std::count(w.channels.begin(), w.channels.end(), 1), 0)
      << "the restore writes the channel the device ran a PWM on";
  EXPECT_EQ(std::count(w.channels.begin(), w.channels.end(), 0), 1);
  // A channel commanded after the failed poll started is the caller's, not the run's.
  ChannelIntents u(relays(OnRestart::kRestore), 4, clock);
  poll(u, {false, false, false, false});
  u.pollStarting();
  clock.advance(10ms);
  u.commanded({1}, {true}, CommandSource::kUser);
  u.observeRunsOfFailedPoll({false, true, false, false});
  const OutputTargets v = u.afterPollTargets(poll(u, {true, true, false, false}));
  EXPECT_EQ(std::count(v.channels.begin(), v.channels.end(), 1), 1);
}
