# What every cross toolchain file of test/cross/ shares; the includer (ARCH.cmake) sets
# MODBUS_RTU_TRIPLET (Debian's GNU triplet) and MODBUS_RTU_QEMU (qemu-user's name for the CPU).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_C_COMPILER ${MODBUS_RTU_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${MODBUS_RTU_TRIPLET}-g++)
set(CMAKE_LIBRARY_ARCHITECTURE ${MODBUS_RTU_TRIPLET})
# qemu-user, invoked explicitly (no binfmt_misc registration assumed): -L makes the target's
# dynamic loader that of Debian's cross packages (/usr/TRIPLET/lib/ld-*.so). The C library must
# be the same build as the loader, and once a multiarch package pulled in libc6:ARCH
# (/lib/TRIPLET, another version) the host's /etc/ld.so.cache, which the emulated loader reads,
# names that one: a loader of 2.36-8cross1 with a libc of 2.36-9+deb12u14 hangs in the first
# pthread_create. LD_LIBRARY_PATH (searched before the cache) keeps the cross runtime together;
# the multiarch libraries (libmodbus, /usr/lib/TRIPLET) are still found at their own paths.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-${MODBUS_RTU_QEMU} -L /usr/${MODBUS_RTU_TRIPLET}
  -E LD_LIBRARY_PATH=/usr/${MODBUS_RTU_TRIPLET}/lib)
# pkg-config (libmodbus) must read the target's .pc files, not the host's.
set(ENV{PKG_CONFIG_LIBDIR} "/usr/lib/${MODBUS_RTU_TRIPLET}/pkgconfig:/usr/share/pkgconfig")
