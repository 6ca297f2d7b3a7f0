# Benchmark (not a test: it prints tables; run scripts/benchmark.sh).
add_executable(modbus_rtu_benchmark bench/benchmark.cpp)
target_link_libraries(modbus_rtu_benchmark modbus_rtu_sim)
