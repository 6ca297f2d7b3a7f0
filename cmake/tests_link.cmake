# Tests of the link area.
catkin_add_gtest(test_rtu_link_golden test/unit/test_rtu_link_golden.cpp)
target_link_libraries(test_rtu_link_golden modbus_rtu_core gtest_main)
target_compile_definitions(test_rtu_link_golden PRIVATE GOLDEN_FRAMES_PATH="${GOLDEN_FRAMES}")
catkin_add_gtest(test_rtu_link_faults test/unit/test_rtu_link_faults.cpp)
target_link_libraries(test_rtu_link_faults modbus_rtu_core gtest_main)
