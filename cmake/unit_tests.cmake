# The unit tests, gtests of the ROS-free code, each listed once for every build: the catkin build
# (test/CMakeLists.txt: catkin_add_gtest, run by `catkin_make run_tests` and scripts/test.sh) and
# the sanitizer build (test/sanitizers/CMakeLists.txt: ASan + UBSan, run by
# scripts/sanitized_tests.sh). Each test links only its own layer, so a test of a lower layer that
# needs a higher one does not link.
#
# The includer has included cmake/layers.cmake and cmake/executables.cmake and defines
#   modbus_rtu_gtest(name source...)   one gtest executable with gtest's main (GTest's
#                                      RUN_ALL_TESTS: every case runs), registered as a test.
get_filename_component(MODBUS_RTU_REAL_DIR ${MODBUS_RTU_DIR} REALPATH)
set(MODBUS_RTU_UNIT_DIR ${MODBUS_RTU_REAL_DIR}/test/unit)
# Every frame the manuals print, kept in the repository as test data.
set(MODBUS_RTU_GOLDEN_FRAMES ${MODBUS_RTU_REAL_DIR}/test/data/golden_frames.tsv)

# unit_test(name library): test/unit/<name>.cpp on <library> (a ;-list for several).
function(unit_test name library)
  modbus_rtu_gtest(${name} ${MODBUS_RTU_UNIT_DIR}/${name}.cpp)
  set_property(GLOBAL APPEND PROPERTY MODBUS_RTU_LISTED_TESTS ${MODBUS_RTU_UNIT_DIR}/${name}.cpp)
  target_link_libraries(${name} ${library})
  target_compile_definitions(${name} PRIVATE GOLDEN_FRAMES_PATH="${MODBUS_RTU_GOLDEN_FRAMES}"
    REPO_DIR="${MODBUS_RTU_REAL_DIR}")
endfunction()

# Core: framing against the manuals' frames, line timing, the request framer, the link on real
# ptys (golden bytes on the wire, each error kind), the bus thread on a manual clock, slave role.
unit_test(test_frame modbus_rtu_core)
unit_test(test_table_names modbus_rtu_core)
unit_test(test_mbap modbus_rtu_core)
unit_test(test_realtime modbus_rtu_core)
unit_test(test_link_config modbus_rtu_core)
# Issue 34 item 3: a kind of link registered from a test file reaches the node's configuration,
# the factory and the commissioning tool's checks and help.
unit_test(test_link_types "modbus_rtu_node_config;modbus_rtu_commission_lib")
# Issue 26 item 3: enum names and their parse from one table, and the one join.
unit_test(test_text modbus_rtu_core)
unit_test(test_request_framer modbus_rtu_core)
# Issue 26 item 4: a request is checked and encoded once, every attempt sends that frame.
unit_test(test_encode_once modbus_rtu_core)
# Issue 50: the poll path's allocations (encode a read, decode its reply, read it), counted.
unit_test(test_poll_allocations modbus_rtu_core)
unit_test(test_rtu_link_golden modbus_rtu_core)
unit_test(test_rtu_link_faults modbus_rtu_core)
unit_test(test_rtu_tcp_link modbus_rtu_core)
unit_test(test_modbus_tcp_link modbus_rtu_core)
unit_test(test_bus_scheduler modbus_rtu_core)
unit_test(test_task_queue modbus_rtu_core)
unit_test(test_slave_server modbus_rtu_core)
# The share: the Modbus TCP server on real sockets, and fuzzed with malformed frames.
unit_test(test_modbus_tcp_server modbus_rtu_core)
unit_test(test_share_fuzz modbus_rtu_core)
# Issue 24: queued share requests never run after the shutdown's safe writes.
unit_test(test_share_shutdown modbus_rtu_devices)
unit_test(test_share_answer_bound modbus_rtu_devices)
# Issue 24: idle and half-closed clients, keep-alive, exception 02, broadcast turnaround.
unit_test(test_share_connections modbus_rtu_node_config)
unit_test(test_signal modbus_rtu_core)

# Devices against a scripted transport (byte exact), merged writes, read-back confirmation.
unit_test(test_devices modbus_rtu_devices)
unit_test(test_devices_confirm modbus_rtu_devices)
unit_test(test_output_batch modbus_rtu_devices)
# Writes touch only the channels asked for (issue 24, item 4), also against the simulator.
unit_test(test_devices_writes modbus_rtu_devices)
unit_test(test_devices_writes_vs_simulator "modbus_rtu_sim;modbus_rtu_devices")
unit_test(test_generic_device modbus_rtu_devices)

