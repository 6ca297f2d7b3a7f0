# RtuLink sources: target_sources(modbus_rtu_core PRIVATE ...)
