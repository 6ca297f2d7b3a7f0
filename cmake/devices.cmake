# Device models and BusScheduler: target_sources(modbus_rtu_core PRIVATE ...)
