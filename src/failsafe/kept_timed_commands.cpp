#include "modbus_rtu_driver/failsafe/kept_timed_commands.h"

namespace modbus_rtu_driver {

std::vector<KeptTimedCommand> keepTimedCommands(const std::vector<TimedIntent>& running,
                                                double now) {
  std::vector<KeptTimedCommand> kept;
  for (const TimedIntent& t : running) {
    // A run with no end (a continuous PWM run, a run the device drives) is not kept: the next
    // node takes it as found, as its first poll reads it (docs/failsafe.md, "What restore
    // writes"), and a restore of that node does not start it again.
    if (t.seconds < 0) continue;
    KeptTimedCommand k;
    k.channel = t.channel;
    k.during = t.during ? static_cast<int>(*t.during) : -1;
    k.after = t.after;
    k.ends = now + t.seconds;
    kept.push_back(k);
  }
  return kept;
}

std::vector<TimedIntent> resumeTimedCommands(const std::vector<KeptTimedCommand>& kept, double now,
                                             size_t channels) {
  std::vector<TimedIntent> running;
  for (const KeptTimedCommand& k : kept) {
    if (k.channel >= channels) continue;
    if (k.ends <= now) continue;  // ended while no node ran (or no end): the poll shows it
    TimedIntent t;
    t.channel = k.channel;
    if (k.during >= 0) t.during = k.during != 0;
    t.after = k.after;
    t.seconds = k.ends - now;
    running.push_back(t);
  }
  return running;
}

}  // namespace modbus_rtu_driver
