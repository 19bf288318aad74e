// What the LIN tests of the VCI C and C++ APIs share: three adapters with a CAN controller (0)
// and a LIN controller (1) on lin0 at 19200 bit/s, and the expected values computed here,
// independently of the model: protected identifiers, checksums, frame times.
#pragma once

#include <cstdint>
#include <vector>

#include "vci/lintype.h"
#include "vci_test_support.hpp"

namespace canemu::testing {

inline const char* const kLinAdapters =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\nbitrate = 19200\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n"
    "lin = [\"lin0\"]\n\n"
    "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n"
    "lin = [\"lin0\"]\n\n"
    "[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n"
    "lin = [\"lin0\"]\n";

inline constexpr UINT32 kLinNo = 1;  // after the one CAN controller
inline constexpr uint32_t kRate = 19200;

// The protected identifier: P0 = ID0^ID1^ID2^ID4 (bit 6), P1 = !(ID1^ID3^ID4^ID5) (bit 7).
inline uint8_t pid_of(uint8_t id) {
  auto bit = [id](int n) { return (id >> n) & 1; };
  const int p0 = bit(0) ^ bit(1) ^ bit(2) ^ bit(4);
  const int p1 = 1 ^ bit(1) ^ bit(3) ^ bit(4) ^ bit(5);
  return static_cast<uint8_t>(id | (p0 << 6) | (p1 << 7));
}

// The inverted sum with carries added back, over `bytes` (and the PID when enhanced).
inline uint8_t checksum_of(const std::vector<uint8_t>& bytes, int pid = -1) {
  unsigned sum = pid >= 0 ? static_cast<unsigned>(pid) : 0U;
  for (uint8_t b : bytes) {
    sum += b;
    if (sum > 0xFF) {
      sum -= 0xFF;
    }
  }
  return static_cast<uint8_t>(~sum);
}

// Bit k of a frame starting at `start_ns` begins at start + floor(k * 1e9 / rate).
inline int64_t after_bits(int64_t start_ns, int64_t bits) {
  return start_ns + bits * 1'000'000'000 / kRate;
}
// The end of a whole frame with `n` data bytes: break 13, delimiter 1, sync 10, PID 10, then
// 10 per byte and 10 for the checksum.
inline int64_t frame_end(int64_t start_ns, int n) {
  return after_bits(start_ns, 34 + 10 * (n + 1));
}
// A no-response error: the header's end and the longest response's maximum time (14 x 9).
inline int64_t no_response_at(int64_t start_ns) {
  return after_bits(start_ns, 34 + 126);
}
// A time stamp: microseconds since the adapter's power-on (0 for configured adapters).
inline uint32_t stamp(int64_t ns) {
  return static_cast<uint32_t>(ns / 1000);
}

inline LINMSG lin_data(uint8_t id, std::vector<uint8_t> bytes, bool enhanced = true,
                       bool header_only = false) {
  LINMSG m{};
  m.uMsgInfo.Bytes.bPid = id;
  m.uMsgInfo.Bytes.bType = LIN_MSGTYPE_DATA;
  m.uMsgInfo.Bytes.bDlen = static_cast<UINT8>(bytes.size());
  m.uMsgInfo.Bits.ecs = enhanced ? 1 : 0;
  m.uMsgInfo.Bits.ido = header_only ? 1 : 0;
  for (std::size_t i = 0; i < bytes.size() && i < 8; ++i) {
    m.abData[i] = bytes[i];
  }
  return m;
}

inline LINMSG lin_type(uint8_t type) {
  LINMSG m{};
  m.uMsgInfo.Bytes.bType = type;
  return m;
}

// Runs simulated time `ns` further and returns the time after it.
inline int64_t step_to(uint64_t ns) {
  UINT64 now = 0;
  EXPECT_EQ(canemuStepTime(ns, &now), VCI_OK);
  return static_cast<int64_t>(now);
}

// A message as a line of text, for comparisons that show what differs.
inline std::string text_of(const LINMSG& m) {
  std::string s = "t=" + std::to_string(m.dwTime) +
                  " type=" + std::to_string(m.uMsgInfo.Bytes.bType) +
                  " pid=" + std::to_string(m.uMsgInfo.Bytes.bPid) +
                  " dlen=" + std::to_string(m.uMsgInfo.Bytes.bDlen) +
                  " flags=" + std::to_string(m.uMsgInfo.Bytes.bFlags) + " data=";
  const int n = m.uMsgInfo.Bytes.bType == LIN_MSGTYPE_DATA ? m.uMsgInfo.Bytes.bDlen : 2;
  for (int i = 0; i < n && i < 8; ++i) {
    s += std::to_string(m.abData[i]) + (i + 1 < n ? "," : "");
  }
  return s;
}

// Every message `take` gives (it returns false when there is none left).
template <class Take>
std::vector<LINMSG> drain_with(Take take) {
  std::vector<LINMSG> got;
  LINMSG m;
  while (take(m)) {
    got.push_back(m);
  }
  return got;
}

// The messages as text.
inline std::vector<std::string> texts_of(const std::vector<LINMSG>& messages) {
  std::vector<std::string> got;
  for (const LINMSG& m : messages) {
    got.push_back(text_of(m));
  }
  return got;
}

// The messages as text, but for the start's info message.
inline std::vector<std::string> texts_but_start(const std::vector<LINMSG>& messages) {
  std::vector<std::string> got;
  for (const LINMSG& m : messages) {
    if (!(m.uMsgInfo.Bytes.bType == LIN_MSGTYPE_INFO && m.abData[0] == LIN_INFO_START)) {
      got.push_back(text_of(m));
    }
  }
  return got;
}

// What a monitor should get: a data frame (flags: ecs, sor) or an event (info, error, ...).
inline std::string frame_text(uint32_t time, uint8_t id, std::vector<uint8_t> bytes, bool ecs,
                              bool sor) {
  LINMSG m = lin_data(id, std::move(bytes), ecs);
  m.dwTime = time;
  m.uMsgInfo.Bits.sor = sor ? 1 : 0;
  return text_of(m);
}
inline std::string event_text(uint32_t time, uint8_t type, uint8_t data0, uint8_t data1 = 0) {
  LINMSG m{};
  m.dwTime = time;
  m.uMsgInfo.Bytes.bPid = 0xFF;
  m.uMsgInfo.Bytes.bType = type;
  m.abData[0] = data0;
  m.abData[1] = data1;
  return text_of(m);
}

// What a monitor gets when its line is started at `t_ns`, stopped and reset: the info messages
// (stop and reset are stamped 0).
inline std::vector<std::string> start_stop_reset(int64_t t_ns) {
  return {event_text(stamp(t_ns), LIN_MSGTYPE_INFO, LIN_INFO_START),
          event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_STOP),
          event_text(0, LIN_MSGTYPE_INFO, LIN_INFO_RESET)};
}

}  // namespace canemu::testing
