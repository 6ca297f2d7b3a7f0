#include "modbus_rtu_driver/failsafe/kept_timed_commands.h"

namespace modbus_rtu_driver {

std::vector<KeptTimedCommand> keepTimedCommands(const std::vector<TimedIntent>& running,
                                                double now) {
  std::vector<KeptTimedCommand> kept;
  for (const TimedIntent& t : running) {
    KeptTimedCommand k;
    k.channel = t.channel;
    k.during = t.during ? static_cast<int>(*t.during) : -1;
    k.after = t.after;
    k.ends = t.seconds < 0 ? -1.0 : now + t.seconds;
    kept.push_back(k);
  }
  return kept;
}

std::vector<TimedIntent> resumeTimedCommands(const std::vector<KeptTimedCommand>& kept, double now,
                                             size_t channels) {
  std::vector<TimedIntent> running;
  for (const KeptTimedCommand& k : kept) {
    if (k.channel >= channels) continue;
    if (k.ends >= 0 && k.ends <= now) continue;  // ended while no node ran: the poll shows it
    TimedIntent t;
    t.channel = k.channel;
    if (k.during >= 0) t.during = k.during != 0;
    t.after = k.after;
    t.seconds = k.ends < 0 ? -1.0 : k.ends - now;
    running.push_back(t);
  }
  return running;
}

}  // namespace modbus_rtu_driver
