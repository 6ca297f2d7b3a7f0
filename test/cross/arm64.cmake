# Cross toolchain for arm64 (scripts/cross_check.sh arm64): Debian's crossbuild-essential-arm64.
set(MODBUS_RTU_TRIPLET aarch64-linux-gnu)
set(MODBUS_RTU_QEMU aarch64)
include(${CMAKE_CURRENT_LIST_DIR}/toolchain.cmake)
