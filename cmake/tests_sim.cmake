# Tests of the sim area.
catkin_add_gtest(test_link_vs_simulator test/unit/test_link_vs_simulator.cpp)
target_link_libraries(test_link_vs_simulator modbus_rtu_sim gtest_main)
