// What the system tests of libxcan.so share: canemud in stepped time with an X-CAN-2i and two
// IXXAT adapters on one bus, the callbacks a test's channels got, CPS and frame helpers.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <vector>

#include "vci_c_test_support.hpp"
#include "xcan.h"

namespace canemu::testing {

// The X-CAN-2i "xcan0" (interface 0 on can0, 1 on can1, both 500 kbit/s) and the IXXAT adapters
// "alpha" and "beta" on can0.
inline const char* const kConfig =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[bus]]\nname = \"can1\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"xcan0\"\nmodel = \"sorcus-x-can-2i\"\ncontrollers = [\"can0\", "
    "\"can1\"]\n";

// 16 time quanta of 125 ns: 500 kbit/s, sampled at 13/16.
inline constexpr XCAN_BITPARAMS k500k = {125, 12, 3, 1, 1, 0, 11};
// The same quanta at 250 ns: 250 kbit/s, against the bus's 500.
inline constexpr XCAN_BITPARAMS k250k = {250, 12, 3, 1, 1, 0, 11};

// What a channel's callback got, in order; waited for by the test (the buffered callbacks run
// on the library's thread).
struct Seen {
  MAX_HANDLE channel;
  std::vector<uint8_t> bytes;
};
inline std::mutex g_mutex;
inline std::condition_variable g_cv;
inline std::vector<Seen> g_seen;

inline void record(MAX_HANDLE hChan, ULONG ulSize, const void* pData) {
  Seen s{hChan, {}};
  if (ulSize > 0) {
    const auto* p = static_cast<const uint8_t*>(pData);
    s.bytes.assign(p, p + ulSize);
  }
  std::lock_guard lock(g_mutex);
  g_seen.push_back(std::move(s));
  g_cv.notify_all();
}

// The callbacks seen so far once there are `n` of them (at most 10 s of wall time).
inline std::vector<Seen> wait_seen(std::size_t n) {
  std::unique_lock lock(g_mutex);
  g_cv.wait_for(lock, std::chrono::seconds(10), [&] { return g_seen.size() >= n; });
  return g_seen;
}

// Bits on the wire of a remote frame with an 11-bit identifier and DLC `dlc`.
inline int64_t remote_bits(uint32_t id, uint8_t dlc) {
  model::FrameSpec spec;
  spec.id = id;
  spec.remote = true;
  spec.dlc = dlc;
  return static_cast<int64_t>(model::encode(*model::Frame::create(spec)).length);
}

inline ULONG status_of(const Seen& s) {
  ULONG v = 0;
  EXPECT_EQ(s.bytes.size(), sizeof v);
  std::memcpy(&v, s.bytes.data(), std::min(sizeof v, s.bytes.size()));
  return v;
}

inline XCAN_MESSAGE message_of(const Seen& s) {
  XCAN_MESSAGE m{};
  EXPECT_EQ(s.bytes.size(), sizeof m);
  std::memcpy(&m, s.bytes.data(), std::min(sizeof m, s.bytes.size()));
  return m;
}

inline CPS_XCAN cps(USHORT device, ULONG id, USHORT flags = 0, USHORT timeout = 0) {
  CPS_XCAN c{};
  c.usDevice = device;
  c.usChannel = 0;
  c.usFlags = flags;
  c.usTimeout = timeout;
  c.ulCanID = id;
  if (device == DEVICE_CTRL) {
    c.usIndexFirst = c.usIndexLast = XCAN_BUS_CTRL_INDEX;
  }
  return c;
}

// canemud with kConfig, the VCI library and libxcan connected to it, the MDD of xcan0 loaded
// and interface 0's bus-control channel (callback `bus_callback`) at `bits`.
struct XcanDaemon {
  VciDaemon vci{kConfig};
  MAX_HANDLE mdd = 0;
  MAX_HANDLE bus = 0;
  explicit XcanDaemon(const XCAN_BITPARAMS& bits = k500k, USHORT bus_flags = 0) {
    {
      std::lock_guard lock(g_mutex);
      g_seen.clear();
    }
    EXPECT_EQ(canemu_xcan_connect(vci.daemon.socket().c_str()), ERR_OK);
    MAX_HANDLE module = 0;
    EXPECT_EQ(canemu_open_module("xcan0", &module), ERR_OK);
    EXPECT_EQ(max_load_mdd(module, 1, 0, 0, 0x803A, nullptr, &mdd), ERR_OK);
    const CPS_XCAN c = cps(DEVICE_CTRL, 0, bus_flags);
    EXPECT_EQ(max_open_channel(mdd, &c, record, &bus), ERR_OK);
    ULONG size = sizeof bits;
    EXPECT_EQ(max_write_channel_block(bus, &size, &bits), ERR_OK);
  }
  ~XcanDaemon() { canemu_xcan_connect(nullptr); }
  MAX_HANDLE open(const CPS_XCAN& c, MAX_CALLBACK callback = nullptr) const {
    MAX_HANDLE h = 0;
    EXPECT_EQ(max_open_channel(mdd, &c, callback, &h), ERR_OK);
    return h;
  }
};

}  // namespace canemu::testing
