// The classic VCI C API (libvcinpl), the functions that do not depend on the bus: version,
// error texts (A and W), identifiers as text, event objects, and the device "dialogs" that
// choose without a dialog on Linux.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <cwchar>
#include <iterator>
#include <set>
#include <string>
#include <thread>

#include <unistd.h>

#include "vci_c_test_support.hpp"
#include "vcinpl.h"

namespace canemu {
namespace {

using testing::id_of;
using testing::VciDaemon;

TEST(VciCApiGeneral, TheVersionIsVci4WithCanemusVersionAsBuildNumber) {
  UINT32 major = 0;
  UINT32 minor = 99;
  ASSERT_EQ(vciGetVersion(&major, &minor), VCI_OK);
  EXPECT_EQ(major, 4u);
  EXPECT_EQ(minor, 0u);
  UINT32 revision = 99;
  UINT32 build = 0;
  ASSERT_EQ(vciGetVersionEx(&major, &minor, &revision, &build), VCI_OK);
  testing::expect_vci_4_0_0(major, minor, revision, build, CANEMU_PROJECT_VERSION);
  EXPECT_EQ(vciGetVersion(&major, nullptr), VCI_E_INVALIDARG);
  EXPECT_EQ(vciGetVersionEx(&major, &minor, &revision, nullptr), VCI_E_INVALIDARG);
}

TEST(VciCApiGeneral, ALuidIsSixteenHexDigitsBothWays) {
  VCIID id{};
  id.AsInt64 = 0x0123456789ABCDEF;
  char text[17];
  EXPECT_EQ(vciLuidToCharA(id, text, 16), VCI_E_BUFFER_OVERFLOW);
  EXPECT_EQ(vciLuidToCharA(id, nullptr, 17), VCI_E_INVALIDARG);
  EXPECT_EQ(vciLuidToCharA(id, text, 0), VCI_E_INVALIDARG);
  ASSERT_EQ(vciLuidToCharA(id, text, 17), VCI_OK);
  EXPECT_STREQ(text, "0123456789ABCDEF");
  std::memset(text, 0, sizeof text);
  ASSERT_EQ(vciLuidToChar(id, text, sizeof text), VCI_OK);  // the plain name: the A form
  EXPECT_STREQ(text, "0123456789ABCDEF");
  wchar_t wide[17];
  EXPECT_EQ(vciLuidToCharW(id, wide, 16), VCI_E_BUFFER_OVERFLOW);  // sizes count characters
  ASSERT_EQ(vciLuidToCharW(id, wide, 17), VCI_OK);
  EXPECT_STREQ(wide, L"0123456789ABCDEF");

  VCIID back{};
  ASSERT_EQ(vciCharToLuidA(text, &back), VCI_OK);
  EXPECT_EQ(back.AsInt64, id.AsInt64);
  EXPECT_EQ(back.AsLuid.LowPart, 0x89ABCDEFu);
  EXPECT_EQ(back.AsLuid.HighPart, 0x01234567);
  back = VCIID{};
  ASSERT_EQ(vciCharToLuidW(wide, &back), VCI_OK);
  EXPECT_EQ(back.AsInt64, id.AsInt64);
  char lower[] = "fedcba9876543210";
  ASSERT_EQ(vciCharToLuid(lower, &back), VCI_OK);
  EXPECT_EQ(static_cast<UINT64>(back.AsInt64), 0xFEDCBA9876543210u);
  char bad_digit[] = "0123456789ABCDEG";
  char short_text[] = "0123456789ABCDE";
  char long_text[] = "0123456789ABCDEF0";
  EXPECT_EQ(vciCharToLuidA(bad_digit, &back), VCI_E_FAIL);
  EXPECT_EQ(vciCharToLuidA(short_text, &back), VCI_E_FAIL);
  EXPECT_EQ(vciCharToLuidA(long_text, &back), VCI_E_FAIL);
  wchar_t not_ascii[] = L"0123456789ABCDE\u0660";  // an Arabic-Indic digit zero
  EXPECT_EQ(vciCharToLuidW(not_ascii, &back), VCI_E_FAIL);
  EXPECT_EQ(vciCharToLuidA(nullptr, &back), VCI_E_INVALIDARG);
  EXPECT_EQ(vciCharToLuidA(text, nullptr), VCI_E_INVALIDARG);
}

TEST(VciCApiGeneral, NewLuidsAreDistinctAndCarryTheProcessId) {
  VCIID a{};
  VCIID b{};
  ASSERT_EQ(vciCreateLuid(&a), VCI_OK);
  ASSERT_EQ(vciCreateLuid(&b), VCI_OK);
  EXPECT_NE(a.AsInt64, b.AsInt64);
  EXPECT_EQ(a.AsLuid.HighPart, static_cast<INT32>(::getpid()));
  EXPECT_EQ(b.AsLuid.LowPart, a.AsLuid.LowPart + 1);
  EXPECT_EQ(vciCreateLuid(nullptr), VCI_E_INVALIDARG);
}

TEST(VciCApiGeneral, ADevicesVciidSurvivesTheTripThroughText) {
  VciDaemon d;
  const VCIID id = id_of("beta");
  char text[32];
  ASSERT_EQ(vciLuidToChar(id, text, sizeof text), VCI_OK);
  VCIID back{};
  ASSERT_EQ(vciCharToLuid(text, &back), VCI_OK);
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(back, &dev), VCI_OK);
  VCIDEVICEINFO info{};
  ASSERT_EQ(vciDeviceGetInfo(dev, &info), VCI_OK);
  EXPECT_NE(std::string(info.Description).find("(canemu beta)"), std::string::npos);
  EXPECT_EQ(vciDeviceClose(dev), VCI_OK);
}

TEST(VciCApiGeneral, AGuidIsTheBracedRegistryForm) {
  const GUID g = testing::kGuid;
  char text[39];
  wchar_t wide[39];
  ASSERT_NO_FATAL_FAILURE(testing::expect_guid_text_both_ways(text, wide));
  ASSERT_EQ(vciGuidToChar(g, text, sizeof text), VCI_OK);  // the form without A or W
  EXPECT_STREQ(text, "{12345678-9ABC-DEF0-0123-456789ABCDEF}");

  GUID back{};
  // IUnknown's well-known identifier, in lower case.
  char unknown[] = "{00000000-0000-0000-c000-000000000046}";
  ASSERT_EQ(vciCharToGuid(unknown, &back), VCI_OK);
  EXPECT_EQ(back.Data1, 0u);
  EXPECT_EQ(back.Data4[0], 0xC0);
  EXPECT_EQ(back.Data4[7], 0x46);
  char unbraced[] = "12345678-9ABC-DEF0-0123-456789ABCDEF";
  char misplaced_dash[] = "{12345678-9ABCD-EF0-0123-456789ABCDEF}";
  EXPECT_EQ(vciCharToGuidA(unbraced, &back), VCI_E_FAIL);
  EXPECT_EQ(vciCharToGuidA(misplaced_dash, &back), VCI_E_FAIL);
  EXPECT_EQ(vciCharToGuidA(nullptr, &back), VCI_E_INVALIDARG);
  EXPECT_EQ(vciGuidToCharW(g, nullptr, 39), VCI_E_INVALIDARG);
}

TEST(VciCApiGeneral, TheWideErrorTextIsTheNarrowOneTruncatedAlike) {
  char narrow[VCI_MAX_ERRSTRLEN];
  ASSERT_NO_FATAL_FAILURE(testing::expect_wide_error_text_is_the_narrow_one(narrow));
  wchar_t small[4] = {L'x', L'x', L'x', L'x'};
  vciFormatErrorW(VCI_E_TIMEOUT, small, 4);
  EXPECT_EQ(std::wcslen(small), 3u);
  EXPECT_EQ(small[0], static_cast<wchar_t>(narrow[0]));
  vciFormatErrorW(VCI_E_TIMEOUT, nullptr, 4);  // nothing happens
  small[0] = L'x';
  vciFormatErrorW(VCI_E_TIMEOUT, small, 0);
  EXPECT_EQ(small[0], L'x');
}

TEST(VciCApiGeneral, EveryCodeOfVcierrHasItsOwnText) {
  const HRESULT later[] = {
      VCI_E_INVALID_LICENSE,        VCI_E_NO_SUCH_LICENSE,      VCI_E_LICENSE_EXPIRED,
      VCI_E_LICENSE_QUOTA_EXCEEDED, VCI_E_INVALID_TIMING,       VCI_E_IN_USE,
      VCI_E_NO_SUCH_DEVICE,         VCI_E_DEVICE_NOT_CONNECTED, VCI_E_DEVICE_NOT_READY,
      VCI_E_TYPE_MISMATCH,          VCI_E_NOT_SUPPORTED,        VCI_E_DUPLICATE_OBJECTID,
      VCI_E_OBJECTID_NOT_FOUND,     VCI_E_WRONG_LEVEL,          VCI_E_WRONG_DRV_VERSION,
      VCI_E_LUIDS_EXHAUSTED};
  std::set<std::string> texts;
  for (const HRESULT hr : later) {
    char text[VCI_MAX_ERRSTRLEN];
    vciFormatError(hr, text, sizeof text);
    EXPECT_EQ(std::string(text).find("unknown error"), std::string::npos) << text;
    texts.insert(text);
  }
  EXPECT_EQ(texts.size(), std::size(later));
}

TEST(VciCApiGeneral, DisplayErrorWritesOneLineToStandardError) {
  char text[VCI_MAX_ERRSTRLEN];
  vciFormatError(VCI_E_INVHANDLE, text, sizeof text);
  char caption[] = "my program";
  ::testing::internal::CaptureStderr();
  vciDisplayErrorA(nullptr, caption, VCI_E_INVHANDLE);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), std::string("my program: ") + text + "\n");
  ::testing::internal::CaptureStderr();
  vciDisplayError(nullptr, nullptr, VCI_E_INVHANDLE);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), std::string(text) + "\n");
  wchar_t wide_caption[] = L"Gr\u00fc\u00dfe";  // written as UTF-8
  ::testing::internal::CaptureStderr();
  vciDisplayErrorW(nullptr, wide_caption, VCI_E_INVHANDLE);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), std::string("Gr\xc3\xbc\xc3\x9f"
                                                                  "e: ") +
                                                          text + "\n");
}

