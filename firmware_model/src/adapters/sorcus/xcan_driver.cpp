// The X-CAN-2i MDD's driver side: how it starts each 82527 (8 MHz system clock, bit timing),
// switches the bus on, reports the bus state, and hands send requests to the buffer manager
// (buffer_manager.hpp). The interrupt's consequences are in xcan_interrupt.cpp.
#include "canemu/firmware_model/adapters/sorcus/bit_params.hpp"
#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"

namespace canemu::model::sorcus {

using namespace i82527;

void XcanModule::init_chip(unsigned i) {
  // The 16 MHz crystal halved (DSC) to the 8 MHz / 125 ns system clock.
  ifaces_[i].mgr->init_chip(true);
  program_timing(i);
}

void XcanModule::program_timing(unsigned i) {
  const XCAN_BITPARAMS& p = ifaces_[i].params;
  // Checked when written (write_bitparams); the default is the factory's 20 kbit/s.
  const auto timing = decode_sorcus(kXCan2i, SorcusTiming{p.Tq, p.Tseg1, p.Tseg2, p.Tsjw, p.SpB});
  if (timing) {
    ifaces_[i].mgr->program_timing(*timing);
  }
}

void XcanModule::bus_on(unsigned i) {
  Interface& f = ifaces_[i];
  // «Nach dem Öffnen des ersten Kanals zu einem Sende- oder Empfangsobjekt ist der Bus
  // standardmäßig eingeschaltet.» Decision: unless the bus-control device switched it already.
  if (!f.controlled) {
    f.mgr->set_bus_on(true);
  }
}

ULONG XcanModule::bus_state(unsigned i) const {
  const Interface& f = ifaces_[i];
  // WARN and BOFF as the interrupt service last saw them: a query does not touch the status
  // register (reading it would end a status change interrupt).
  const uint8_t s = f.error_bits;
  USHORT flags = 0;
  if (f.chip.participating() && !(s & STATUS_BOFF)) {  // INI clear
    flags |= XCAN_BUS_ON;
  }
  if (s & STATUS_WARN) {
    flags |= XCAN_BUS_HEAVY;
  }
  if (s & STATUS_BOFF) {
    flags |= XCAN_BUS_OFF;
  }
  if (f.line_error) {
    flags |= XCAN_LINE_ERROR;
  }
  return XCAN_STATUS(flags, f.last_lec);
}

uint32_t XcanModule::request(unsigned i, const SendRequest& r) {
  Interface& f = ifaces_[i];
  if (f.error_bits & STATUS_BOFF) {
    return ERR_XCAN_NOT_READY;  // Decision: a bus-off interface takes no send requests
  }
  // Decision: the FIFO holds the object, not its data (as SL-CANi): the data that go are those
  // current when it leaves.
  return f.mgr->request(r) == RequestResult::fifo_full ? uint32_t{ERR_XCAN_FIFO_FULL}
                                                       : uint32_t{ERR_OK};
}

}  // namespace canemu::model::sorcus
