// The fail-safe's two words for an event (ROS-free): what set it off and what it wrote. One enum
// each, compared as enums in the code; their names are what ~failsafe's events carry
// (docs/ros_api.md, FailsafeEvent's `trigger` and `action`) and what the logs say.
#pragma once

#include <cstdint>

#include "modbus_rtu_driver/core/modbus/text.h"
#include "modbus_rtu_driver/devices/failsafe.h"

namespace modbus_rtu_driver {

// docs/failsafe.md, "What happens when". kHeartbeat and kCommandTimeout last: they hold their
// channels safe until commanded again (ChannelIntents::hold); the others write once.
enum class Trigger : uint8_t { kHeartbeat, kCommandTimeout, kStart, kShutdown, kRestart };
// kSafe: the safe states (or a generic device's safe values); kRestore: what users had set;
// kLeave: nothing written (on_restart: leave).
enum class Action : uint8_t { kSafe, kRestore, kLeave };

inline constexpr NameTable<Trigger, 5> kTriggerNames{{{Trigger::kHeartbeat, "heartbeat"},
                                                      {Trigger::kCommandTimeout, "command_timeout"},
                                                      {Trigger::kStart, "start"},
                                                      {Trigger::kShutdown, "shutdown"},
                                                      {Trigger::kRestart, "restart"}}};
inline constexpr NameTable<Action, 3> kActionNames{
    {{Action::kSafe, "safe"}, {Action::kRestore, "restore"}, {Action::kLeave, "leave"}}};

const char* triggerName(Trigger trigger);
const char* actionName(Action action);
// A trigger that holds its channels safe until they are commanded again.
bool holdsChannels(Trigger trigger);
// What a restart does under `policy` (on_restart's words are the actions' own).
Action restartAction(OnRestart policy);

}  // namespace modbus_rtu_driver
