// The VCI requests to canemud, each built in one place for the C APIs (libvcinpl, libvcinpl2)
// and the C++ API (libvciapi): which operation, which flags, which arguments in which slot.
// The APIs check their own arguments and convert their structs; these send and return the
// VCI result (VCI_E_DISCONNECTED with a detail when canemud cannot be reached).
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>

#include "vci_core.hpp"

namespace canemu::client::vci::req {

// Opens an object canemud holds for us (`op`: a control unit, channel, cyclic list, LIN control
// unit or monitor) on controller `controller` of `device`; `handle` gets canemud's handle.
HRESULT open(ipc::VciOp op, uint16_t flags, const DeviceDesc& device, uint32_t controller,
             uint32_t& handle);
// A CAN object (`kind`: control, channel or scheduler) on controller `controller` of
// `device`, for the API version `v2` (CANMSG2, CANBTP) or not, `exclusive` for a channel.
HRESULT open_can(Object::Kind kind, bool v2, bool exclusive, const DeviceDesc& device,
                 uint32_t controller, std::unique_ptr<Remote>& out);

// A call on a remote object with no payload or arguments beyond `args`.
HRESULT simple(const Remote& object, ipc::VciOp op, std::initializer_list<uint32_t> args = {},
               ipc::VciReply* reply = nullptr);

// The line's structures (capabilities, line status at ipc::kVci*Offset in the payload): of the
// controller an object is on, or of controller `controller` of `device` with no object open.
HRESULT line_info(const Remote& object, ipc::VciReply& reply);
HRESULT line_info(const DeviceDesc& device, uint32_t controller, ipc::VciReply& reply);

// Filter calls (`op` control_filter or channel_filter): `kind` one of kFilter*; `mode_out`
// (may be null) gets the mode canemud reports.
inline constexpr uint32_t kFilterGetMode = 0;
inline constexpr uint32_t kFilterSetMode = 1;
inline constexpr uint32_t kFilterAcceptance = 2;
inline constexpr uint32_t kFilterAddIds = 3;
inline constexpr uint32_t kFilterRemoveIds = 4;
HRESULT filter(const Remote& object, ipc::VciOp op, uint32_t kind, bool extended, uint8_t mode,
               uint32_t code, uint32_t mask, uint8_t* mode_out);

// Initializes a control unit's line with `init` (CANINITLINE, or with `v2` CANINITLINE2).
HRESULT init_line(const Remote& control, const void* init, std::size_t size, bool v2);

// Bit-rate detection on a control unit: starts it with `table` (CANBTRTABLE, or with `v2`
// CANBTPTABLE) and waits for its end, asking canemud every millisecond (without holding the
// connection, so that another thread may step time meanwhile). `index` gets the entry found.
HRESULT detect(const Remote& control, bool v2, const void* table, std::size_t size,
               uint16_t timeout_ms, uint8_t op_mode, uint8_t ex_mode, uint32_t& index);

// Adds `msg` to a cyclic list; `index` (may be null) gets its index, 0xFFFFFFFF on failure.
HRESULT scheduler_add(const Remote& list, const CANCYCLICTXMSG2& msg, PUINT32 index);

// Initializes a channel's FIFOs and maps its rings (`tx` 0: none).
HRESULT init_channel(ChannelObj& channel, uint32_t rx, uint32_t rx_threshold, uint32_t tx,
                     uint32_t tx_threshold, uint32_t filter_size, uint8_t filter_mode);
// A LIN monitor's receive FIFO of at least `rx` LINMSGs.
HRESULT init_lin_monitor(ChannelObj& monitor, uint32_t rx, uint32_t rx_threshold);

}  // namespace canemu::client::vci::req
