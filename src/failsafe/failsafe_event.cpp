#include "modbus_rtu_driver/failsafe/failsafe_event.h"

namespace modbus_rtu_driver {

const char* triggerName(Trigger trigger) {
  return nameIn(kTriggerNames, trigger).data();  // the names are literals: terminated
}

const char* actionName(Action action) {
  return nameIn(kActionNames, action).data();
}

bool holdsChannels(Trigger trigger) {
  return trigger == Trigger::kHeartbeat || trigger == Trigger::kCommandTimeout;
}

Action restartAction(OnRestart policy) {
  switch (policy) {
    case OnRestart::kRestore:
      return Action::kRestore;
    case OnRestart::kSafe:
      return Action::kSafe;
    case OnRestart::kLeave:
      break;
  }
  return Action::kLeave;
}

}  // namespace modbus_rtu_driver
