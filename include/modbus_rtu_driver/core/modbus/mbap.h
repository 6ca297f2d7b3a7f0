// Modbus TCP framing: the MBAP header (transaction id, protocol 0, length, unit id) in front of
// the same PDU an RTU frame carries. Written as a conversion to and from the RTU ADU, so every
// encoder and decoder in frame.h (requests, replies, exceptions, checks) serves TCP too: the
// client transports, the node's share and the simulator's TCP server all go through here.
#pragma once

#include <cstdint>

#include "modbus_rtu_driver/core/modbus/frame.h"

namespace modbus_rtu_driver {

constexpr size_t kMbapHeaderLength = 7;  // transaction 2, protocol 2, length 2, unit 1
constexpr size_t kMaxMbapAduLength = 260;

// The MBAP ADU carrying the RTU ADU `rtu` (slave, PDU, CRC; the CRC is dropped, not checked).
Bytes rtuToMbap(uint16_t transaction, const Bytes& rtu);
// The RTU ADU (unit as slave, PDU, a fresh CRC) carried by a complete MBAP ADU.
Bytes mbapToRtu(const Bytes& mbap);
uint16_t mbapTransaction(const Bytes& mbap);  // needs 2 bytes

// Total ADU length announced by the header read so far: 0 = need more bytes; -1 = not an MBAP
// header this side accepts (protocol id not 0, length outside 2-254), `error` says why.
int mbapLengthFromHeader(const Bytes& partial, std::string* error = nullptr);

}  // namespace modbus_rtu_driver
