# ROS adapters and the node executables.
add_library(modbus_rtu_ros
  src/ros/adapter_registry.cpp
  src/ros/bus_node.cpp
  src/ros/device_adapter.cpp
  src/ros/device_failsafe.cpp
  src/ros/digital_states_publisher.cpp
  src/ros/lc_relay8_adapter.cpp
  src/ros/ld58a08_adapter.cpp
  src/ros/raw_writes.cpp
  src/ros/slave_node.cpp
  src/ros/yaml_params.cpp
  src/ros/yespeed_pdu_adapter.cpp
)
target_link_libraries(modbus_rtu_ros PUBLIC modbus_rtu_core ${catkin_LIBRARIES})
add_dependencies(modbus_rtu_ros ${PROJECT_NAME}_generate_messages_cpp)

add_executable(modbus_rtu_bus src/ros/bus_node_main.cpp)
target_link_libraries(modbus_rtu_bus modbus_rtu_ros)
