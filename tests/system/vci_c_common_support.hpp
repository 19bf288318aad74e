// What the tests of the two VCI C libraries (libvcinpl and libvcinpl2) share: the functions
// both headers declare alike. Include it after vcinpl.h or vcinpl2.h (a program includes one).
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
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

// The capabilities of the opened device `dev`.
inline VCIDEVICECAPS device_caps(HANDLE dev) {
  VCIDEVICECAPS caps{};
  EXPECT_EQ(vciDeviceGetCaps(dev, &caps), VCI_OK);
  return caps;
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

// A cyclic list's entry and status: CANCYCLICTXMSG and CANSCHEDULERSTATUS through libvcinpl,
// their "2" forms through libvcinpl2.
#ifdef CANEMU_VCI_VCINPL2_H
using CyclicMsg = CANCYCLICTXMSG2;
using SchedulerStatus = CANSCHEDULERSTATUS2;
#else
using CyclicMsg = CANCYCLICTXMSG;
using SchedulerStatus = CANSCHEDULERSTATUS;
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

// The messages of `type` among `msgs`, in order.
inline std::vector<ChannelMsg> of_type(const std::vector<ChannelMsg>& msgs, UINT8 type) {
  std::vector<ChannelMsg> got;
  for (const ChannelMsg& m : msgs) {
    if (m.uMsgInfo.Bytes.bType == type) {
      got.push_back(m);
    }
  }
  return got;
}

// What arrived, by type: the error messages, the status messages and the data frames.
struct ByType {
  std::vector<ChannelMsg> errors;
  std::vector<ChannelMsg> statuses;
  std::vector<ChannelMsg> frames;
};
inline ByType by_type(const std::vector<ChannelMsg>& msgs) {
  return {of_type(msgs, CAN_MSGTYPE_ERROR), of_type(msgs, CAN_MSGTYPE_STATUS),
          of_type(msgs, CAN_MSGTYPE_DATA)};
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

// The control unit of the adapter named `name` and nothing else, closed with the object.
struct ControlUnit : ControllerHandles {
  explicit ControlUnit(const std::string& name) {
    EXPECT_EQ(vciDeviceOpen(id_of(name), &device), VCI_OK);
    EXPECT_EQ(canControlOpen(device, 0, &control), VCI_OK);
  }
};

// A handle that `close` closes with the object; it converts to the handle.
template <auto close>
class OwnedHandle {
 public:
  OwnedHandle() = default;
  OwnedHandle(const OwnedHandle&) = delete;
  OwnedHandle& operator=(const OwnedHandle&) = delete;
  ~OwnedHandle() {
    if (handle_ != nullptr) {
      close(handle_);
    }
  }
  operator HANDLE() const { return handle_; }

 protected:
  HANDLE handle_ = nullptr;
};

// The cyclic transmit list of `device`'s controller, opened as a program opens it.
class CyclicList : public OwnedHandle<canSchedulerClose> {
 public:
  explicit CyclicList(HANDLE device) { EXPECT_EQ(canSchedulerOpen(device, 0, &handle_), VCI_OK); }

  SchedulerStatus status() const {
    SchedulerStatus s{};
    EXPECT_EQ(canSchedulerGetStatus(handle_, &s), VCI_OK);
    return s;
  }

  // Adds `m`, starts it without end and activates the list.
  void send_without_end(CyclicMsg m) const {
    UINT32 index = 99;
    ASSERT_EQ(canSchedulerAddMessage(handle_, &m, &index), VCI_OK);
    ASSERT_EQ(canSchedulerStartMessage(handle_, index, 0), VCI_OK);
    ASSERT_EQ(canSchedulerActivate(handle_, TRUE), VCI_OK);
  }

  // canSchedulerReset stops the task and empties every entry: none can be started after it.
  void expect_reset_empties_it() const {
    ASSERT_EQ(canSchedulerReset(handle_), VCI_OK);
    const SchedulerStatus s = status();
    EXPECT_EQ(s.bTaskStat, CAN_CTXTSK_STAT_STOPPED);
    for (UINT8 stat : s.abMsgStat) {
      EXPECT_EQ(stat, CAN_CTXMSG_STAT_EMPTY);
    }
    EXPECT_EQ(canSchedulerStartMessage(handle_, 0, 0), VCI_E_INVALID_INDEX);
  }
};

// vciGuidToCharA and vciGuidToCharW write kGuid in its braced registry form into `text` and
// `wide` (39 characters; 38 are too few), and vciCharToGuidA and vciCharToGuidW read it back.
inline constexpr GUID kGuid = {
    0x12345678, 0x9ABC, 0xDEF0, {0x01, 0x23, 0x45, 0x67, 0x89, 0xAB, 0xCD, 0xEF}};
inline void expect_guid_text_both_ways(char (&text)[39], wchar_t (&wide)[39]) {
  EXPECT_EQ(vciGuidToCharA(kGuid, text, 38), VCI_E_BUFFER_OVERFLOW);
  ASSERT_EQ(vciGuidToCharA(kGuid, text, 39), VCI_OK);
  EXPECT_STREQ(text, "{12345678-9ABC-DEF0-0123-456789ABCDEF}");
  EXPECT_EQ(vciGuidToCharW(kGuid, wide, 38), VCI_E_BUFFER_OVERFLOW);
  ASSERT_EQ(vciGuidToCharW(kGuid, wide, 39), VCI_OK);
  EXPECT_STREQ(wide, L"{12345678-9ABC-DEF0-0123-456789ABCDEF}");
  GUID back{};
  ASSERT_EQ(vciCharToGuidA(text, &back), VCI_OK);
  EXPECT_EQ(std::memcmp(&back, &kGuid, sizeof kGuid), 0);
  back = GUID{};
  ASSERT_EQ(vciCharToGuidW(wide, &back), VCI_OK);
  EXPECT_EQ(std::memcmp(&back, &kGuid, sizeof kGuid), 0);
}

// The build number both libraries report for canemu's `version` ("1.2.3"): major * 10000 +
// minor * 100 + patch.
inline UINT32 expected_build(const char* version) {
  unsigned major = 0;
  unsigned minor = 0;
  unsigned patch = 0;
  EXPECT_EQ(std::sscanf(version, "%u.%u.%u", &major, &minor, &patch), 3);
  return major * 10000 + minor * 100 + patch;
}

// The version both libraries report: VCI 4.0.0 with canemu's `version` as the build number.
inline void expect_vci_4_0_0(UINT32 major, UINT32 minor, UINT32 revision, UINT32 build,
                             const char* version) {
  EXPECT_EQ(major, 4u);
  EXPECT_EQ(minor, 0u);
  EXPECT_EQ(revision, 0u);
  EXPECT_EQ(build, expected_build(version));
}

}  // namespace canemu::testing
