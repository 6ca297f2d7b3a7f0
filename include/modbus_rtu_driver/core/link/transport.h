// The one thing device code talks to: run a Modbus transaction, get the outcome.
// Implemented by the links (core/link/link.h: serial RtuLink, ModbusTcpLink, RtuOverTcpLink) and by
// the unit tests' ScriptedTransport.
// Only the bus thread (BusScheduler) calls these.
#pragma once

#include <string>

#include "modbus_rtu_driver/core/modbus/types.h"

namespace modbus_rtu_driver {

class Transport {
 public:
  virtual ~Transport() = default;
  // Runs one request (with the link's retries). Broadcasts return success once sent.
  virtual Result execute(const Request& request) = 0;
  // Attempts `first`, `first` + 1, ... of `request` (0: a new transaction; more: the retries of
  // one whose answer was lost), at most `most` of them (< 0: as many as the retries allow). When
  // the answer was lost in all of them and the retries allow more, the result says
  // `retry_owed`: the caller asks again later with `first` moved on. A transport without
  // retries runs the request once.
  virtual Result executeAttempts(const Request& request, int first, int most) {
    (void)first;
    (void)most;
    return execute(request);
  }
  // (Re)opens the port. False with a message when it cannot.
  virtual bool connect(std::string* error) {
    (void)error;
    return true;
  }
  virtual bool connected() const { return true; }
  virtual void disconnect() {}
  // Waits until the line may carry the next frame (the silence after the last one), so the
  // scheduler can pick what goes next as late as possible.
  virtual void awaitLineFree() {}
  // The late-reply guard (docs/failsafe.md F90): how long `next` would still wait for a quiet
  // line before it goes (0: it would go now).
  virtual double guardLeft(const Request& next) const {
    (void)next;
    return 0;
  }
  // The longest `request` can keep the line, every retry included but not the guard that may
  // follow it (that guard holds only that slave's next request); < 0: unknown.
  virtual double lineSeconds(const Request& request) const {
    (void)request;
    return -1;
  }
  // The longest one attempt of `request` can keep the line; < 0: unknown. A transport without
  // retries: the whole request.
  virtual double attemptSeconds(const Request& request) const { return lineSeconds(request); }
};

}  // namespace modbus_rtu_driver
