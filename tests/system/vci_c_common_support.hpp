// What the tests of the two VCI C libraries (libvcinpl and libvcinpl2) share: the functions
// both headers declare alike. Include it after vcinpl.h or vcinpl2.h (a program includes one).
#pragma once

#include <gtest/gtest.h>

#include <string>

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

}  // namespace canemu::testing
