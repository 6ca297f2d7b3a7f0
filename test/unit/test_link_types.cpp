// Issue 34 item 3: a kind of link registers itself from its own file, and every user of a port
// takes it with no shared edit. This file registers a fake one ("fake://NAME", a link that no
// device answers) as a new transport's file would, and shows that the node's configuration,
// the factory, the commissioning tool's checks and its help all know it.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <memory>
#include <string>

#include "modbus_rtu_driver/core/link/link.h"
#include "modbus_rtu_driver/core/link/link_types.h"
#include "modbus_rtu_driver/core/link/make_link.h"
#include "modbus_rtu_driver/node_config/bus_config.h"
#include "modbus_rtu_driver/tools/commission.h"

using namespace modbus_rtu_driver;

namespace {

// The medium: nothing answers, a broadcast is sent.
class FakeLink : public Link {
 public:
  using Link::Link;

 protected:
  Result attempt(const EncodedRequest& request) override {
    return Result::failure(ErrorKind::kTimeout, request.request().describe() + ": no answer");
  }
  Result sendBroadcast(const EncodedRequest& /*request*/) override { return Result::success(); }
};

bool parseFake(const std::string& port, const std::string& rest, LinkTarget* out,
               std::string* error) {
  if (rest.empty()) {
    if (error) *error = "port: '" + port + "' is not fake://NAME (a bench's name)";
    return false;
  }
  out->host = rest;
  return true;
}

std::unique_ptr<Link> makeFake(const LinkConfig& config, const LinkTarget& target) {
  return std::make_unique<FakeLink>(config, target);
}

const LinkType kFakeLink{"fake://",
                         "fake bench",
                         "fake://NAME",
                         "fake://",
                         "a bench that never answers (the test's own kind)",
                         /*networked=*/true,
                         /*answers_for_silence=*/false,
                         parseFake,
                         makeFake};
const bool kRegistered = linkTypes().add(kFakeLink);

const char* kBus = R"(
port: fake://bench-7
devices:
  relays: {type: lc_relay8, address: 1}
)";

}  // namespace

TEST(LinkTypes, TheNodesConfigurationTakesARegisteredKind) {
  ASSERT_TRUE(kRegistered);
  BusConfig config;
  std::string error;
  ASSERT_TRUE(parseBusConfig(YAML::Load(kBus), &config, &error)) << error;
  EXPECT_EQ(config.link_target.type, &kFakeLink);
  EXPECT_EQ(config.link_target.host, "bench-7");
  // Its own parser's message, naming the field.
  EXPECT_FALSE(parseBusConfig(YAML::Load("{port: 'fake://', devices: {r: {type: lc_relay8, "
                                         "address: 1}}}"),
                              &config, &error));
  EXPECT_EQ(error, "port: 'fake://' is not fake://NAME (a bench's name)");
  // An unknown scheme's message lists it with the others, generated from the registry.
  EXPECT_FALSE(parseBusConfig(YAML::Load("{port: 'mqtt://h:1', devices: {r: {type: lc_relay8, "
                                         "address: 1}}}"),
                              &config, &error));
  EXPECT_EQ(error, "port: 'mqtt://h:1' is not " + linkTypes().shortFormList());
  EXPECT_EQ(error.rfind("port: 'mqtt://h:1' is not a device path, tcp://, ", 0), 0u) << error;
  EXPECT_NE(error.find("fake://"), std::string::npos) << error;
  LinkTarget target;
  EXPECT_FALSE(parseLinkTarget("", &target, &error));
  EXPECT_EQ(error, "port: must name " + linkTypes().formList());
  EXPECT_NE(error.find(", fake://NAME"), std::string::npos) << error;
}

TEST(LinkTypes, TheFactoryMakesItsLinkWithTheParsedTarget) {
  BusConfig config;
  std::string error;
  ASSERT_TRUE(parseBusConfig(YAML::Load(kBus), &config, &error)) << error;
  const std::unique_ptr<Link> link = makeLink(config.link, config.link_target);
  ASSERT_NE(dynamic_cast<FakeLink*>(link.get()), nullptr);
  EXPECT_EQ(link->target().type, &kFakeLink);
  EXPECT_EQ(link->target().host, "bench-7");
  // The link works as any other: its attempts go through the shared retry rule.
  ASSERT_TRUE(link->connect(&error));
  const Result r = link->execute(Request::readHoldingRegisters(1, 0, 1));
  EXPECT_EQ(r.error, ErrorKind::kTimeout);
  EXPECT_EQ(link->stats().attempts, 2u) << "retries: 1 by default";
}

TEST(LinkTypes, TheCommissioningToolChecksAndListsIt) {
  CommissionCommand c;
  std::string error;
  ASSERT_TRUE(parseCommission({"--port", "fake://bench-7", "scan"}, &c, &error)) << error;
  EXPECT_EQ(c.target.type, &kFakeLink);
  EXPECT_FALSE(parseCommission({"--port", "fake://", "scan"}, &c, &error));
  EXPECT_EQ(error, "--port: 'fake://' is not fake://NAME (a bench's name)");
  ASSERT_TRUE(parseCommission({"--help"}, &c, &error)) << error;
  EXPECT_NE(c.help.find("--port PORT"), std::string::npos) << c.help;
  EXPECT_NE(c.help.find(linkTypes().formList() + " (needed"), std::string::npos) << c.help;
  EXPECT_NE(linkTypes().formList().find("fake://NAME"), std::string::npos);
  EXPECT_NE(c.help.find("  fake://NAME\n      fake bench: a bench that never answers (the "
                        "test's own kind)\n"),
            std::string::npos)
      << c.help;
  EXPECT_NE(linkTypesHelp().find("fake://NAME"), std::string::npos);
}
