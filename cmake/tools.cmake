# Commissioning tool (ROS-free, links modbus_rtu_core only): a library the unit tests use and a
# small main. catkin puts the executable in the package's lib dir, so rosrun finds it.
add_library(modbus_rtu_commission_lib
  src/tools/commission_args.cpp
  src/tools/commission_device.cpp
  src/tools/commission_output.cpp
  src/tools/commission_scan.cpp
  src/tools/commission_session.cpp
  src/tools/commission_table.cpp
  src/tools/commission_usage.cpp
)
target_link_libraries(modbus_rtu_commission_lib PUBLIC modbus_rtu_core nlohmann_json::nlohmann_json
  PRIVATE CLI11::CLI11)
add_executable(modbus_rtu_commission src/tools/commission_main.cpp)
target_link_libraries(modbus_rtu_commission modbus_rtu_commission_lib)
