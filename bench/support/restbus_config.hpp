// The restbus of canemud's benchmarks: one 500 kbit/s bus with 40 simulated ECUs ([[can_node]])
// sending 300 cyclic 8-byte messages of distinct identifiers, with their signals (4 to 8 each:
// little- and big-endian, signed, scaled and offset, a float; an alive counter on three
// messages of four, a CRC-8 SAE J1850 checksum on half of them, a sum8 on a quarter) or, as the
// baseline, the same nodes and messages without signals (payloads of zeros).
#pragma once

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "canemu/firmware_model/bus/frame.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"

namespace canemu::bench {

struct RestbusMessage {
  int node = 0;  // ECU_00 .. ECU_39
  uint32_t id = 0;
  int64_t cycle_ns = 0;
  int64_t delay_ns = 0;
  int layout = 0;  // which of the four signal layouts below
};

struct Restbus {
  static constexpr int kNodes = 40;
  static constexpr uint32_t kBitrate = 500'000;
  std::vector<RestbusMessage> messages;

  // Frames queued per second by the schedule.
  double frames_per_second() const {
    double f = 0;
    for (const RestbusMessage& m : messages) {
      f += 1e9 / static_cast<double>(m.cycle_ns);
    }
    return f;
  }

  // The bus load the schedule makes with the baseline's payloads (eight bytes of zeros): every
  // frame's exact bit count from start of frame through end of frame, stuff bits included,
  // plus the 3-bit intermission, in percent of the bus's bits.
  double baseline_load_percent() const {
    double bits = 0;
    const uint8_t zeros[8] = {};
    for (const RestbusMessage& m : messages) {
      const auto frame = model::Frame::classic(m.id, std::span<const uint8_t>(zeros, 8));
      bits += (model::encode(*frame).length + 3) * 1e9 / static_cast<double>(m.cycle_ns);
    }
    return 100.0 * bits / kBitrate;
  }

  // The message with identifier `id`, or nothing.
  const RestbusMessage* find(uint32_t id) const {
    for (const RestbusMessage& m : messages) {
      if (m.id == id) {
        return &m;
      }
    }
    return nullptr;
  }

  // How many frames `m` queues at instants in [from_ns, to_ns): delay + k * cycle, k >= 0.
  static int64_t queued_in(const RestbusMessage& m, int64_t from_ns, int64_t to_ns) {
    const auto first_at_or_after = [&](int64_t t) -> int64_t {  // k of the first instant >= t
      return t <= m.delay_ns ? 0 : (t - m.delay_ns + m.cycle_ns - 1) / m.cycle_ns;
    };
    return std::max<int64_t>(0, first_at_or_after(to_ns) - first_at_or_after(from_ns));
  }

