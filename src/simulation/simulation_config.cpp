// The configuration a seed draws (docs/simulation.md, "What it runs").
#include <yaml-cpp/yaml.h>

#include "modbus_rtu_driver/core/config/signal.h"
#include "simulation_world.h"

namespace modbus_rtu_driver {
namespace simulation_world {

Config drawConfig(uint64_t seed) {
  Rng r{seed ^ 0xC0FFEEull};
  Config c;
  c.link.port = "memory";
  c.link.baud = r.pick({9600, 19200});
  c.link.response_timeout = r.pick({0.05, 0.1, 0.2});
  c.link.retries = r.pick({0, 1, 2});
  c.link.late_reply_guard = 0;
  c.heartbeat = r.pick({0.3, 0.5, 1.0});
  for (int d = 0; d < kDevices; ++d) {
    DeviceConfig dc;
    dc.name = kNames[d];
    dc.type = kTypes[d];
    dc.address = kAddr[d];
    dc.poll_rate = r.pick({2.0, 5.0, 10.0});
    FailsafeConfig& fs = dc.failsafe;
    fs.on_start_safe = r.chance(50);
    if (d != kGen) {
      fs.on_restart = r.pick({OnRestart::kRestore, OnRestart::kSafe, OnRestart::kLeave});
      fs.safe_state.resize(kChannels);
      fs.command_timeout.assign(kChannels, 0.0);
      for (int ch = 0; ch < kChannels; ++ch) {
        const int k = r.below(10);
        fs.safe_state[ch] = k < 4 ? SafeState::kLeave : k < 8 ? SafeState::kOff : SafeState::kOn;
        if (fs.safe_state[ch] != SafeState::kLeave && r.chance(30))
          fs.command_timeout[ch] = r.pick({0.3, 1.0, 2.0});
      }
    } else {
      // The drive as a user writes it (docs/ros_api.md, generic devices), through the node's
      // own parser; only the safe values are drawn.
      const int run_safe = r.chance(70) ? 0 : 1;
      const int speed_safe = r.pick({0, 10, 25});
      dc.generic = parseSignalMap(
          YAML::Load("signals:\n"
                     "  - {name: run, table: coil, address: 0, type: bool, writable: true,\n"
                     "     safe_value: " +
                     std::to_string(run_safe) +
                     "}\n"
                     "  - {name: speed, table: holding_register, address: 0x10, type: int16,\n"
                     "     scale: 0.1, unit: Hz, writable: true, min: 0, max: 50,\n"
                     "     safe_value: " +
                     std::to_string(speed_safe) +
                     "}\n"
                     "  - {name: mode, table: holding_register, address: 0x20, type: uint16,\n"
                     "     writable: true, safe_value: 3}\n"),
          "devices/drive/", "");
      c.generic_refuses = r.chance(50);
    }
    c.devices.push_back(dc);
  }
  c.ld_save = r.chance(30);
  // The LD58A08's own heartbeat (F7: that device only) in half the seeds; drawn last,
  // so the draws above stay what they were.
  if (r.chance(50)) {
    c.devices[kLd].failsafe.heartbeat_topic = "pwm_alive";
    c.devices[kLd].failsafe.heartbeat_timeout = r.pick({0.3, 1.0});
  }
  // Drawn after every other draw, so that those stay what they were.
  c.kept_latency = r.pick({0.0, 0.0, 0.05, 0.3});
  // The link's late-reply guard (docs/ros_api.md; default 0.1 s), or none.
  c.link.late_reply_guard = r.pick({0.1, 0.1, 0.0});
  return c;
}

}  // namespace simulation_world
}  // namespace modbus_rtu_driver
