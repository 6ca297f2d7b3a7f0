# ROS-free core: framing, link, devices, scheduler. Never links roscpp.
add_library(modbus_rtu_core
  src/core/bus_config.cpp
  src/core/frame.cpp
  src/core/link_config.cpp
  src/core/port_claim.cpp
  src/core/request_framer.cpp
  src/core/slave_server.cpp
  src/core/status.cpp
  src/core/types.cpp
)
target_include_directories(modbus_rtu_core PUBLIC include ${LIBMODBUS_INCLUDE_DIRS})
target_link_libraries(modbus_rtu_core PUBLIC ${LIBMODBUS_LIBRARIES} yaml-cpp Threads::Threads)
# The link (libmodbus) and the device models add their sources to the core library.
include(cmake/link.cmake)
include(cmake/devices.cmake)
