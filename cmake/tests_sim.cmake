# Tests of the sim area. Each test file stands alone (the sanitizer build makes one executable
# of each test/unit/test_*.cpp).
catkin_add_gtest(test_link_vs_simulator test/unit/test_link_vs_simulator.cpp)
target_link_libraries(test_link_vs_simulator modbus_rtu_sim gtest_main)

# The devices alone: requests in, replies out, time given to them.
catkin_add_gtest(test_sim_golden test/unit/test_sim_golden.cpp)
target_link_libraries(test_sim_golden modbus_rtu_sim gtest_main)
target_compile_definitions(test_sim_golden PRIVATE GOLDEN_FRAMES_PATH="${GOLDEN_FRAMES}")
foreach(name test_sim_ld58a08 test_sim_lc_relay8 test_sim_yespeed_pdu)
  catkin_add_gtest(${name} test/unit/${name}.cpp)
  target_link_libraries(${name} modbus_rtu_sim gtest_main)
endforeach()

# The line over a real pty, the control interface, power cycle and state file.
catkin_add_gtest(test_sim_line test/unit/test_sim_line.cpp)
target_link_libraries(test_sim_line modbus_rtu_sim gtest_main)
target_compile_definitions(test_sim_line PRIVATE GOLDEN_FRAMES_PATH="${GOLDEN_FRAMES}")
catkin_add_gtest(test_sim_state test/unit/test_sim_state.cpp)
target_link_libraries(test_sim_state modbus_rtu_sim gtest_main)
target_compile_definitions(test_sim_state PRIVATE REPO_DIR="${REPO_REAL_DIR}")

# The executable and test/sim_control.py's command line.
catkin_add_gtest(test_sim_executable test/unit/test_sim_executable.cpp)
target_link_libraries(test_sim_executable modbus_rtu_sim gtest_main)
target_compile_definitions(test_sim_executable PRIVATE REPO_DIR="${REPO_REAL_DIR}"
  SIMULATOR_EXE="$<TARGET_FILE:modbus_rtu_simulator>")
add_dependencies(test_sim_executable modbus_rtu_simulator)

# Injected faults: what the wire carries and the counters.
catkin_add_gtest(test_sim_faults test/unit/test_sim_faults.cpp)
target_link_libraries(test_sim_faults modbus_rtu_sim gtest_main)
