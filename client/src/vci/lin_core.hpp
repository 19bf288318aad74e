// The LIN objects of the VCI C and C++ APIs (control unit, monitor, the socket's view), as
// calls to canemud. A monitor is a ChannelObj of kind lin_monitor: its FIFO is read by the
// channel data path (vci_core.hpp channel_peek, channel_read, ...).
#pragma once

#include <memory>

#include "requests.hpp"
#include "vci_core.hpp"

namespace canemu::client::vci {

// Whether `bus_no` is a LIN controller of `device` (numbered after its CAN controllers).
bool is_lin_controller(const DeviceDesc& device, uint32_t bus_no);

// Opens the control unit (Kind::lin_control) or a monitor (Kind::lin_monitor, a ChannelObj) of
// LIN controller `bus_no`. VCI_E_INVALIDARG when it is not one.
HRESULT lin_open(const DeviceDesc& device, uint32_t bus_no, Object::Kind kind, bool exclusive,
                 std::unique_ptr<Remote>& out);

// Capabilities and line status (either may be null) through `object`, or with `object` null
// through the socket's view of controller `bus_no` of `device`.
HRESULT lin_info(const DeviceDesc& device, uint32_t bus_no, const Remote* object,
                 LINCAPABILITIES* caps, LINLINESTATUS* status);

HRESULT lin_init(const Remote& control, uint8_t op_mode, uint16_t bitrate);
HRESULT lin_write(const Remote& control, bool send, const LINMSG* msg);
HRESULT lin_monitor_activate(const Remote& monitor, bool enable);
HRESULT lin_monitor_status(ChannelObj& monitor, LINMONITORSTATUS* out);

}  // namespace canemu::client::vci
