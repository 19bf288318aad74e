// A frame an IXXAT adapter received (CANMSG of the VCI C API) written as candump writes one, so
// that a test compares identifier, remote flag, DLC and data in one string.
#pragma once

#include <cstdio>
#include <string>

#include "vcinpl.h"

namespace canemu::testing {

// "ID#DATA" with the data in hex (ID: 3 digits, 8 for an extended frame), or "ID#R" and the
// DLC for a remote frame.
inline std::string candump_text(const CANMSG& m) {
  char out[40];
  int at = std::snprintf(out, sizeof out, m.uMsgInfo.Bits.ext ? "%08X#" : "%03X#",
                         static_cast<unsigned>(m.dwMsgId));
  if (m.uMsgInfo.Bits.rtr) {
    std::snprintf(out + at, sizeof out - at, "R%u", static_cast<unsigned>(m.uMsgInfo.Bits.dlc));
    return out;
  }
  for (unsigned k = 0; k < m.uMsgInfo.Bits.dlc && k < 8; ++k) {
    at += std::snprintf(out + at, sizeof out - at, "%02X", m.abData[k]);
  }
  return out;
}

}  // namespace canemu::testing
