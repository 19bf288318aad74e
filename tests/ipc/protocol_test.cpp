#include "canemu/ipc/protocol.hpp"

#include <gtest/gtest.h>

namespace canemu::ipc {
namespace {

TEST(ProtocolNames, EachWireValueHasTheNameConfigurationsAndStatusUse) {
  EXPECT_EQ(to_string(WireDeviceModel::ixxat_usb_to_can), "ixxat-usb-to-can");
  EXPECT_EQ(to_string(WireDeviceModel::ixxat_usb_to_can_fd), "ixxat-usb-to-can-fd");
  EXPECT_EQ(to_string(WireDeviceModel::ephemeral), "ephemeral");
  EXPECT_EQ(to_string(WireDeviceModel::sorcus_x_can_2i), "sorcus-x-can-2i");
  EXPECT_EQ(to_string(WireDeviceModel::sorcus_sl_cani), "sorcus-sl-cani");
  EXPECT_EQ(to_string(WireBusKind::can), "can");
  EXPECT_EQ(to_string(WireBusKind::can_fd), "can-fd");
  EXPECT_EQ(to_string(WireBusKind::lin), "lin");
  EXPECT_EQ(to_string(WireTimeMode::realtime), "realtime");
  EXPECT_EQ(to_string(WireTimeMode::scaled), "scaled");
  EXPECT_EQ(to_string(WireTimeMode::stepped), "stepped");
  EXPECT_EQ(to_string(WireFaultState::pending), "pending");
  EXPECT_EQ(to_string(WireFaultState::active), "active");
  EXPECT_EQ(to_string(WireFaultState::done), "done");
  EXPECT_EQ(to_string(WireFaultState::cleared), "cleared");
}

TEST(ProtocolNames, AValueOutsideTheProtocolIsAQuestionMark) {
  EXPECT_EQ(to_string(static_cast<WireDeviceModel>(5)), "?");
  EXPECT_EQ(to_string(static_cast<WireBusKind>(3)), "?");
  EXPECT_EQ(to_string(static_cast<WireTimeMode>(3)), "?");
  EXPECT_EQ(to_string(static_cast<WireFaultState>(4)), "?");
}

}  // namespace
}  // namespace canemu::ipc
