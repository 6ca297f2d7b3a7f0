#include "modbus_rtu_driver/core/link/link_types.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "modbus_rtu_driver/core/modbus/text.h"

namespace modbus_rtu_driver {

namespace {

// "a, b or c"
std::string orList(const std::vector<std::string>& items) {
  if (items.size() <= 1) return items.empty() ? "" : items.front();
  const std::vector<std::string> head(items.begin(), items.end() - 1);
  return join(head) + " or " + items.back();
}

}  // namespace

LinkTypes& linkTypes() {
  static LinkTypes registry;  // built at its first use, by the first kind added
  return registry;
}

bool LinkTypes::add(const LinkType& type) {
  if (!by_scheme_.emplace(type.scheme, &type).second) {
    std::fprintf(stderr, "modbus_rtu_driver: link scheme '%s' is registered twice\n", type.scheme);
    std::abort();
  }
  return true;
}

const LinkType* LinkTypes::find(const std::string& port) const {
  const size_t end = port.find("://");
  const std::string scheme = end == std::string::npos ? "" : port.substr(0, end + 3);
  const auto it = by_scheme_.find(scheme);
  return it == by_scheme_.end() ? nullptr : it->second;
}

std::vector<const LinkType*> LinkTypes::types() const {
  std::vector<const LinkType*> out;
  out.reserve(by_scheme_.size());
  for (const auto& kv : by_scheme_) out.push_back(kv.second);
  std::stable_sort(out.begin(), out.end(), [](const LinkType* a, const LinkType* b) {
    return std::strlen(a->scheme) < std::strlen(b->scheme);
  });
  return out;
}

std::string LinkTypes::formList() const {
  std::vector<std::string> forms;
  for (const LinkType* t : types()) forms.emplace_back(t->form);
  return orList(forms);
}

std::string LinkTypes::shortFormList() const {
  std::vector<std::string> forms;
  for (const LinkType* t : types()) forms.emplace_back(t->short_form);
  return orList(forms);
}

bool parseLinkTarget(const std::string& port, LinkTarget* out, std::string* error) {
  *out = LinkTarget{};
  if (port.empty()) {
    if (error) *error = "port: must name " + linkTypes().formList();
    return false;
  }
  const LinkType* type = linkTypes().find(port);
  if (!type) {
    if (error) *error = "port: '" + port + "' is not " + linkTypes().shortFormList();
    return false;
  }
  out->type = type;
  return type->parse(port, port.substr(std::strlen(type->scheme)), out, error);
}

LinkTarget linkTargetOf(const std::string& port) {
  LinkTarget target;
  if (!parseLinkTarget(port, &target, nullptr)) target = LinkTarget{};
  return target;
}

bool parseHostPort(const std::string& port, const std::string& rest, LinkTarget* out,
                   std::string* error) {
  const size_t colon = rest.rfind(':');
  std::string host = colon == std::string::npos ? "" : rest.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);  // [::1]
  const std::string number = colon == std::string::npos ? "" : rest.substr(colon + 1);
  const bool digits = !number.empty() && number.size() <= 5 &&
                      number.find_first_not_of("0123456789") == std::string::npos;
  const int host_port = digits ? std::stoi(number) : 0;
  if (host.empty() || host.find_first_of("/[] ") != std::string::npos || host_port < 1 ||
      host_port > 65535) {
    if (error) *error = "port: '" + port + "' is not " + out->type->form + " (port 1-65535)";
    return false;
  }
  out->host = host;
  out->host_port = host_port;
  return true;
}

std::string validateLink(const LinkConfig& config, LinkTarget* target) {
  std::string error;
  if (!parseLinkTarget(config.port, target, &error)) return error;
  return validateLinkConfig(config);
}

std::string linkTypesHelp() {
  std::string out;
  for (const LinkType* t : linkTypes().types())
    out += "  " + std::string(t->form) + "\n      " + t->name + ": " + t->help + "\n";
  return out;
}

}  // namespace modbus_rtu_driver
