// What the tests of the VCI firmware (can_line.hpp and its parts) share: channel FIFOs that
// tests fill and read, message and filter-call builders, and a line on an SJA1000 with a peer
// station on a simulated bus.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <deque>
#include <initializer_list>
#include <ostream>
#include <tuple>
#include <vector>

#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/firmware_model/chips/sja1000/sja1000_node.hpp"
#include "hosted_station.hpp"

namespace canemu::model::testing {

using ixxat::ChannelId;
using ixxat::FilterOp;

constexpr int64_t kUs = 1'000;      // one device tick (time stamps, delays) with default Clocks
constexpr int64_t kMs = 1'000'000;  // one tick of the cyclic list
constexpr uint8_t kOpAll = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME;
constexpr uint32_t kStdMask = 0xFFF;
constexpr uint32_t kExtMask = 0x3FFFFFFF;

// A channel's FIFOs: the transmit FIFO the test fills, a bounded receive FIFO.
struct Port final : ixxat::ChannelPort {
  explicit Port(std::size_t rx_capacity = 1024) : capacity(rx_capacity) {}
  int deferred = 0;  // times the firmware deferred this port
  bool put(const CANMSG2& m) override {
    if (rx.size() >= capacity) {
      return false;
    }
    rx.push_back(m);
    return true;
  }
  std::optional<CANMSG2> peek() override {
    if (tx.empty()) {
      return std::nullopt;
    }
    return tx.front();
  }
  void pop() override { tx.pop_front(); }
  void defer() override { ++deferred; }

  std::vector<CANMSG2> of_type(uint8_t type) const {
    std::vector<CANMSG2> out;
    for (const CANMSG2& m : rx) {
      if (m.uMsgInfo.Bits.type == type) {
        out.push_back(m);
      }
    }
    return out;
  }
  std::vector<CANMSG2> data() const { return of_type(CAN_MSGTYPE_DATA); }
  std::vector<uint32_t> data_ids() const {
    std::vector<uint32_t> ids;
    for (const CANMSG2& m : data()) {
      ids.push_back(m.dwMsgId);
    }
    return ids;
  }

  std::size_t capacity;
  std::deque<CANMSG2> tx;
  std::vector<CANMSG2> rx;
};

// The four bytes of CANMSGINFO: type, flags2 (ssm hpm edl fdr esi), flags (dlc ovr srr rtr
// ext), accept.
struct Info {
  unsigned type, flags2, flags, accept;
  friend bool operator==(const Info&, const Info&) = default;
  friend std::ostream& operator<<(std::ostream& os, const Info& i) {
    return os << "{type " << i.type << ", flags2 0x" << std::hex << i.flags2 << ", flags 0x"
              << i.flags << ", accept 0x" << i.accept << std::dec << "}";
  }
};
inline Info info(const CANMSG2& m) {
  const auto& b = m.uMsgInfo.Bytes;
  return {b.bType, b.bFlags2, b.bFlags, b.bAccept};
}

inline CANMSG2 msg(uint32_t id, std::vector<uint8_t> data = {0x11, 0x22}, bool ext = false) {
  CANMSG2 m{};
  m.dwMsgId = id;
  m.uMsgInfo.Bits.type = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = data.size() & 0x0FU;
  m.uMsgInfo.Bits.ext = ext ? 1 : 0;
  std::memcpy(m.abData, data.data(), data.size());
  return m;
}
inline CANMSG2 with_srr(CANMSG2 m) {
  m.uMsgInfo.Bits.srr = 1;
  return m;
}

inline Frame remote(uint32_t id, bool ext = false) {
  FrameSpec s;
  s.id = id;
  s.extended = ext;
  s.remote = true;
  s.dlc = 0;
  return *Frame::create(s);
}
inline Frame classic(uint32_t id, std::vector<uint8_t> data = {0x11, 0x22}, bool ext = false) {
  return testing::frame(id, std::move(data), ext);
}
// Bits from SOF to the end of EOF of a classic frame.
inline int64_t bits_of(const Frame& f) {
  return frame_duration(encode(f), testing::timing_500k()).ns() / kBit;
}

inline FilterOp acceptance(uint8_t select, uint32_t code, uint32_t mask) {
  return {FilterOp::Kind::set_acceptance, select, 0, code, mask};
}
inline FilterOp add_ids(uint8_t select, uint32_t code, uint32_t mask) {
  return {FilterOp::Kind::add_ids, select, 0, code, mask};
}
inline FilterOp remove_ids(uint8_t select, uint32_t code, uint32_t mask) {
  return {FilterOp::Kind::remove_ids, select, 0, code, mask};
}
inline FilterOp set_mode(uint8_t select, uint8_t mode) {
  return {FilterOp::Kind::set_mode, select, mode, 0, 0};
}
inline FilterOp get_mode(uint8_t select) {
  return {FilterOp::Kind::get_mode, select, 0, 0, 0};
}

inline ixxat::LineInit v1_init(uint8_t op_mode = kOpAll) {
  ixxat::LineInit init;
  init.op_mode = op_mode;
  init.btr0 = CAN_BT0_500KB;
  init.btr1 = CAN_BT1_500KB;
  return init;
}
inline ixxat::LineInit v2_init(uint8_t sf_mode = CAN_FILTER_INCL,
                               uint8_t ef_mode = CAN_FILTER_INCL) {
  ixxat::LineInit init;
  init.v2 = true;
  init.op_mode = kOpAll;
  init.sf_mode = sf_mode;
  init.ef_mode = ef_mode;
  init.sdr = CAN_BTP_500KB;
  return init;
}

// An SJA1000 station at 500 kbit/s that acknowledges the line's frames once started.
struct Peer : testing::Station<Sja1000Node> {
  using testing::Station<Sja1000Node>::Station;
  void start() {
    HostedNodeSettings s;
    s.btr0 = 0x00;
    s.btr1 = 0x1C;
    testing::Station<Sja1000Node>::start(s);
  }
};

// A line on an SJA1000 with a peer on the same bus (not started unless a test starts it).
struct Rig {
  explicit Rig(const ixxat::Clocks& clocks = {}) : line(b.sched, node, clocks, SimTime{}) {}

