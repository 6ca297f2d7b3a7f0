// modbus_rtu_commission --help: what CLI11's option lists do not say (each command's words,
// the boards' ranges, the scan's duration, confirmations, exit codes), after those lists.
#include "modbus_rtu_driver/tools/commission.h"

namespace modbus_rtu_driver {

std::string commissionHelpDetails() {
  return R"(
Details (COMMAND --help lists a command's options):
  scan [--from A] [--to B | --addresses 1-5,255] [--bauds 9600,19200|all]
       [--parities none,even,odd|all] [--first]
      Harmless reads at every address (default 1-255) and line setting (default --baud and
      --parity); names the type of each device that answers. Ctrl-C stops early and still
      lists what was found. A silent address costs one read: the scan timeout (0.05 s + 30
      characters at --baud: 0.081 s at the default 9600 8N1) plus the 3.5-character gap kept
      before the next request. Every baud and parity over 1-255 (--bauds all --parities all)
      is 255 x 8 x 3 = 6120 reads: 6120 x 0.081 s = 8.3 min of timeouts + 0.8 min of gaps,
      about 9 minutes (each device found adds up to 4 reads).
  info --address A                         type and settings of the device at A
  get-address --type ld58a08|lc_relay8 [--address A]
  set-address --type ld58a08|lc_relay8 [--address A] NEW
      ld58a08: 1-248, register 0x00FD at A, or through 0xFF without --address.
      lc_relay8: 1-255, always through address 0 (--address A: check it is A first).
      Through 0xFF or 0 the board must be ALONE on the bus: every board takes the command.
      An LD58A08 also answers some requests at 0xFF: move LC boards off their factory
      address 255 before they share a bus with one.
  get-baud --type T --address A
  set-baud --type T --address A BAUD       a rate or a code: ld58a08 0-7 (1200-115200),
                                           lc_relay8 2-4 (4800, 9600, 19200)
  get-parity --address A / set-parity --address A none|even|odd          (ld58a08)
  get-return-delay --address A / set-return-delay --address A MS
                                           (ld58a08, 0-1000 ms in steps of 40)
  get-save --address A / set-save --address A on|off
                                           (ld58a08, power-down save of the PWM settings)
  factory-reset --type ld58a08 [--address A]   (through 0xFF without --address)
  get-limits --address A                   (yespeed_pdu: over-voltage, under-voltage,
                                           over-current)
  set-limits --address A [--over-voltage V] [--under-voltage V] [--over-current A]
      (yespeed_pdu) Limits not given stay as the PDU holds them (it is read first). The
      manual's rules, checked on the register values that will be written (0.1 V, 0.01 A):
      over-voltage above 180.0 V and above under-voltage, under-voltage below 280.0 V,
      over-current above 5.00 A and below 20.00 A. Read back after the write.
  read --address A coils|discrete-inputs|holding|input-registers START [COUNT]
  write --address A coils|holding START VALUE... [--multiple]
                                           FC05/FC06 for one value, FC15/FC16 for more
                                           (--multiple: FC15/FC16 always)
  watch --address A TABLE START [COUNT] [--interval S] [--count N]
      Polls and prints a line only when something changed; Ctrl-C ends it.

Numbers may be decimal or 0x-hex. Changes to how a device answers (address, baud, parity,
return delay, factory reset) and the PDU's limits ask for confirmation on stdin unless --yes;
without a "y" (or at end of input) nothing is changed.
Baud and parity take effect after the device is powered off and on.
--timeout: wait for a reply, default 0.05 s + 30 characters for scans and 1 s more for other
commands (an LD58A08 may wait up to 1000 ms before answering; scan such a board with a
--timeout above its return delay).

exit codes: 0 ok, 2 bad arguments, 3 not found / no answer, 4 refused by the device (Modbus
exception), 5 other bus error (CRC, I/O, port), 6 not confirmed by the user
)";
}

}  // namespace modbus_rtu_driver
