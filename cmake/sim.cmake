# ROS-free simulator: device models, line emulation on a pty, executable. Never links roscpp.
add_library(modbus_rtu_sim
  src/sim/dm500_master.cpp
  src/sim/dm500_garbage.cpp
  src/sim/pty_link.cpp
  src/sim/sim_device.cpp
  src/sim/sim_lc_relay8.cpp
  src/sim/sim_ld58a08.cpp
  src/sim/sim_yespeed_pdu.cpp
  src/sim/simulator.cpp
  src/sim/simulator_config.cpp
  src/sim/simulator_control.cpp
)
target_link_libraries(modbus_rtu_sim PUBLIC modbus_rtu_core yaml-cpp Threads::Threads)

# catkin puts executables in devel/lib/modbus_rtu_driver: `rosrun modbus_rtu_driver
# modbus_rtu_simulator` finds it.
add_executable(modbus_rtu_simulator src/sim/simulator_main.cpp)
target_link_libraries(modbus_rtu_simulator modbus_rtu_sim CLI11::CLI11)

add_executable(modbus_rtu_dm500_sim src/sim/dm500_main.cpp)
target_link_libraries(modbus_rtu_dm500_sim modbus_rtu_sim CLI11::CLI11)
