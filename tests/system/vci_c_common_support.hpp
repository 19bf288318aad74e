// What the tests of the two VCI C libraries (libvcinpl and libvcinpl2) share: the functions
// both headers declare alike. Include it after vcinpl.h or vcinpl2.h (a program includes one).
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <cwchar>
#include <string>
#include <vector>

#if !defined(CANEMU_VCI_VCINPL_H) && !defined(CANEMU_VCI_VCINPL2_H)
#error "include vcinpl.h or vcinpl2.h first"
#endif

namespace canemu::testing {

// The VciObjectId of the adapter named `name` (zero if there is none), by enumeration.
inline VCIID id_of(const std::string& name) {
  HANDLE e = nullptr;
  EXPECT_EQ(vciEnumDeviceOpen(&e), VCI_OK);
  VCIDEVICEINFO info{};
  VCIID id{};
  while (vciEnumDeviceNext(e, &info) == VCI_OK) {
    if (std::string(info.Description).find("(canemu " + name + ")") != std::string::npos) {
      id = info.VciObjectId;
    }
  }
  vciEnumDeviceClose(e);
  return id;
}

// vciFormatErrorW gives the text vciFormatErrorA writes into `narrow` (VCI_MAX_ERRSTRLEN
// characters) for VCI_E_TIMEOUT, character for character.
inline void expect_wide_error_text_is_the_narrow_one(char* narrow) {
  wchar_t wide[VCI_MAX_ERRSTRLEN];
  vciFormatErrorA(VCI_E_TIMEOUT, narrow, VCI_MAX_ERRSTRLEN);
  vciFormatErrorW(VCI_E_TIMEOUT, wide, VCI_MAX_ERRSTRLEN);
  ASSERT_GT(std::strlen(narrow), 3u);
  ASSERT_EQ(std::wcslen(wide), std::strlen(narrow));
  for (std::size_t i = 0; narrow[i] != '\0'; ++i) {
    EXPECT_EQ(wide[i], static_cast<wchar_t>(narrow[i])) << i;
  }
}

// The message a channel hands out: CANMSG through libvcinpl, CANMSG2 through libvcinpl2.
#ifdef CANEMU_VCI_VCINPL2_H
using ChannelMsg = CANMSG2;
#else
using ChannelMsg = CANMSG;
#endif

// What `channel` holds, taken out (`data_only`: only the data frames).
inline std::vector<ChannelMsg> drain(HANDLE channel, bool data_only = true) {
  std::vector<ChannelMsg> got;
  ChannelMsg m;
  while (canChannelPeekMessage(channel, &m) == VCI_OK) {
    if (!data_only || m.uMsgInfo.Bytes.bType == CAN_MSGTYPE_DATA) {
      got.push_back(m);
    }
  }
  return got;
}

// A controller's device, control unit and channel as a program holds them, closed with the
// object (channel, control unit, device).
struct ControllerHandles {
  HANDLE device = nullptr;
  HANDLE control = nullptr;
  HANDLE channel = nullptr;
  ControllerHandles() = default;
  ControllerHandles(const ControllerHandles&) = delete;
  ControllerHandles& operator=(const ControllerHandles&) = delete;
  ~ControllerHandles() {
    canChannelClose(channel);
    canControlClose(control);
    vciDeviceClose(device);
  }
};

}  // namespace canemu::testing