using Clock = std::chrono::steady_clock;

TEST(VciCApiGeneral, AnAutoResetEventIsTakenByTheWaitItEnds) {
  HANDLE e = nullptr;
  ASSERT_EQ(vciEventCreate(FALSE, FALSE, &e), VCI_OK);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);
  const auto start = Clock::now();
  EXPECT_EQ(vciEventWaitFor(e, 50), VCI_E_TIMEOUT);
  EXPECT_GE(Clock::now() - start, std::chrono::milliseconds(50));
  ASSERT_EQ(vciEventSignal(e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);  // reset by the wait
  ASSERT_EQ(vciEventSignal(e), VCI_OK);
  ASSERT_EQ(vciEventReset(e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);
  // Another thread waits without limit; the signal ends its wait whenever it comes.
  std::atomic<HRESULT> waited{VCI_E_UNEXPECTED};
  std::thread waiter([&] { waited = vciEventWaitFor(e, INFINITE); });
  ASSERT_EQ(vciEventSignal(e), VCI_OK);
  waiter.join();
  EXPECT_EQ(waited.load(), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);
  ASSERT_EQ(vciEventDelete(e), VCI_OK);
  EXPECT_EQ(vciEventSignal(e), VCI_E_INVHANDLE);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_INVHANDLE);
  EXPECT_EQ(vciEventDelete(e), VCI_E_INVHANDLE);
}

