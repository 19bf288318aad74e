// An X-CAN-2i module for tests: interface 0 on a 500 kbit/s bus with an SJA1000 node beside it
// (interface 1 on a bus of its own), a sink that logs every callback and completion, and the
// channel calls a client makes. Instants are in ns at 500 kbit/s (2000 ns per bit).
#pragma once

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "canemu/firmware_model/adapters/sorcus/xcan_module.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"
#include "hosted_station.hpp"

namespace canemu::model::sorcus::testing {

using model::testing::kBit;
using Bytes = std::vector<uint8_t>;

struct LogSink final : XcanSink {
  std::vector<XcanCallback> callbacks;
  std::vector<XcanCompletion> completions;
  void callback(const XcanCallback& c) override { callbacks.push_back(c); }
  void completed(const XcanCompletion& c) override { completions.push_back(c); }
};

// SOF through EOF of `f`, in ns.
inline int64_t frame_ns(const Frame& f) {
  return encode(f).length * kBit;
}
inline constexpr int64_t kIntermission = 3 * kBit;

using model::testing::remote_frame;
// A valid classic data frame; a test that asks for an impossible one stops here, loudly.
inline Frame data_frame(uint32_t id, std::vector<uint8_t> data, bool extended = false) {
  auto frame = Frame::classic(id, data, extended);
  if (!frame) {
    throw std::invalid_argument("data_frame: " + frame.error().message);
  }
  return *frame;
}

inline XCAN_BITPARAMS params_500k() {
  return XCAN_BITPARAMS{125, 13, 2, 1, 1, 0, 11};
}

inline std::span<const uint8_t> bytes(const auto& v) {
  return {reinterpret_cast<const uint8_t*>(&v), sizeof v};
}

struct Peer : model::testing::Station<Sja1000Node> {
  using model::testing::Station<Sja1000Node>::Station;
  void start(uint8_t btr0 = 0x00, uint8_t btr1 = 0x1C) {
    HostedNodeSettings s;
    s.btr0 = btr0;
    s.btr1 = btr1;
    model::testing::Station<Sja1000Node>::start(s);
  }
};

struct Xcan {
  model::testing::BusFixture b;
  CanBus bus1{b.sched, "can1"};
  LogSink sink;
  XcanModule m;
  Peer peer{b};

  explicit Xcan(XcanVariant variant = XcanVariant::h) : m(b.sched, variant, sink) {
    m.connect(0, b.bus);
    m.connect(1, bus1);
    peer.start();
  }
  void run_until(int64_t ns) { b.run_until(ns); }
  int64_t now() const { return b.sched.now().ns(); }

  static CPS_XCAN cps(USHORT device, ULONG id, USHORT flags = 0, USHORT timeout = 0,
                      USHORT iface = 0) {
    // Device, interface, index range (0 to 0: set only for bus control), flags, timeout, id.
    return CPS_XCAN{device, iface, 0, 0, flags, timeout, id};
  }
  // Opens a channel that must open.
  ChannelHandle open(const CPS_XCAN& c, bool callback = true) {
    auto h = m.open_channel(c, callback);
    EXPECT_TRUE(h.has_value()) << "error " << (h ? 0u : h.error());
    return h.value_or(0);
  }
  // The bus-control device of interface `i`, at 500 kbit/s.
  ChannelHandle bus_control(USHORT i = 0, XCAN_BITPARAMS p = params_500k(), USHORT flags = 0) {
    CPS_XCAN c = cps(DEVICE_CTRL, 0, flags, 0, i);
    c.usIndexFirst = c.usIndexLast = XCAN_BUS_CTRL_INDEX;
    const ChannelHandle h = open(c);
    EXPECT_EQ(m.write_block(h, bytes(p)).error, uint32_t{ERR_OK});
    return h;
  }
  ChannelHandle filter(ULONG id = XCAN_AUTO_ID, USHORT flags = 0, USHORT i = 0) {
    return open(cps(DEVICE_CTRL, id, flags, 0, i));
  }
  uint32_t write(ChannelHandle h, std::vector<uint8_t> data) {
    return m.write_block(h, data).error;
  }
  std::vector<uint8_t> read(ChannelHandle h) {
    const Reply r = m.read_block(h);
    EXPECT_EQ(r.error, uint32_t{ERR_OK});
    return r.data;
  }
  // The valid data bytes of each callback so far.
  std::vector<Bytes> callback_data() const {
    std::vector<Bytes> out;
    for (const XcanCallback& c : sink.callbacks) {
      out.emplace_back(c.data.begin(), c.data.begin() + c.size);
    }
    return out;
  }
  uint32_t send_general(ChannelHandle h, ULONG id, std::vector<uint8_t> data, USHORT flags = 0) {
    XCAN_MESSAGE msg{};
    msg.ulCanId = id;
    msg.usFlags = flags;
    msg.usDataSize = static_cast<USHORT>(data.size());
    std::memcpy(msg.aucData, data.data(), std::min<std::size_t>(data.size(), 8));
    return m.write_block(h, bytes(msg)).error;
  }
};

}  // namespace canemu::model::sorcus::testing
