// An SL-CANi in slot 1 for tests: its 82527 on a 500 kbit/s bus (EEPROM words 15..19 = 100 ns,
// 16, 3, 1, 1) with an SJA1000 node beside it, a sink that logs every service routine call
// and service request, and the library's calls. Instants are in ns at 500 kbit/s.
#pragma once

#include <vector>

#include "adapters/sorcus/xcan_fixture.hpp"
#include "canemu/firmware_model/adapters/sorcus/slcan_module.hpp"

namespace canemu::model::sorcus::testing {

struct SlcanLog final : SlcanSink {
  std::vector<SlcanServiceCall> calls;
  std::vector<std::pair<int64_t, USHORT>> requests;
  void service(const SlcanServiceCall& c) override { calls.push_back(c); }
  void service_request(SimTime at, USHORT word) override { requests.emplace_back(at.ns(), word); }
};

// The manual's example routine: task 100, function 4.
inline constexpr USHORT kTask = 100;
inline constexpr USHORT kFunc = 4;
inline constexpr USHORT kErrFunc = 5;

struct Slcan {
  model::testing::BusFixture b;
  SlcanLog log;
  SlcanModule m;
  Peer peer{b};

  // `with_peer`: the SJA1000 node is on the bus (else the S-Link is alone: nobody acknowledges).
  explicit Slcan(bool with_peer = true) : m(b.sched, 1, log) {
    m.connect(b.bus);
    EXPECT_TRUE(m.write_eeprom(SL064_EEPROM_TQ, 100));
    EXPECT_TRUE(m.write_eeprom(SL064_EEPROM_TSEG1, 16));
    EXPECT_TRUE(m.write_eeprom(SL064_EEPROM_TSEG2, 3));
    EXPECT_TRUE(m.write_eeprom(SL064_EEPROM_SJW, 1));
    m.install_routine(kTask, kFunc);
    m.install_routine(kTask, kErrFunc);
    if (with_peer) {
      peer.start();
    }
  }
  void run_until(int64_t ns) { b.run_until(ns); }
  int64_t now() const { return b.sched.now().ns(); }

  // Startup and config_module with the error routine (task 100, function 5).
  void configure(USHORT err_task = kTask, USHORT err_func = kErrFunc) {
    EXPECT_EQ(m.bib_startup(), 0);
    EXPECT_EQ(m.config_module(err_task, err_func), 0);
    EXPECT_EQ(m.get_diagnosis(), 0);
  }
  // config_msg_object; the diagnosis it left in `diag`.
  SL064Handle object(ULONG id, USHORT flags, USHORT* diag = nullptr, USHORT task = kTask,
                     USHORT func = kFunc) {
    SL064MsgType c{id, flags, task, func};
    SL064Handle h = 0xFFFF;
    const USHORT r = m.config_msg_object(c, h);
    const USHORT d = m.get_diagnosis();
    if (diag != nullptr) {
      *diag = d;
    } else {
      EXPECT_EQ(r, 0) << "diagnosis " << d;
      EXPECT_EQ(d, 0);
    }
    return h;
  }
  // A call's return value and diagnosis together.
  std::pair<USHORT, USHORT> diag(USHORT r) { return {r, m.get_diagnosis()}; }
  USHORT set(SL064Handle h, std::vector<uint8_t> data) { return m.set_data(h, data); }
  std::vector<uint8_t> get(SL064Handle h, uint8_t want = 8) {
    std::array<uint8_t, 8> d{};
    uint8_t size = want;
    (void)m.get_data(h, d, size);
    return {d.begin(), d.begin() + size};
  }
  std::vector<SL064Handle> message_calls() const {
    std::vector<SL064Handle> out;
    for (const auto& c : log.calls) {
      if (c.kind == SlcanServiceCall::Kind::message) {
        out.push_back(c.handle);
      }
    }
    return out;
  }
};

using Diag = std::pair<USHORT, USHORT>;
inline constexpr Diag kOk{0, 0};
inline Diag warning(USHORT code) {
  return {0, code};
}
inline Diag error(USHORT code) {
  return {SL064_E_DRIVER, code};
}

}  // namespace canemu::model::sorcus::testing
