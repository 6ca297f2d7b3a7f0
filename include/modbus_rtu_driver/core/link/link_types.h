// The kinds of link a `port` may name, each registered from its own source file as device types
// are (core/config/type_registry.h): the serial link (a device path, no scheme: rtu_link.cpp),
// Modbus TCP (tcp://: modbus_tcp_link.cpp), RTU over TCP (rtu+tcp://: rtu_over_tcp_link.cpp).
// A new kind is its own files alone:
//   const bool kRegistered = linkTypes().add(kMyLinkType);
// and the node's configuration, the commissioning tool (its checks and its help) and makeLink
// take it (docs/transports.md). The port string is parsed once, by parseLinkTarget, into the
// LinkTarget that the link and its users keep.
// The registry sits with the links (core/link), not with the settings (core/config): its
// entries make links, and the library that holds the registrations is then the one every
// user of a port calls into, so it is always loaded (the layer libraries are shared objects).
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "modbus_rtu_driver/core/config/link_config.h"

namespace modbus_rtu_driver {

class Link;
struct LinkType;

// A port string, parsed.
struct LinkTarget {
  const LinkType* type = nullptr;  // set by parseLinkTarget
  std::string path;                // the form without a scheme: the device
  std::string host;                // network forms: the host, an IPv6 address without brackets
  int host_port = 0;               // network forms: 1-65535
};

struct LinkType {
  const char* scheme;  // "tcp://"; "" for the one form without a scheme (a device path)
  const char* name;    // "Modbus TCP": the node's log line and diagnostics
  // How messages and the tool's help show the form: "tcp://HOST:PORT"; and how a message listing
  // the schemes names it: "tcp://".
  const char* form;
  const char* short_form;
  const char* help;  // one line: what the link carries and to what (the tool's help)
  // What the users of a link ask of its kind (not which kind it is):
  bool networked;  // network_allowance applies (diagnostics show it instead of low latency)
  // The far end answers for a silent address itself (a Modbus TCP gateway's exception 0B), and
  // keeps working on a request given up: a scan waits for its answers (kGatewayScanTimeout).
  bool answers_for_silence;
  // `rest` (the port after the scheme) into `out` (its type already set); false with a message
  // that names the port and the form, "port: '...' is not ...".
  bool (*parse)(const std::string& port, const std::string& rest, LinkTarget* out,
                std::string* error);
  // The link; `config` is valid (validateLink) and `target` its port, parsed.
  std::unique_ptr<Link> (*make)(const LinkConfig& config, const LinkTarget& target);
};

class LinkTypes {
 public:
  // Runs during static initialisation, before main: a scheme added twice is a programming error
  // (two files claiming one form), reported and fatal there.
  bool add(const LinkType& type);
  // The kind `port` names by its scheme (none: the scheme-less kind); null when unknown.
  const LinkType* find(const std::string& port) const;
  // Shortest scheme first (the device path, then tcp://, ...): the order messages list them in.
  std::vector<const LinkType*> types() const;
  // "a serial device such as /dev/ttyUSB0, tcp://HOST:PORT or rtu+tcp://HOST:PORT"
  std::string formList() const;
  // "a device path, tcp:// or rtu+tcp://"
  std::string shortFormList() const;

 private:
  std::map<std::string, const LinkType*> by_scheme_;
};
LinkTypes& linkTypes();

// False with a message naming the port and what it may be when it does not parse.
bool parseLinkTarget(const std::string& port, LinkTarget* out, std::string* error);
// The target of a port known to parse (a link built from its config alone); an empty target
// (no type) otherwise.
LinkTarget linkTargetOf(const std::string& port);
// The network forms' `rest`: HOST:PORT ([v6]:PORT), the port 1-65535.
bool parseHostPort(const std::string& port, const std::string& rest, LinkTarget* out,
                   std::string* error);
// Empty when valid, else one message naming the field: the port first (its target into
// `target`), then the line settings (validateLinkConfig).
std::string validateLink(const LinkConfig& config, LinkTarget* target);
// The tool's help: one line per kind, its form and what it carries.
std::string linkTypesHelp();

}  // namespace modbus_rtu_driver
