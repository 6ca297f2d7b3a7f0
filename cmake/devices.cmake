# Device models and the bus thread.
target_sources(modbus_rtu_core PRIVATE
  src/devices/device.cpp
  src/devices/failsafe.cpp
  src/devices/ld58a08.cpp
  src/devices/lc_relay8.cpp
  src/devices/yespeed_pdu.cpp
  src/devices/registry.cpp
  src/devices/output_batch.cpp
  src/core/bus_scheduler.cpp
)
