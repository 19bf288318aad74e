// What the LIN tests of the classic VCI C API (libvcinpl) share: an adapter's LIN controller
// opened as a VCI program opens it.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "vci_c_test_support.hpp"
#include "vci_lin_test_support.hpp"

namespace canemu::testing {

// An adapter's LIN controller opened as a VCI program opens it: control unit and one monitor
// (FIFO `fifo`, active), initialized with `mode` at 19200 bit/s and started.
struct LinAdapter {
  HANDLE device = nullptr;
  HANDLE control = nullptr;
  HANDLE monitor = nullptr;
  explicit LinAdapter(const std::string& name, UINT8 mode = LIN_OPMODE_SLAVE, bool start = true,
                      UINT16 fifo = 64) {
    EXPECT_EQ(vciDeviceOpen(id_of(name), &device), VCI_OK);
    EXPECT_EQ(linControlOpen(device, kLinNo, &control), VCI_OK);
    EXPECT_EQ(linMonitorOpen(device, kLinNo, FALSE, &monitor), VCI_OK);
    EXPECT_EQ(linMonitorInitialize(monitor, fifo, 1), VCI_OK);
    EXPECT_EQ(linMonitorActivate(monitor, TRUE), VCI_OK);
    EXPECT_EQ(linControlInitialize(control, mode, kRate), VCI_OK);
    if (start) {
      EXPECT_EQ(linControlStart(control, TRUE), VCI_OK);
    }
  }
  ~LinAdapter() {
    linMonitorClose(monitor);
    linControlClose(control);
    vciDeviceClose(device);
  }
  std::vector<LINMSG> drain() const {
    return drain_with([this](LINMSG& m) { return linMonitorPeekMessage(monitor, &m) == VCI_OK; });
  }
  std::vector<std::string> texts() const { return texts_but_start(drain()); }
  HRESULT write(bool send, LINMSG m) const { return linControlWriteMessage(control, send, &m); }
  HRESULT write_null(bool send) const { return linControlWriteMessage(control, send, nullptr); }
  HRESULT stop() const { return linControlStart(control, FALSE); }
};

using Texts = std::vector<std::string>;

}  // namespace canemu::testing
