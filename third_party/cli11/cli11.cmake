# CLI11: the system's when it has one (Debian 12+, Ubuntu 22.04+: libcli11-dev, installed by
# scripts/debian_packages.txt; no rosdep key in package.xml, since rosdep's cli11 is "not
# available" on focal and `rosdep install` stops there, issue 33).
# Debian 11 and Ubuntu 20.04 (Noetic's) have no CLI11 package and rosdep's cli11 key resolves to
# nothing there, so the released single header CLI11 2.4.2 (BSD-3-Clause, licence beside it) is
# kept here and used only then: header-only, no build step, the series Debian 13 ships.
# Included by the top-level CMakeLists.txt and test/sanitizers/CMakeLists.txt; defines the
# target CLI11::CLI11 and MODBUS_RTU_VENDORED_CLI11_DIR.
set(MODBUS_RTU_VENDORED_CLI11_DIR ${CMAKE_CURRENT_LIST_DIR}/include)
find_package(CLI11 QUIET)
if(NOT CLI11_FOUND)
  message(STATUS "CLI11: no system package; using the vendored single header in third_party/cli11")
  add_library(CLI11::CLI11 INTERFACE IMPORTED)
  set_target_properties(CLI11::CLI11 PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES ${MODBUS_RTU_VENDORED_CLI11_DIR})
endif()
