// libFuzzer target: arbitrary bytes through the request framer, the request decoder, every
// simulated device, and the reply decoder. Invariants: nothing crashes (ASan/UBSan watch), and
// every reply a device builds has a valid CRC and decodes as a reply or an exception.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <optional>
#include <vector>

#include "modbus_rtu_driver/core/modbus/frame.h"
#include "modbus_rtu_driver/core/modbus/request_framer.h"
#include "modbus_rtu_driver/sim/simulator.h"

using namespace modbus_rtu_driver;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

void serve(const Bytes& frame) {
  const auto request = decodeRequest(frame);
  if (!request) return;
  // A well-formed request encodes back to its own frame, except that the unused bits of an
  // FC15's last byte (the spec asks for zeros; real devices and libmodbus ignore them) are not
  // kept: there, decoding the re-encoded frame gives the same request.
  if (request->validate().empty()) {
    const Bytes again = encodeRequest(*request);
    if (request->function == FunctionCode::kWriteMultipleCoils) {
      const auto reread = decodeRequest(again);
      check(again.size() == frame.size() && reread && reread->values == request->values &&
            reread->address == request->address && reread->slave == request->slave);
    } else {
      check(again == frame);
    }
  }
  // Every simulated type the simulator registered (sim/simulator.h), a generic one without
  // signals included: a new type is fuzzed without an edit here.
  const uint8_t address = request->slave ? request->slave : 1;
  std::vector<std::unique_ptr<SimDevice>> devices;
  for (const DeviceDescriptor* type : simDeviceClasses().types())
    devices.push_back(makeSimDevice({type->name, address}, SimLineSettings{}));
  for (auto& device : devices) {
    std::optional<Bytes> reply;
    if (request->slave == kBroadcastAddress)
      reply = device->handleBroadcast(*request, SimClock::now());
    else if (device->answersTo(request->slave, &*request))
      reply = device->handle(*request, SimClock::now());
    if (!reply) continue;
    check(hasValidCrc(*reply));
    // An answered broadcast is the LC board's address command, which the driver asks as
    // LcRelay8::readAddressAtZero / setAddressAtZero do: of the one device at 0, its FC16 reply
    // echoing the whole request.
    Request asked = *request;
    if (request->slave == kBroadcastAddress) {
      asked.single_device_at_zero = true;
      asked.reply_echoes_request = request->function == FunctionCode::kWriteMultipleRegisters;
    }
    // A request the driver would refuse is never sent, so it has no reply to decode.
    const std::optional<EncodedRequest> sent = EncodedRequest::encode(asked);
    if (!sent) continue;
    const Result r = decodeReply(*sent, *reply);
    check(r.ok() || r.error == ErrorKind::kException);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  RequestFramer framer;
  framer.push(data, size / 2);
  for (const Bytes& f : framer.take(false)) serve(f);
  framer.push(data + size / 2, size - size / 2);
  for (const Bytes& f : framer.take(true)) serve(f);
  check(!framer.pending());
  // The same bytes as replies to typical requests.
  const Bytes bytes(data, data + size);
  for (const Request& r :
       {Request::readCoils(1, 0, 8), Request::readHoldingRegisters(255, 0, 3),
        Request::writeSingleCoil(1, 3, true), Request::writeMultipleRegisters(1, 0, {1, 2, 3})}) {
    const size_t need = replyLengthFromHeader(r, bytes);
    check(need <= 5 + 255);
    decodeReply(EncodedRequest::encode(r).value(), bytes);
  }
  return 0;
}
