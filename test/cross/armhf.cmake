# Cross toolchain for armhf (scripts/cross_check.sh armhf): Debian's crossbuild-essential-armhf.
set(MODBUS_RTU_TRIPLET arm-linux-gnueabihf)
set(MODBUS_RTU_QEMU arm)
include(${CMAKE_CURRENT_LIST_DIR}/toolchain.cmake)
