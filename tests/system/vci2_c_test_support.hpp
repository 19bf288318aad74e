// What the tests of the VCI "2" C API (libvcinpl2: CANMSG2, CANBTP) share: CAN FD adapters
// opened as a VCI program opens them, messages and their time on the wire at 500 kbit/s /
// 2 Mbit/s.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "canemu/firmware_model/adapters/ixxat/btp.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "vci_test_support.hpp"
#include "vcinpl2.h"
// after vcinpl2.h
#include "vci_c_common_support.hpp"

namespace canemu::testing {

// Two CAN FD adapters, alpha and beta, on the FD bus fd0 (500 kbit/s, 2 Mbit/s in the data
// phase), and a classic one, gamma, on the classic bus can0 (500 kbit/s).
inline const std::string kFdAdapters =
    "[[bus]]\nname = \"fd0\"\nkind = \"can-fd\"\nbitrate = 500000\ndata_bitrate = 2000000\n\n"
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n\n"
    "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can-fd\"\ncontrollers = [\"fd0\"]\n\n"
    "[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n";

inline constexpr UINT8 kMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED | CAN_OPMODE_ERRFRAME;
inline constexpr UINT8 kFd = CAN_EXMODE_EXTDATA | CAN_EXMODE_FASTDATA;
inline constexpr CANBTP btp(UINT32 bps, UINT16 ts1, UINT16 ts2) {
  return CANBTP{0, bps, ts1, ts2, 1, 0};
}
inline constexpr CANBTP kNominal = btp(500000, 14, 2);  // 16 quanta of 80 MHz / 10, 87.5 %
inline constexpr CANBTP kData = btp(2000000, 8, 2);     // 10 quanta, 80 %

// The adapter named `name`, opened.
inline HANDLE device_named(const std::string& name) {
  HANDLE dev = nullptr;
  EXPECT_EQ(vciDeviceOpen(id_of(name), &dev), VCI_OK);
  return dev;
}

// Initializes `control`'s line for classic frames alone (CAN_EXMODE_DISABLED) with `mode` at
// `sdr`, both filters inclusive with 2048 entries.
inline HRESULT init_classic(HANDLE control, CANBTP sdr, UINT8 mode = kMode) {
  return canControlInitialize(control, mode, CAN_EXMODE_DISABLED, CAN_FILTER_INCL, CAN_FILTER_INCL,
                              2048, 2048, &sdr, nullptr);
}

// A controller opened as a program opens it: device, control unit, one PASS channel
// (activated unless told otherwise), the line initialized with `mode`, `ex_mode` and the
// timings (`fdr` given only with an extended mode) and started if asked.
struct Line : ControllerHandles {
  Line(const std::string& name, UINT8 mode, UINT8 ex_mode, CANBTP sdr, CANBTP fdr,
       bool start = true, bool activate = true) {
    device = device_named(name);
    EXPECT_EQ(canControlOpen(device, 0, &control), VCI_OK);
    EXPECT_EQ(canChannelOpen(device, 0, FALSE, &channel), VCI_OK);
    EXPECT_EQ(canChannelInitialize(channel, 256, 1, 64, 1, 0, CAN_FILTER_PASS), VCI_OK);
    if (activate) {
      EXPECT_EQ(canChannelActivate(channel, TRUE), VCI_OK);
    }
    init(mode, ex_mode, sdr, ex_mode != CAN_EXMODE_DISABLED ? &fdr : nullptr);
    if (start) {
      EXPECT_EQ(canControlStart(control, TRUE), VCI_OK);
    }
  }
  HRESULT init(UINT8 mode, UINT8 ex_mode, CANBTP sdr, const CANBTP* fdr) const {
    CANBTP f = fdr != nullptr ? *fdr : CANBTP{};
    const HRESULT hr =
        canControlInitialize(control, mode, ex_mode, CAN_FILTER_INCL, CAN_FILTER_INCL, 2048, 2048,
                             &sdr, fdr != nullptr ? &f : nullptr);
    EXPECT_EQ(hr, VCI_OK);
    return hr;
  }
  void post(const CANMSG2& m) const {
    CANMSG2 copy = m;
    ASSERT_EQ(canChannelPostMessage(channel, &copy), VCI_OK);
  }
  // The messages of `type` among what arrived.
  std::vector<CANMSG2> drain(UINT8 type) const {
    std::vector<CANMSG2> got;
    for (const CANMSG2& m : testing::drain(channel, false)) {
      if (m.uMsgInfo.Bytes.bType == type) {
        got.push_back(m);
      }
    }
    return got;
  }
  UINT32 line_status() const {
    CANLINESTATUS2 s{};
    EXPECT_EQ(canControlGetStatus(control, &s), VCI_OK);
    return s.dwStatus;
  }
};

// An FD adapter's line at 500 kbit/s / 2 Mbit/s (kNominal, kData) with `ex_mode`.
struct FdAdapter : Line {
  explicit FdAdapter(const std::string& name, bool start = true, UINT8 ex_mode = kFd,
                     bool activate = true)
      : Line(name, kMode, ex_mode, kNominal, kData, start, activate) {}
  // Initializes the line again with `ex_mode` (the data timing given whatever the mode).
  HRESULT init(UINT8 ex_mode) const { return Line::init(kMode, ex_mode, kNominal, &kData); }
};

inline CANMSG2 msg(uint32_t id, const std::vector<uint8_t>& bytes, bool fd = false,
                   bool brs = false) {
  CANMSG2 m{};
  m.dwMsgId = id;
  m.uMsgInfo.Bytes.bType = CAN_MSGTYPE_DATA;
  m.uMsgInfo.Bits.dlc = *model::length_to_dlc(bytes.size(), fd) & 0x0FU;
  m.uMsgInfo.Bits.edl = fd ? 1 : 0;
  m.uMsgInfo.Bits.fdr = brs ? 1 : 0;
  if (!bytes.empty()) {
    std::memcpy(m.abData, bytes.data(), bytes.size());
  }
  return m;
}

// The bit timing that `b` gives in `range` and `phase`.
inline model::BitTiming fd_timing(const CANBTP& b, const model::ixxat::BtpRange& range,
                                  model::ixxat::Phase phase) {
  return *model::ixxat::decode_btp({b.dwMode, b.dwBPS, b.wTS1, b.wTS2, b.wSJW, b.wTDO}, range,
                                   phase);
}

// The end of a frame started at `start_us`, in ticks of 1 us, at 500 kbit/s / 2 Mbit/s.
inline UINT32 end_of(uint32_t start_us, const model::Frame& f) {
  const auto nominal =
      fd_timing(kNominal, model::ixxat::kFdNominalRange, model::ixxat::Phase::nominal);
  const auto data = fd_timing(kData, model::ixxat::kFdDataRange, model::ixxat::Phase::data);
  return static_cast<UINT32>(
      (start_us * int64_t{1000} + model::frame_duration(model::encode(f), nominal, data).ns()) /
      1000);
}

}  // namespace canemu::testing
