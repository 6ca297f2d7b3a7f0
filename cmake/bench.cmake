# Benchmark (not a test: it prints tables; run scripts/benchmark.sh).
add_executable(modbus_rtu_benchmark bench/benchmark.cpp bench/bench_scale.cpp)
target_link_libraries(modbus_rtu_benchmark modbus_rtu_sim)
# The pymodbus column runs this script (--pymodbus overrides it).
target_compile_definitions(modbus_rtu_benchmark PRIVATE
  PYMODBUS_CLIENT="${CMAKE_CURRENT_SOURCE_DIR}/bench/pymodbus_client.py")