  // The instant a frame of `m` that ended at `end_ns` was queued, when it waited less than one
  // cycle (at this load every frame goes within a few milliseconds).
  static int64_t queued_at(const RestbusMessage& m, int64_t end_ns) {
    return end_ns < m.delay_ns ? -1 : m.delay_ns + (end_ns - m.delay_ns) / m.cycle_ns * m.cycle_ns;
  }
};

// 300 messages: the faster the cycle, the lower (higher priority) the identifier; each cycle's
// messages spread over it by their delays, and over the 40 nodes in turn.
inline Restbus restbus_schedule() {
  struct Group {
    int cycle_ms;
    int count;
  };
  constexpr Group kGroups[] = {{10, 4},   {20, 8},   {50, 16},  {100, 42},
                               {200, 70}, {500, 80}, {1000, 80}};  // 300 messages
  Restbus r;
  int index = 0;
  for (int g = 0; g < static_cast<int>(std::size(kGroups)); ++g) {
    const Group& group = kGroups[g];
    for (int j = 0; j < group.count; ++j, ++index) {
      RestbusMessage m;
      m.node = index % Restbus::kNodes;
      m.id = 0x0A0 + 6 * static_cast<uint32_t>(index);
      m.cycle_ns = int64_t{group.cycle_ms} * 1'000'000;
      m.delay_ns = int64_t{(j * group.cycle_ms / group.count + 3 * g) % group.cycle_ms} * 1'000'000;
      m.layout = index % 4;
      r.messages.push_back(m);
    }
  }
  return r;
}

namespace restbus_detail {

struct Signal {
  const char* name;
  int start;
  int length;
  bool big_endian;
  bool is_signed;
  const char* type;  // "integer" or "float32"
  double scale;
  double offset;
  double initial;
  const char* role;  // "", "counter", "crc8_sae_j1850", "sum8"
};

// Four layouts of eight bytes, every bit of most of them used.
inline std::span<const Signal> layout(int n) {
  static constexpr Signal kA[] = {
      // little-endian, a CRC-8 in byte 0 and a counter
      {"crc", 0, 8, false, false, "integer", 1, 0, 0, "crc8_sae_j1850"},
      {"alive", 8, 4, false, false, "integer", 1, 0, 0, "counter"},
      {"status", 12, 4, false, false, "integer", 1, 0, 3, ""},
      {"speed", 16, 16, false, false, "integer", 0.01, 0, 12.34, ""},
      {"torque", 32, 12, false, true, "integer", 0.5, 0, -20, ""},
      {"temperature", 44, 12, false, false, "integer", 0.1, -40, 25, ""},
      {"gear", 56, 8, false, false, "integer", 1, 0, 4, ""}};
  static constexpr Signal kB[] = {
      // big-endian, a counter and a CRC-8 in byte 7
      {"rpm", 7, 16, true, false, "integer", 0.25, 0, 800, ""},
      {"angle", 23, 16, true, true, "integer", 0.1, 0, -12.5, ""},
      {"flags", 39, 8, true, false, "integer", 1, 0, 5, ""},
      {"voltage", 47, 12, true, false, "integer", 0.01, 0, 12.6, ""},
      {"alive", 51, 4, true, false, "integer", 1, 0, 0, "counter"},
      {"crc", 63, 8, true, false, "integer", 1, 0, 0, "crc8_sae_j1850"}};
  static constexpr Signal kC[] = {// mixed: a float, no counter, no checksum
                                  {"pressure", 0, 32, false, false, "float32", 1, 0, 3.5, ""},
                                  {"trim", 39, 8, true, true, "integer", 1, 0, -3, ""},
                                  {"level", 40, 10, false, false, "integer", 0.1, -10, 5, ""},
                                  {"position", 50, 14, false, true, "integer", 1, 0, -1000, ""}};
  static constexpr Signal kD[] = {// eight bytes: a counter, a sum8
                                  {"alive", 0, 8, false, false, "integer", 1, 0, 0, "counter"},
                                  {"offset_a", 8, 8, false, true, "integer", 1, 0, -5, ""},
                                  {"half", 16, 8, false, false, "integer", 0.5, 0, 20, ""},
                                  {"celsius", 24, 8, false, false, "integer", 1, -40, 0, ""},
                                  {"motorola", 39, 8, true, false, "integer", 1, 0, 200, ""},
                                  {"enable", 40, 8, false, false, "integer", 1, 0, 1, ""},
                                  {"offset_b", 48, 8, false, true, "integer", 1, 0, -100, ""},
                                  {"sum", 56, 8, false, false, "integer", 1, 0, 0, "sum8"}};
  switch (n) {
    case 0:
      return kA;
    case 1:
      return kB;
    case 2:
      return kC;
    default:
      return kD;
  }
}

// A TOML float: "1.0", not the integer "1".
inline std::string toml_float(double v) {
  std::ostringstream o;
  o << v;
  std::string t = o.str();
  return t.find_first_of(".e") == std::string::npos ? t + ".0" : t;
}

}  // namespace restbus_detail

// A configuration file's text: [simulation] with `time` (e.g. "realtime", "stepped"), bus can0
// at 500 kbit/s, and the 40 [[can_node]]s of `r`, with their signals or without.
inline std::string restbus_config(const Restbus& r, const std::string& time, bool signals) {
  std::ostringstream f;
  f << "[simulation]\ntime = \"" << time
    << "\"\n\n[[bus]]\nname = \"can0\"\nbitrate = " << Restbus::kBitrate << "\n";
  for (int node = 0; node < Restbus::kNodes; ++node) {
    f << "\n[[can_node]]\nname = \"ECU_" << (node < 10 ? "0" : "") << node
      << "\"\nbus = \"can0\"\n";
    for (const RestbusMessage& m : r.messages) {
      if (m.node != node) {
        continue;
      }
      f << "\n[[can_node.message]]\nname = \"M" << std::hex << m.id << std::dec
        << "\"\nid = " << m.id << "\nlength = 8\nsend = \"cyclic\"\ncycle = \""
        << m.cycle_ns / 1'000'000 << "ms\"\ndelay = \"" << m.delay_ns / 1'000'000 << "ms\"\n";
      if (!signals) {
        continue;
      }
      for (const restbus_detail::Signal& s : restbus_detail::layout(m.layout)) {
        f << "[[can_node.message.signal]]\nname = \"" << s.name << "\"\nstart = " << s.start
          << "\nlength = " << s.length << "\nbyte_order = \""
          << (s.big_endian ? "big_endian" : "little_endian")
          << "\"\nsigned = " << (s.is_signed ? "true" : "false") << "\ntype = \"" << s.type
          << "\"\nscale = " << restbus_detail::toml_float(s.scale)
          << "\noffset = " << restbus_detail::toml_float(s.offset)
          << "\ninitial = " << restbus_detail::toml_float(s.initial) << "\n";
        const std::string role = s.role;
        if (role == "counter") {
          f << "counter = true\n";
        } else if (!role.empty()) {
          f << "checksum = \"" << role << "\"\n";
          if (role == "crc8_sae_j1850") {
            f << "data_id = " << m.id << "\n";
          }
        }
      }
    }
  }
  return f.str();
}

}  // namespace canemu::bench