  // Control unit opened and the line initialized (v1, 500 kbit/s).
  void init(uint8_t op_mode = kOpAll) {
    ASSERT_EQ(line.open_control(), VCI_OK);
    ASSERT_EQ(line.init_line(v1_init(op_mode)), VCI_OK);
  }
  // A channel opened, initialized with `port` and activated.
  ChannelId channel(Port& port, bool v2 = false, ixxat::ChannelSetup setup = {}) {
    auto id = line.open_channel(false, v2);
    EXPECT_TRUE(id.has_value());
    EXPECT_EQ(line.init_channel(id.value(), setup, &port), VCI_OK);
    EXPECT_EQ(line.activate(*id), VCI_OK);
    return *id;
  }
  // init(), a v1 channel on `port` and the peer started; the line is not started yet, so the
  // test can fill the transmit FIFO first.
  ChannelId ready(Port& port) {
    init();
    const ChannelId id = channel(port);
    peer.start();
    return id;
  }
  // ready(port), `frames` in its transmit FIFO, then the line started: the first frame is
  // loaded into the controller at once.
  ChannelId start_with(Port& port, std::vector<CANMSG2> frames) {
    const ChannelId id = ready(port);
    port.tx.assign(frames.begin(), frames.end());
    EXPECT_EQ(line.start_line(), VCI_OK);
    return id;
  }
  // A channel to open on `port`: v1, or v2 with its filter setup.
  struct Open {
    Port& port;
    bool v2 = false;
    ixxat::ChannelSetup setup = {};
  };
  // init(), a channel for each of `channels`, the line started and the peer started, all at now;
  // their ids, in order.
  std::vector<ChannelId> online(std::initializer_list<Open> channels) {
    init();
    std::vector<ChannelId> ids;
    for (const Open& c : channels) {
      ids.push_back(channel(c.port, c.v2, c.setup));
    }
    EXPECT_EQ(line.start_line(), VCI_OK);
    peer.start();
    return ids;
  }
  // The same with one v1 channel on `port`.
  ChannelId online(Port& port) { return online({Open{port}})[0]; }
  void send(Port& port, const CANMSG2& m) {
    port.tx.push_back(m);
    line.tx_ready();
  }
  ixxat::ChannelCounters counters(ChannelId id) const { return line.channel_status(id)->counters; }

  testing::BusFixture b;
  Sja1000Node node{b.sched, b.bus};
  ixxat::CanLine line;
  Peer peer{b};
};

}  // namespace canemu::model::testing
