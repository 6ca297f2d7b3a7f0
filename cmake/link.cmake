# RtuLink sources: target_sources(modbus_rtu_core PRIVATE ...)
target_sources(modbus_rtu_core PRIVATE src/core/rtu_link.cpp src/core/rtu_link_line.cpp)
