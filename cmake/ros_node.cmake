# The ROS layer, defined once: the adapters (one small class per device type) and the node,
# whose main is a few lines, on modbus_rtu_runtime (cmake/layers.cmake). Each build brings
# its own ROS and sets, before including this file:
#   MODBUS_RTU_ROS_INCLUDE_DIRS  ROS's headers and the generated message headers, if the
#                                build's include_directories() do not give them already
#   MODBUS_RTU_ROS_LIBRARIES     ROS's libraries
# The catkin build (CMakeLists.txt): catkin's (its headers through include_directories()). The
# sanitizer build (test/sanitizers/, with MSG_INCLUDE): the ROS libraries as Debian built them,
# through pkg-config, and the catkin workspace's generated message headers, for node_devices.test
# under the sanitizers.
layer_sources(MODBUS_RTU_ROS_SOURCES ros)
add_library(modbus_rtu_ros ${MODBUS_RTU_LIBRARY_TYPE} ${MODBUS_RTU_ROS_SOURCES})
if(MODBUS_RTU_ROS_INCLUDE_DIRS)
  target_include_directories(modbus_rtu_ros PUBLIC ${MODBUS_RTU_ROS_INCLUDE_DIRS})
endif()
target_link_libraries(modbus_rtu_ros PUBLIC modbus_rtu_runtime ${MODBUS_RTU_ROS_LIBRARIES})
add_executable(modbus_rtu_bus ${MODBUS_RTU_DIR}/src/ros/bus_node_main.cpp)
target_link_libraries(modbus_rtu_bus modbus_rtu_ros)
