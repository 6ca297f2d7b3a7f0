# Commissioning tool (ROS-free): a library (tested in-process) and a small main.
add_library(modbus_rtu_commission_lib
  src/tools/commission_args.cpp
  src/tools/commission_run.cpp
)
target_link_libraries(modbus_rtu_commission_lib PUBLIC modbus_rtu_core)
add_executable(modbus_rtu_commission src/tools/commission_main.cpp)
target_link_libraries(modbus_rtu_commission modbus_rtu_commission_lib)
