# The ROS-free layer libraries and every library's source list, written once. Included by the
# catkin build (CMakeLists.txt) and by the instrumented builds (test/sanitizers/CMakeLists.txt:
# ASan + UBSan with gcc, or libFuzzer with clang), so a source file added here is in all of them.
#
# The includer has found libmodbus (LIBMODBUS_*), yaml-cpp, Threads, nlohmann_json and CLI11, and
# may set:
#   MODBUS_RTU_LIBRARY_TYPE   SHARED in the instrumented builds: device types register through
#                             static initializers in objects nothing references, which a static
#                             archive would leave out of the executable. Unset (catkin): catkin's
#                             default, shared.
#   MODBUS_RTU_ALLOW_UNDEFINED  ON in the fuzz build: clang links its sanitizer runtimes into
#                             executables only, so a library leaves __asan_* undefined and
#                             --no-undefined would fail. The gcc builds keep the rule.
#
# The layers, each a library linked only on the ones below it; --no-undefined makes a call that
# goes the wrong way a link error, and scripts/check_conventions.sh checks the includes:
#   core (framing, the link, the bus thread, slave role; ROS-free)
#   <- devices (one class per device type, fail-safe policy) <- config (the bus node's YAML)
#   <- ros (adapters, node).   sim and tools sit on core (tools also on devices).
# The repository's root, without "cmake/..": the include path then reads as before (catkin_lint
# reads the set(), the build the normalised path).
set(MODBUS_RTU_DIR ${CMAKE_CURRENT_LIST_DIR}/..)
get_filename_component(MODBUS_RTU_DIR ${MODBUS_RTU_DIR} ABSOLUTE)

function(layer target)
  if(NOT MODBUS_RTU_ALLOW_UNDEFINED)
    target_link_options(${target} PRIVATE -Wl,--no-undefined)
  endif()
endfunction()

# Core: framing, the RTU link (libmodbus plus our own reader), the bus thread, the slave role.
add_library(modbus_rtu_core ${MODBUS_RTU_LIBRARY_TYPE}
  ${MODBUS_RTU_DIR}/src/core/bus_scheduler.cpp
  ${MODBUS_RTU_DIR}/src/core/config_yaml.cpp
  ${MODBUS_RTU_DIR}/src/core/fd_io.cpp
  ${MODBUS_RTU_DIR}/src/core/frame.cpp
  ${MODBUS_RTU_DIR}/src/core/link.cpp
  ${MODBUS_RTU_DIR}/src/core/link_config.cpp
  ${MODBUS_RTU_DIR}/src/core/link_line.cpp
  ${MODBUS_RTU_DIR}/src/core/make_transport.cpp
  ${MODBUS_RTU_DIR}/src/core/mbap.cpp
  ${MODBUS_RTU_DIR}/src/core/modbus_tcp_link.cpp
  ${MODBUS_RTU_DIR}/src/core/modbus_tcp_server.cpp
  ${MODBUS_RTU_DIR}/src/core/rate_meter.cpp
  ${MODBUS_RTU_DIR}/src/core/realtime.cpp
  ${MODBUS_RTU_DIR}/src/core/request_framer.cpp
  ${MODBUS_RTU_DIR}/src/core/rtu_link.cpp
  ${MODBUS_RTU_DIR}/src/core/serial_port.cpp
  ${MODBUS_RTU_DIR}/src/core/share_gateway.cpp
  ${MODBUS_RTU_DIR}/src/core/signal.cpp
  ${MODBUS_RTU_DIR}/src/core/signal_yaml.cpp
  ${MODBUS_RTU_DIR}/src/core/slave_config.cpp
  ${MODBUS_RTU_DIR}/src/core/slave_server.cpp
  ${MODBUS_RTU_DIR}/src/core/tcp_link.cpp
  ${MODBUS_RTU_DIR}/src/core/task_queue.cpp
  ${MODBUS_RTU_DIR}/src/core/tcp_socket.cpp
  ${MODBUS_RTU_DIR}/src/core/types.cpp
)
target_include_directories(modbus_rtu_core PUBLIC ${MODBUS_RTU_DIR}/include ${LIBMODBUS_INCLUDE_DIRS})
target_link_libraries(modbus_rtu_core PUBLIC ${LIBMODBUS_LIBRARIES} yaml-cpp Threads::Threads)
layer(modbus_rtu_core)