# Configuration rules, fail-safe policy.
unit_test(test_bus_config modbus_rtu_node_config)
unit_test(test_failsafe modbus_rtu_node_config)
unit_test(test_channel_intents modbus_rtu_failsafe)
unit_test(test_device_commands modbus_rtu_failsafe)
unit_test(test_generic_failsafe modbus_rtu_failsafe)
unit_test(test_kept_timed_commands modbus_rtu_failsafe)
# The fail-safe's deterministic simulation (docs/simulation.md): regression cases, determinism,
# a bounded run (the 60 s run is scripts/test.sh's, hours: scripts/simulate.sh).
unit_test(test_failsafe_simulation modbus_rtu_simulation)
# The link's late-reply guard on the real Link over the in-memory line (manual clock).
unit_test(test_late_reply_guard modbus_rtu_simulation)
# Writes that failed after part of them was done, on the node's bus runtime in memory.
unit_test(test_failsafe_partial_writes modbus_rtu_simulation)
unit_test(test_failsafe_node_cases modbus_rtu_simulation)
unit_test(test_generic_config modbus_rtu_node_config)
unit_test(test_generic_failsafe_config modbus_rtu_node_config)
unit_test(test_config_messages modbus_rtu_node_config)

# Simulator: the devices alone (requests in, replies out, time given to them), the line over a
# real pty, the control interface, power cycle and state file, injected faults, the executable.
unit_test(test_link_vs_simulator "modbus_rtu_sim;modbus_rtu_devices")
unit_test(test_sim_gateway modbus_rtu_sim)
unit_test(test_sim_golden modbus_rtu_sim)
unit_test(test_sim_ld58a08 modbus_rtu_sim)
unit_test(test_sim_lc_relay8 modbus_rtu_sim)
unit_test(test_sim_yespeed_pdu modbus_rtu_sim)
unit_test(test_sim_generic modbus_rtu_sim)
unit_test(test_sim_line modbus_rtu_sim)
unit_test(test_sim_state modbus_rtu_sim)
unit_test(test_sim_power_cycle modbus_rtu_sim)
unit_test(test_sim_faults modbus_rtu_sim)
unit_test(test_sim_executable modbus_rtu_sim)
target_compile_definitions(test_sim_executable PRIVATE
  SIMULATOR_EXE="$<TARGET_FILE:modbus_rtu_simulator>")
add_dependencies(test_sim_executable modbus_rtu_simulator)

# Commissioning tool: the command line, and the commands against a scripted transport with the
# manuals' frames.
unit_test(test_commission_args modbus_rtu_commission_lib)
# Issue 32 item 16: the scan through a Modbus TCP gateway (the share): its 0B is no device, and
# each address waits for its own answer.
unit_test(test_commission_share_scan modbus_rtu_commission_lib)
# The commands, one executable of two files (the device commands; the register table).
modbus_rtu_gtest(test_commission_commands ${MODBUS_RTU_UNIT_DIR}/test_commission_device.cpp
  ${MODBUS_RTU_UNIT_DIR}/test_commission_table.cpp)
set_property(GLOBAL APPEND PROPERTY MODBUS_RTU_LISTED_TESTS
  ${MODBUS_RTU_UNIT_DIR}/test_commission_device.cpp ${MODBUS_RTU_UNIT_DIR}/test_commission_table.cpp)
target_link_libraries(test_commission_commands modbus_rtu_commission_lib)
target_compile_definitions(test_commission_commands PRIVATE
  GOLDEN_FRAMES_PATH="${MODBUS_RTU_GOLDEN_FRAMES}")
# The command-line tests again with the command line built against the vendored CLI11 2.4
# (Debian 13's series, stricter about clashing names than Debian 12's 2.1), whatever CLI11 the
# system has. Every source of the command line that includes CLI11 is compiled here, none taken
# from the library (built against the system's CLI11): one CLI11 per program.
modbus_rtu_gtest(test_commission_args_cli11_2_4 ${MODBUS_RTU_UNIT_DIR}/test_commission_args.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_args.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_cli.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_parse.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_settings.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_validators.cpp
  ${MODBUS_RTU_DIR}/src/tools/commission_values.cpp)
target_include_directories(test_commission_args_cli11_2_4 BEFORE PRIVATE
  ${MODBUS_RTU_DIR}/third_party/cli11/include)
target_link_libraries(test_commission_args_cli11_2_4 modbus_rtu_commission_lib)

# The ROS layer's writer of ~running_timed against masters that fail (roscpp, no rosmaster),
# where the build has the ROS layer (the sanitizer build only with MSG_INCLUDE).
if(TARGET modbus_rtu_ros)
  unit_test(test_running_timed_parameter modbus_rtu_ros)
else()
  set_property(GLOBAL APPEND PROPERTY MODBUS_RTU_LISTED_TESTS
    ${MODBUS_RTU_UNIT_DIR}/test_running_timed_parameter.cpp)
endif()

# A test file in test/unit that no line above lists would run in no build: stop the configure.
file(GLOB unlisted CONFIGURE_DEPENDS ${MODBUS_RTU_UNIT_DIR}/test_*.cpp)
get_property(listed GLOBAL PROPERTY MODBUS_RTU_LISTED_TESTS)
list(REMOVE_ITEM unlisted ${listed})
if(unlisted)
  message(FATAL_ERROR "cmake/unit_tests.cmake lists no test of ${unlisted}: add a unit_test line")
endif()
