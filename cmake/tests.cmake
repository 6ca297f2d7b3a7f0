# Unit tests (gtest) of the ROS-free core and simulator.
# Every frame the manuals print, kept in the repository as test data.
get_filename_component(REPO_REAL_DIR ${PROJECT_SOURCE_DIR} REALPATH)
set(GOLDEN_FRAMES ${REPO_REAL_DIR}/test/data/golden_frames.tsv)
catkin_add_gtest(test_frame test/unit/test_frame.cpp)
target_link_libraries(test_frame modbus_rtu_core gtest_main)
target_compile_definitions(test_frame PRIVATE
  GOLDEN_FRAMES_PATH="${GOLDEN_FRAMES}")
include(cmake/tests_link.cmake)
include(cmake/tests_devices.cmake)
include(cmake/tests_sim.cmake)
include(cmake/tests_node.cmake)
catkin_add_gtest(test_link_config test/unit/test_link_config.cpp)
target_link_libraries(test_link_config modbus_rtu_core gtest_main)
include(cmake/tests_tools.cmake)
catkin_add_gtest(test_request_framer test/unit/test_request_framer.cpp)
target_link_libraries(test_request_framer modbus_rtu_core gtest_main)
