# The ROS-free executables on the layer libraries (cmake/layers.cmake), defined once for every
# build: the catkin build puts them in devel/lib/modbus_rtu_driver (so `rosrun` finds them) and
# installs them; the sanitizer build (test/sanitizers/) makes them instrumented, for the unit
# tests that run them (test_sim_executable runs the simulator).
# The simulators (the RTU devices; the DM500 master).
add_executable(modbus_rtu_simulator ${MODBUS_RTU_DIR}/src/sim/simulator_main.cpp)
target_link_libraries(modbus_rtu_simulator modbus_rtu_sim CLI11::CLI11)
add_executable(modbus_rtu_dm500_sim ${MODBUS_RTU_DIR}/src/sim/dm500_main.cpp)
target_link_libraries(modbus_rtu_dm500_sim modbus_rtu_sim CLI11::CLI11)
# The fail-safe's deterministic simulation (docs/simulation.md; scripts/simulate.sh runs it).
add_executable(failsafe_simulation ${MODBUS_RTU_DIR}/src/simulation/failsafe_simulation_main.cpp)
target_link_libraries(failsafe_simulation modbus_rtu_simulation)
# The commissioning tool.
add_executable(modbus_rtu_commission ${MODBUS_RTU_DIR}/src/tools/commission_main.cpp)
target_link_libraries(modbus_rtu_commission modbus_rtu_commission_lib)