TEST(VciCApiGeneral, AManualResetEventStaysSignalledUntilReset) {
  HANDLE e = nullptr;
  ASSERT_EQ(vciEventCreate(TRUE, TRUE, &e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 1000), VCI_OK);
  ASSERT_EQ(vciEventReset(e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);
  const auto start = Clock::now();
  EXPECT_EQ(vciEventWaitFor(e, 20), VCI_E_TIMEOUT);
  EXPECT_GE(Clock::now() - start, std::chrono::milliseconds(20));
  ASSERT_EQ(vciEventSignal(e), VCI_OK);
  ASSERT_EQ(vciEventSignal(e), VCI_OK);  // twice is once
  ASSERT_EQ(vciEventReset(e), VCI_OK);
  EXPECT_EQ(vciEventWaitFor(e, 0), VCI_E_TIMEOUT);
  EXPECT_EQ(vciEventDelete(e), VCI_OK);
  EXPECT_EQ(vciEventCreate(TRUE, FALSE, nullptr), VCI_E_INVALIDARG);
}

TEST(VciCApiGeneral, AnEventCallRefusesAHandleThatIsNotAnEvent) {
  VciDaemon d;
  HANDLE dev = nullptr;
  ASSERT_EQ(vciDeviceOpen(id_of("alpha"), &dev), VCI_OK);
  EXPECT_EQ(vciEventSignal(dev), VCI_E_INVHANDLE);
  EXPECT_EQ(vciEventWaitFor(dev, 0), VCI_E_INVHANDLE);
  EXPECT_EQ(vciEventDelete(dev), VCI_E_INVHANDLE);
  EXPECT_EQ(vciDeviceClose(dev), VCI_OK);
  HANDLE e = nullptr;
  ASSERT_EQ(vciEventCreate(FALSE, FALSE, &e), VCI_OK);
  EXPECT_EQ(vciDeviceClose(e), VCI_E_INVHANDLE);
  EXPECT_EQ(vciEventDelete(e), VCI_OK);
}

// Sets CANEMU_VCI_DEVICE for the scope (unset when `value` is null).
class DeviceChoice {
 public:
  explicit DeviceChoice(const char* value) {
    if (value != nullptr) {
      ::setenv("CANEMU_VCI_DEVICE", value, 1);
    } else {
      ::unsetenv("CANEMU_VCI_DEVICE");
    }
  }
  ~DeviceChoice() { ::unsetenv("CANEMU_VCI_DEVICE"); }
};

TEST(VciCApiGeneral, TheDialogsChooseTheFirstDeviceOrTheOneTheEnvironmentNames) {
  VciDaemon d;
  VCIID id{};
  {
    DeviceChoice none(nullptr);
    ASSERT_EQ(vciSelectDeviceDlg(nullptr, &id), VCI_OK);
    EXPECT_EQ(id.AsInt64, id_of("alpha").AsInt64);  // the first of the enumeration
    EXPECT_EQ(vciSelectDeviceDlg(nullptr, nullptr), VCI_E_INVALIDARG);
  }
  {
    DeviceChoice beta("beta");
    ASSERT_EQ(vciSelectDeviceDlg(nullptr, &id), VCI_OK);
    EXPECT_EQ(id.AsInt64, id_of("beta").AsInt64);
    HANDLE dev = nullptr;
    ASSERT_EQ(vciDeviceOpenDlg(nullptr, &dev), VCI_OK);
    VCIDEVICEINFO info{};
    ASSERT_EQ(vciDeviceGetInfo(dev, &info), VCI_OK);
    EXPECT_EQ(info.VciObjectId.AsInt64, id_of("beta").AsInt64);
    HANDLE control = nullptr;
    EXPECT_EQ(canControlOpen(dev, 0, &control), VCI_OK);  // an ordinary device handle
    EXPECT_EQ(canControlClose(control), VCI_OK);
    EXPECT_EQ(vciDeviceClose(dev), VCI_OK);
  }
  {
    char text[17];
    ASSERT_EQ(vciLuidToChar(id_of("beta"), text, sizeof text), VCI_OK);
    DeviceChoice by_id(text);
    ASSERT_EQ(vciSelectDeviceDlg(nullptr, &id), VCI_OK);
    EXPECT_EQ(id.AsInt64, id_of("beta").AsInt64);
  }
  {
    DeviceChoice nobody("nobody");
    id.AsInt64 = 42;
    EXPECT_EQ(vciSelectDeviceDlg(nullptr, &id), VCI_E_NO_MORE_ITEMS);
    EXPECT_EQ(id.AsInt64, 42);
    HANDLE dev = &id;
    EXPECT_EQ(vciDeviceOpenDlg(nullptr, &dev), VCI_E_NO_MORE_ITEMS);
    EXPECT_EQ(dev, nullptr);
    char text[VCI_MAX_ERRSTRLEN];
    vciFormatError(VCI_E_NO_MORE_ITEMS, text, sizeof text);
    EXPECT_NE(std::string(text).find("\"nobody\""), std::string::npos) << text;
  }
}

TEST(VciCApiGeneral, WithoutCanemudTheDialogsFailAtOnce) {
  EXPECT_EQ(canemuConnect("/nonexistent/canemud.sock"), VCI_E_DISCONNECTED);
  VCIID id{};
  EXPECT_EQ(vciSelectDeviceDlg(nullptr, &id), VCI_E_DISCONNECTED);
  HANDLE dev = nullptr;
  EXPECT_EQ(vciDeviceOpenDlg(nullptr, &dev), VCI_E_DISCONNECTED);
  EXPECT_EQ(dev, nullptr);
  canemuConnect(nullptr);
}

}  // namespace
}  // namespace canemu
