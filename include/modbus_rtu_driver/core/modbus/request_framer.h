// Cuts the byte stream a master sends into request frames: by the length each header announces,
// and, at a silence, past noise, bad CRCs and layouts it cannot length-parse, by looking for a
// valid frame at every offset. Shared by the simulator and the slave role.
#pragma once

#include <cstdint>
#include <vector>

#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

class RequestFramer {
 public:
  void push(const uint8_t* data, size_t size) { input_.insert(input_.end(), data, data + size); }
  // Frames complete so far (CRC checked). With `silence` (the line rested t3.5), what is left
  // is resynchronised: bytes before the next valid frame are dropped.
  std::vector<Bytes> take(bool silence);
  bool pending() const { return !input_.empty(); }
  uint64_t dropped() const { return dropped_; }  // runs of bytes dropped (noise, bad CRC)

 private:
  Bytes input_;
  uint64_t dropped_ = 0;
};

}  // namespace modbus_rtu_driver
