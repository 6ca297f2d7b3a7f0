install(TARGETS
  modbus_rtu_benchmark modbus_rtu_bus modbus_rtu_commission modbus_rtu_commission_lib modbus_rtu_core
  modbus_rtu_dm500_sim modbus_rtu_ros modbus_rtu_sim modbus_rtu_simulator
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/ DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION})
install(DIRECTORY config launch DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
catkin_install_python(PROGRAMS scripts/plot_bag.py DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
