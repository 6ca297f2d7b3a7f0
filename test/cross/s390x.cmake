# Cross toolchain for s390x (scripts/cross_check.sh s390x): Debian's crossbuild-essential-s390x.
set(MODBUS_RTU_TRIPLET s390x-linux-gnu)
set(MODBUS_RTU_QEMU s390x)
include(${CMAKE_CURRENT_LIST_DIR}/toolchain.cmake)
