// The four Modbus tables have one name each, wherever users write one; the spellings earlier
// versions took are refused with that name.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "modbus_rtu_driver/core/config/config_yaml.h"
#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {
namespace {

TEST(TableNames, EachNameParsesToItsTable) {
  for (const auto& row : kTableNames) {
    std::string error;
    const auto table = parseTableName(row.name, &error);
    ASSERT_TRUE(table) << row.name << ": " << error;
    EXPECT_EQ(*table, row.value);
    EXPECT_EQ(tableName(*table), row.name);
  }
  EXPECT_TRUE(isBitTable(Table::kCoil));
  EXPECT_TRUE(isBitTable(Table::kDiscreteInput));
  EXPECT_FALSE(isBitTable(Table::kHoldingRegister));
  EXPECT_FALSE(isBitTable(Table::kInputRegister));
}

TEST(TableNames, FormerSpellingsAreRefusedWithTheName) {
  const std::pair<const char*, const char*> former[] = {{"coils", "coil"},
                                                        {"discrete_inputs", "discrete_input"},
                                                        {"discrete-inputs", "discrete_input"},
                                                        {"holding", "holding_register"},
                                                        {"holding_registers", "holding_register"},
                                                        {"input-registers", "input_register"},
                                                        {"ireg", "input_register"}};
  for (const auto& [old, now] : former) {
    std::string error;
    EXPECT_FALSE(parseTableName(old, &error)) << old;
    EXPECT_EQ(error, std::string("'") + old +
                         "' is not one of coil, discrete_input, holding_register, input_register"
                         " (the table is now named '" +
                         now + "')");
  }
  std::string error;
  EXPECT_FALSE(parseTableName("input", &error)) << "it meant two tables: no guess";
  EXPECT_EQ(error, "'input' is not one of coil, discrete_input, holding_register, input_register");
}

TEST(TableNames, ReadRequestOfEachTable) {
  EXPECT_EQ(Request::read(1, Table::kCoil, 2, 3).function, FunctionCode::kReadCoils);
  EXPECT_EQ(Request::read(1, Table::kDiscreteInput, 2, 3).function,
            FunctionCode::kReadDiscreteInputs);
  EXPECT_EQ(Request::read(1, Table::kHoldingRegister, 2, 3).function,
            FunctionCode::kReadHoldingRegisters);
  const Request r = Request::read(1, Table::kInputRegister, 2, 3);
  EXPECT_EQ(r.function, FunctionCode::kReadInputRegisters);
  EXPECT_EQ(r.slave, 1);
  EXPECT_EQ(r.address, 2);
  EXPECT_EQ(r.count, 3);
}

TEST(TableNames, YamlTableKeyNamesTheKeyAndTheName) {
  EXPECT_EQ(config::getTable(YAML::Load("holding_register"), "signals[0]/table"),
            Table::kHoldingRegister);
  try {
    config::getTable(YAML::Load("holding"), "signals[0]/table");
    FAIL() << "'holding' was taken";
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(e.message,
              "signals[0]/table: 'holding' is not one of coil, discrete_input, "
              "holding_register, input_register (the table is now named 'holding_register')");
  }
}

}  // namespace
}  // namespace modbus_rtu_driver

// One definition of each function's table and limit (the client's checks, the slave role and
// the simulator all use it): the Modbus spec's figures.
TEST(FunctionCodes, TheTableAndTheLimitOfEachFunction) {
  EXPECT_EQ(modbus_rtu_driver::tableOf(modbus_rtu_driver::FunctionCode::kReadCoils),
            modbus_rtu_driver::Table::kCoil);
  EXPECT_EQ(modbus_rtu_driver::tableOf(modbus_rtu_driver::FunctionCode::kReadDiscreteInputs),
            modbus_rtu_driver::Table::kDiscreteInput);
  EXPECT_EQ(modbus_rtu_driver::tableOf(modbus_rtu_driver::FunctionCode::kReadHoldingRegisters),
            modbus_rtu_driver::Table::kHoldingRegister);
  EXPECT_EQ(modbus_rtu_driver::tableOf(modbus_rtu_driver::FunctionCode::kReadInputRegisters),
            modbus_rtu_driver::Table::kInputRegister);
  EXPECT_EQ(modbus_rtu_driver::tableOf(modbus_rtu_driver::FunctionCode::kWriteSingleCoil),
            modbus_rtu_driver::Table::kCoil);
  EXPECT_EQ(modbus_rtu_driver::tableOf(modbus_rtu_driver::FunctionCode::kWriteMultipleCoils),
            modbus_rtu_driver::Table::kCoil);
  EXPECT_EQ(modbus_rtu_driver::tableOf(modbus_rtu_driver::FunctionCode::kWriteSingleRegister),
            modbus_rtu_driver::Table::kHoldingRegister);
  EXPECT_EQ(modbus_rtu_driver::tableOf(modbus_rtu_driver::FunctionCode::kWriteMultipleRegisters),
            modbus_rtu_driver::Table::kHoldingRegister);
  EXPECT_EQ(modbus_rtu_driver::maxCount(modbus_rtu_driver::FunctionCode::kReadCoils), 2000);
  EXPECT_EQ(modbus_rtu_driver::maxCount(modbus_rtu_driver::FunctionCode::kReadDiscreteInputs),
            2000);
  EXPECT_EQ(modbus_rtu_driver::maxCount(modbus_rtu_driver::FunctionCode::kReadHoldingRegisters),
            125);
  EXPECT_EQ(modbus_rtu_driver::maxCount(modbus_rtu_driver::FunctionCode::kReadInputRegisters), 125);
  EXPECT_EQ(modbus_rtu_driver::maxCount(modbus_rtu_driver::FunctionCode::kWriteSingleCoil), 1);
  EXPECT_EQ(modbus_rtu_driver::maxCount(modbus_rtu_driver::FunctionCode::kWriteSingleRegister), 1);
  EXPECT_EQ(modbus_rtu_driver::maxCount(modbus_rtu_driver::FunctionCode::kWriteMultipleCoils),
            1968);
  EXPECT_EQ(modbus_rtu_driver::maxCount(modbus_rtu_driver::FunctionCode::kWriteMultipleRegisters),
            123);
}
