# Tests of the sim area.
catkin_add_gtest(test_link_vs_simulator test/unit/test_link_vs_simulator.cpp)
target_link_libraries(test_link_vs_simulator modbus_rtu_sim gtest_main)
catkin_add_gtest(test_sim_devices test/unit/test_sim_devices.cpp)
target_link_libraries(test_sim_devices modbus_rtu_sim gtest_main)
target_compile_definitions(test_sim_devices PRIVATE GOLDEN_FRAMES_PATH="${GOLDEN_FRAMES}")