# Devices: one class per type, one registry line each; merged writes; the fail-safe policy.
add_library(modbus_rtu_devices ${MODBUS_RTU_LIBRARY_TYPE}
  ${MODBUS_RTU_DIR}/src/devices/device.cpp
  ${MODBUS_RTU_DIR}/src/devices/failsafe.cpp
  ${MODBUS_RTU_DIR}/src/devices/generic_device.cpp
  ${MODBUS_RTU_DIR}/src/devices/lc_relay8.cpp
  ${MODBUS_RTU_DIR}/src/devices/ld58a08.cpp
  ${MODBUS_RTU_DIR}/src/devices/output_batch.cpp
  ${MODBUS_RTU_DIR}/src/devices/registry.cpp
  ${MODBUS_RTU_DIR}/src/devices/signal_map.cpp
  ${MODBUS_RTU_DIR}/src/devices/yespeed_pdu.cpp
)
target_link_libraries(modbus_rtu_devices PUBLIC modbus_rtu_core)
layer(modbus_rtu_devices)

# The bus node's configuration: link, devices (checked against their type), fail-safe keys.
add_library(modbus_rtu_config ${MODBUS_RTU_LIBRARY_TYPE} ${MODBUS_RTU_DIR}/src/config/bus_config.cpp)
target_link_libraries(modbus_rtu_config PUBLIC modbus_rtu_devices)
layer(modbus_rtu_config)

# Simulator (ROS-free): simulated devices, the line on a pty, fault injection, control socket.
add_library(modbus_rtu_sim ${MODBUS_RTU_LIBRARY_TYPE}
  ${MODBUS_RTU_DIR}/src/sim/dm500_garbage.cpp
  ${MODBUS_RTU_DIR}/src/sim/dm500_master.cpp
  ${MODBUS_RTU_DIR}/src/sim/pty_link.cpp
  ${MODBUS_RTU_DIR}/src/sim/sim_device.cpp
  ${MODBUS_RTU_DIR}/src/sim/sim_gateway.cpp
  ${MODBUS_RTU_DIR}/src/sim/sim_generic.cpp
  ${MODBUS_RTU_DIR}/src/sim/sim_lc_relay8.cpp
  ${MODBUS_RTU_DIR}/src/sim/sim_ld58a08.cpp
  ${MODBUS_RTU_DIR}/src/sim/sim_yespeed_pdu.cpp
  ${MODBUS_RTU_DIR}/src/sim/simulator.cpp
  ${MODBUS_RTU_DIR}/src/sim/simulator_config.cpp
  ${MODBUS_RTU_DIR}/src/sim/simulator_control.cpp
  ${MODBUS_RTU_DIR}/src/sim/simulator_tcp.cpp
)
target_link_libraries(modbus_rtu_sim PUBLIC modbus_rtu_core yaml-cpp Threads::Threads)
layer(modbus_rtu_sim)

# Commissioning tool (ROS-free): a library the unit tests use (its main is the includer's).
add_library(modbus_rtu_commission_lib ${MODBUS_RTU_LIBRARY_TYPE}
  ${MODBUS_RTU_DIR}/src/tools/commission_args.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_device.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_output.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_scan.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_session.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_table.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_usage.cpp
)
target_link_libraries(modbus_rtu_commission_lib PUBLIC modbus_rtu_devices nlohmann_json::nlohmann_json
  PRIVATE CLI11::CLI11)
layer(modbus_rtu_commission_lib)

# The ROS layer's sources (adapters, one small class per device type, and the node). Only a list:
# each build makes the library with its own ROS (catkin's targets, or pkg-config's in the
# sanitizer build) on modbus_rtu_config.
set(MODBUS_RTU_ROS_SOURCES
  ${MODBUS_RTU_DIR}/src/ros/adapter_registry.cpp
  ${MODBUS_RTU_DIR}/src/ros/bus_node.cpp
  ${MODBUS_RTU_DIR}/src/ros/device_adapter.cpp
  ${MODBUS_RTU_DIR}/src/ros/device_failsafe.cpp
  ${MODBUS_RTU_DIR}/src/ros/digital_states_publisher.cpp
  ${MODBUS_RTU_DIR}/src/ros/generic_adapter.cpp
  ${MODBUS_RTU_DIR}/src/ros/lc_relay8_adapter.cpp
  ${MODBUS_RTU_DIR}/src/ros/ld58a08_adapter.cpp
  ${MODBUS_RTU_DIR}/src/ros/raw_writes.cpp
  ${MODBUS_RTU_DIR}/src/ros/share_bridge.cpp
  ${MODBUS_RTU_DIR}/src/ros/slave_node.cpp
  ${MODBUS_RTU_DIR}/src/ros/yaml_params.cpp
  ${MODBUS_RTU_DIR}/src/ros/yespeed_pdu_adapter.cpp
)
