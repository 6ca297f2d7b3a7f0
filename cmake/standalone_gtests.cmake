# The unit tests of cmake/unit_tests.cmake in a plain CMake build (test/sanitizers/, test/cross/):
# each a plain executable on gtest's main, built from Debian's googletest sources with this
# build's compiler and flags (so neither libgtest-dev for a foreign architecture nor a gtest built
# without the sanitizers is needed), linked on its own layer as in the catkin build. ctest lists
# them; a cross build runs them through CMAKE_CROSSCOMPILING_EMULATOR (qemu-user).
enable_testing()
add_subdirectory(/usr/src/googletest ${CMAKE_BINARY_DIR}/googletest EXCLUDE_FROM_ALL)
function(modbus_rtu_gtest name)
  add_executable(${name} ${ARGN})
  target_link_libraries(${name} gtest_main)
  add_test(NAME ${name} COMMAND ${name})
endfunction()
include(${CMAKE_CURRENT_LIST_DIR}/unit_tests.cmake)
