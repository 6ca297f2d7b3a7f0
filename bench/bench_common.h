// What the parts of modbus_rtu_benchmark share (defined in benchmark.cpp): the rate loop and the
// plain libmodbus reference call every table compares against.
#pragma once

#include <modbus/modbus.h>

#include <fstream>
#include <functional>
#include <string>

#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

// Transactions per second of `once` over `seconds` (0 when one of them failed).
double transactionRate(double seconds, const std::function<bool()>& once);
// `r` through libmodbus's own API on `ctx`: true when it succeeded.
bool plainLibmodbus(modbus_t* ctx, const Request& r);

void benchmarkScale(const std::string& dir, double seconds, double warm_up_seconds,
                    std::ofstream& csv);
void benchmarkTransports(const std::string& dir, double seconds, std::ofstream& csv);

}  // namespace modbus_rtu_driver
