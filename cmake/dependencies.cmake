# The ROS-free dependencies of the layer libraries, the tools and the unit tests, found once for
# every build: the catkin build (CMakeLists.txt, which finds ROS's with catkin) and the
# instrumented builds (test/sanitizers/CMakeLists.txt). What each build finds besides is its own:
# catkin's packages, or ROS through pkg-config for the sanitized node; its gtest.
# The includer sets MODBUS_RTU_DIR, the repository's root, which every cmake/ file builds its
# paths on: the catkin build ${PROJECT_SOURCE_DIR} (which catkin_lint resolves, where it reads
# ${CMAKE_CURRENT_LIST_DIR} as a relative path), the instrumented builds ../.. of theirs.
# 32-bit targets (armhf): 64-bit file offsets and inode numbers. Without, stat() and readdir()
# fail with EOVERFLOW where a value needs more than 32 bits: an inode number on XFS, btrfs or NFS
# (the simulator's stat() of its pty link and control socket), an ext4 directory offset under
# qemu-user (issue 49: scripts/cross_check.sh armhf found test_failsafe_simulation reading no case
# file). Debian builds armhf with it from Debian 13 on. Only there: 64-bit targets have it anyway
# (and keep their flags, so no rebuild).
if(CMAKE_SIZEOF_VOID_P EQUAL 4)
  add_compile_definitions(_FILE_OFFSET_BITS=64)
endif()
find_package(PkgConfig REQUIRED)
# libmodbus opens the serial port and sends (core/link).
pkg_check_modules(LIBMODBUS REQUIRED libmodbus)
# The settings' YAML (core/config, config, sim).
find_package(yaml-cpp REQUIRED)
find_package(Threads REQUIRED)
# Header-only: the command lines of the tools and simulators, the commissioning tool's JSON.
find_package(nlohmann_json REQUIRED)
# CLI11 (header-only, the tools' command lines): the system's, or where there is none (Debian 11,
# Ubuntu 20.04) the vendored single header; why and how in third_party/cli11/cli11.cmake. It may
# define an imported target: the catkin build includes this file after catkin_package(), as
# catkin_lint wants no target defined before it.
include(${MODBUS_RTU_DIR}/third_party/cli11/cli11.cmake)
