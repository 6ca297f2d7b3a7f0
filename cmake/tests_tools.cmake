# Commissioning tool: the command line (gtest), the commands against a scripted transport with
# the manuals' frames (gtest), and the executable against the simulator (rostest).
catkin_add_gtest(test_commission_args test/unit/test_commission_args.cpp)
target_link_libraries(test_commission_args modbus_rtu_commission_lib gtest_main)
catkin_add_gtest(test_commission_commands
  test/unit/test_commission_device.cpp test/unit/test_commission_table.cpp)
target_link_libraries(test_commission_commands modbus_rtu_commission_lib gtest_main)
target_compile_definitions(test_commission_commands PRIVATE GOLDEN_FRAMES_PATH="${GOLDEN_FRAMES}")
find_package(rostest REQUIRED)
add_rostest(test/rostest/commission.test DEPENDENCIES modbus_rtu_commission modbus_rtu_simulator)
