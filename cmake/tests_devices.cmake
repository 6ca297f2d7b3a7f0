# Tests of the devices area.
catkin_add_gtest(test_devices test/unit/test_devices.cpp)
target_link_libraries(test_devices modbus_rtu_core gtest_main)
catkin_add_gtest(test_bus_scheduler test/unit/test_bus_scheduler.cpp)
target_link_libraries(test_bus_scheduler modbus_rtu_core gtest_main)
catkin_add_gtest(test_devices_confirm test/unit/test_devices_confirm.cpp)
target_link_libraries(test_devices_confirm modbus_rtu_core gtest_main)
