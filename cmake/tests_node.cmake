# Tests of the node: configuration parsing (gtest) and rostests against the simulator.
catkin_add_gtest(test_bus_config test/unit/test_bus_config.cpp)
target_link_libraries(test_bus_config modbus_rtu_core gtest_main)

find_package(rostest REQUIRED)
find_package(roslaunch REQUIRED)
add_rostest(test/rostest/node_devices.test)
add_rostest(test/rostest/bad_config.test)
add_rostest(test/rostest/bag.test)
roslaunch_add_file_check(launch/bus.launch)
roslaunch_add_file_check(launch/demo.launch)
add_rostest(test/rostest/slave_dm500.test)
catkin_add_gtest(test_slave_server test/unit/test_slave_server.cpp)
target_link_libraries(test_slave_server modbus_rtu_core gtest_main)
