// What the VCI tests share: a canemud with a configuration of their own, stepped time through
// the canemu extension, and faults loaded into it. Used by the tests of libvcinpl, libvcinpl2
// and libvciapi (each built against its own header); what only one API's tests share is in
// vci_c_test_support.hpp and vci_cpp_test_support.hpp.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "canemu_vci.h"
#include "cantype.h"
#include "daemon_process.hpp"

namespace canemu::testing {

// Two adapters, alpha and beta, each with one SJA1000 on the classic bus can0 (500 kbit/s).
inline const char* const kTwoAdapters =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n";

// A configuration file in a fresh directory, removed with the object.
class ConfigFile {
 public:
  explicit ConfigFile(const std::string& text) {
    char dir[] = "/tmp/canemu-vci-XXXXXX";
    dir_ = ::mkdtemp(dir);
    path_ = dir_ + "/canemu.toml";
    FILE* f = std::fopen(path_.c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
  }
  ~ConfigFile() {
    ::unlink(path_.c_str());
    ::rmdir(dir_.c_str());
  }
  const std::string& path() const { return path_; }

 private:
  std::string dir_;
  std::string path_;
};

// canemud in stepped time on `config`, and the VCI library pointed at it.
struct VciDaemon {
  ConfigFile config;
  Daemon daemon;
  explicit VciDaemon(const std::string& text = kTwoAdapters)
      : config(text), daemon("stepped", {"--config=" + config.path()}) {
    EXPECT_EQ(canemuConnect(daemon.socket().c_str()), VCI_OK);
  }
  ~VciDaemon() { canemuConnect(nullptr); }
};

// Runs simulated time `ns` further.
inline void step_ns(uint64_t ns) {
  UINT64 now = 0;
  ASSERT_EQ(canemuStepTime(ns, &now), VCI_OK);
}

// Steps simulated time a millisecond at a time until `done` (set by another thread that waits
// for something in simulated time), for at most 30 s of wall time.
inline void step_until(const std::atomic<bool>& done) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!done && std::chrono::steady_clock::now() < give_up) {
    step_ns(1'000'000);
  }
  ASSERT_TRUE(done) << "the waiting call did not return";
}

// Runs `call`, which blocks until something happens in simulated time, on a thread of its own
// while this one steps simulated time until it returns (for at most 30 s of wall time).
template <class Call>
void step_while(Call call) {
  std::atomic<bool> done{false};
  std::thread caller([&] {
    call();
    done = true;
  });
  step_until(done);
  caller.join();
}

// Simulated time from canemud's start (each test starts its own canemud at 0), stepped to
// exact instants.
struct SimClock {
  uint64_t now = 0;
  void to(uint64_t t_ns) {
    ASSERT_GT(t_ns, now);
    UINT64 after = 0;
    ASSERT_EQ(canemuStepTime(t_ns - now, &after), VCI_OK);
    now = after;
    ASSERT_EQ(now, t_ns);
  }
};

// The BTR0/BTR1 pairs of cantype.h's table (SJA1000 at 16 MHz) and the bit rates they give.
struct BtrRate {
  UINT8 btr0;
  UINT8 btr1;
  uint64_t bps;
};
inline constexpr BtrRate kBtrTable[] = {
    {CAN_BT0_5KB, CAN_BT1_5KB, 5'000},       {CAN_BT0_10KB, CAN_BT1_10KB, 10'000},
    {CAN_BT0_20KB, CAN_BT1_20KB, 20'000},    {CAN_BT0_50KB, CAN_BT1_50KB, 50'000},
    {CAN_BT0_100KB, CAN_BT1_100KB, 100'000}, {CAN_BT0_125KB, CAN_BT1_125KB, 125'000},
    {CAN_BT0_250KB, CAN_BT1_250KB, 250'000}, {CAN_BT0_500KB, CAN_BT1_500KB, 500'000},
    {CAN_BT0_800KB, CAN_BT1_800KB, 800'000}, {CAN_BT0_1000KB, CAN_BT1_1000KB, 1'000'000}};

// An entry of the cyclic transmit list (CANCYCLICTXMSG or CANCYCLICTXMSG2): a data frame with
// identifier `id` and `dlc`, sent every `cycle` ticks; its data bytes zero, no increment.
template <class Cyclic = CANCYCLICTXMSG>
inline Cyclic cyclic_data(UINT32 id, UINT16 cycle, UINT8 dlc = 0) {
  Cyclic m{};
  m.wCycleTime = cycle;
  m.dwMsgId = id;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = dlc & 0x0FU;
  return m;
}

// The identifier 0123456789ABCDEF into text through `to_char` (vciLuidToCharA, VciLuidToChar:
// 16 characters are too few, 17 hold it) and back through `from_char`, which refuses `bad`.
template <class ToChar, class FromChar>
void expect_luid_round_trip(ToChar to_char, FromChar from_char, char* bad) {
  VCIID id{};
  id.AsInt64 = 0x0123456789ABCDEF;
  char text[17];
  EXPECT_EQ(to_char(id, text, 16), VCI_E_BUFFER_OVERFLOW);
  ASSERT_EQ(to_char(id, text, 17), VCI_OK);
  EXPECT_STREQ(text, "0123456789ABCDEF");
  VCIID back{};
  ASSERT_EQ(from_char(text, &back), VCI_OK);
  EXPECT_EQ(back.AsInt64, id.AsInt64);
  EXPECT_EQ(from_char(bad, &back), VCI_E_FAIL);
}

// The identifiers of `msgs` (CANMSG or CANMSG2), in order.
template <class Msg>
inline std::vector<uint32_t> ids_of(const std::vector<Msg>& msgs) {
  std::vector<uint32_t> ids;
  for (const Msg& m : msgs) {
    ids.push_back(m.dwMsgId);
  }
  return ids;
}

// Loads a fault scenario from `text` into the daemon.
inline void load_faults(const Daemon& d, const std::string& text) {
  auto c = connect(d, "faults");
  auto m = ipc::make_message<ipc::FaultLoadRequest>();
  ipc::copy_name(m.source, "test.toml");
  m.length = static_cast<uint32_t>(text.size());
  std::memcpy(m.text, text.data(), text.size());
  auto r = c.call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(m);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_GT(r->applied, 0u) << r->errors;  // a refused scenario is the test's mistake
}

}  // namespace canemu::testing
