// The control protocol between canemud and its clients: fixed-layout messages over an AF_UNIX
// SOCK_SEQPACKET socket, one message per packet, every one starting with MsgHeader. The
// messages live in protocol_core.hpp (the daemon's own), capture_messages.hpp (recorders and
// bridges), distributed_messages.hpp (other daemons), fault_messages.hpp (fault scenarios),
// vci_messages.hpp and xcan_messages.hpp
// (the personalities); this header gathers them with their message types, the constructor of a
// message and the check of a received one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>

#include "canemu/ipc/can_node_messages.hpp"
#include "canemu/ipc/capture_messages.hpp"
#include "canemu/ipc/distributed_messages.hpp"
#include "canemu/ipc/fault_messages.hpp"
#include "canemu/ipc/lin_node_messages.hpp"
#include "canemu/ipc/protocol_core.hpp"
#include "canemu/ipc/slcan_messages.hpp"
#include "canemu/ipc/timeline_messages.hpp"
#include "canemu/ipc/vci_messages.hpp"
#include "canemu/ipc/xcan_messages.hpp"

namespace canemu::ipc {

// The message type of each struct (and, in protocol.cpp, the size of each type).
template <class T>
inline constexpr MsgType type_of_v = MsgType{};
template <>
inline constexpr MsgType type_of_v<CanNodeRequest> = MsgType::can_node_request;
template <>
inline constexpr MsgType type_of_v<CanNodeReply> = MsgType::can_node_reply;
template <>
inline constexpr MsgType type_of_v<LinNodeRequest> = MsgType::lin_node_request;
template <>
inline constexpr MsgType type_of_v<LinNodeReply> = MsgType::lin_node_reply;
template <>
inline constexpr MsgType type_of_v<TimelineRequest> = MsgType::timeline_request;
template <>
inline constexpr MsgType type_of_v<TimelineReply> = MsgType::timeline_reply;
template <>
inline constexpr MsgType type_of_v<LoadHistoryReply> = MsgType::load_history_reply;
template <>
inline constexpr MsgType type_of_v<Hello> = MsgType::hello;
template <>
inline constexpr MsgType type_of_v<HelloReply> = MsgType::hello_reply;
template <>
inline constexpr MsgType type_of_v<ErrorReply> = MsgType::error_reply;
template <>
inline constexpr MsgType type_of_v<StatusRequest> = MsgType::status_request;
template <>
inline constexpr MsgType type_of_v<StatusReply> = MsgType::status_reply;
template <>
inline constexpr MsgType type_of_v<TimeStepRequest> = MsgType::time_step_request;
template <>
inline constexpr MsgType type_of_v<TimeStepReply> = MsgType::time_step_reply;
template <>
inline constexpr MsgType type_of_v<OpenChannelRequest> = MsgType::open_channel_request;
template <>
inline constexpr MsgType type_of_v<OpenChannelReply> = MsgType::open_channel_reply;
template <>
inline constexpr MsgType type_of_v<CloseChannelRequest> = MsgType::close_channel_request;
template <>
inline constexpr MsgType type_of_v<CloseChannelReply> = MsgType::close_channel_reply;
template <>
inline constexpr MsgType type_of_v<ChannelStatusRequest> = MsgType::channel_status_request;
template <>
inline constexpr MsgType type_of_v<ChannelStatusReply> = MsgType::channel_status_reply;
template <>
inline constexpr MsgType type_of_v<DeviceListRequest> = MsgType::device_list_request;
template <>
inline constexpr MsgType type_of_v<DeviceListReply> = MsgType::device_list_reply;
template <>
inline constexpr MsgType type_of_v<ClientListRequest> = MsgType::client_list_request;
template <>
inline constexpr MsgType type_of_v<ClientListReply> = MsgType::client_list_reply;
template <>
inline constexpr MsgType type_of_v<SubscribeRequest> = MsgType::subscribe_request;
template <>
inline constexpr MsgType type_of_v<SubscribeReply> = MsgType::subscribe_reply;
template <>
inline constexpr MsgType type_of_v<Notification> = MsgType::notification;
template <>
inline constexpr MsgType type_of_v<FaultLoadRequest> = MsgType::fault_load_request;
template <>
inline constexpr MsgType type_of_v<FaultLoadReply> = MsgType::fault_load_reply;
template <>
inline constexpr MsgType type_of_v<FaultListRequest> = MsgType::fault_list_request;
template <>
inline constexpr MsgType type_of_v<FaultListReply> = MsgType::fault_list_reply;
template <>
inline constexpr MsgType type_of_v<FaultClearRequest> = MsgType::fault_clear_request;
template <>
inline constexpr MsgType type_of_v<FaultClearReply> = MsgType::fault_clear_reply;
template <>
inline constexpr MsgType type_of_v<VciRequest> = MsgType::vci_request;
template <>
inline constexpr MsgType type_of_v<VciReply> = MsgType::vci_reply;
template <>
inline constexpr MsgType type_of_v<XcanRequest> = MsgType::xcan_request;
template <>
inline constexpr MsgType type_of_v<XcanReply> = MsgType::xcan_reply;
template <>
inline constexpr MsgType type_of_v<XcanCallbackMsg> = MsgType::xcan_callback;
template <>
inline constexpr MsgType type_of_v<RecorderListRequest> = MsgType::recorder_list_request;
template <>
inline constexpr MsgType type_of_v<RecorderListReply> = MsgType::recorder_list_reply;
template <>
inline constexpr MsgType type_of_v<BridgeAddRequest> = MsgType::bridge_add_request;
template <>
inline constexpr MsgType type_of_v<BridgeAddReply> = MsgType::bridge_add_reply;
template <>
inline constexpr MsgType type_of_v<BridgeRemoveRequest> = MsgType::bridge_remove_request;
template <>
inline constexpr MsgType type_of_v<BridgeRemoveReply> = MsgType::bridge_remove_reply;
template <>
inline constexpr MsgType type_of_v<BridgeRestartRequest> = MsgType::bridge_restart_request;
template <>
inline constexpr MsgType type_of_v<BridgeRestartReply> = MsgType::bridge_restart_reply;
template <>
inline constexpr MsgType type_of_v<BridgeListRequest> = MsgType::bridge_list_request;
template <>
inline constexpr MsgType type_of_v<BridgeListReply> = MsgType::bridge_list_reply;
template <>
inline constexpr MsgType type_of_v<PeerListRequest> = MsgType::peer_list_request;
template <>
inline constexpr MsgType type_of_v<PeerListReply> = MsgType::peer_list_reply;
template <>
inline constexpr MsgType type_of_v<SlcanRequest> = MsgType::slcan_request;
template <>
inline constexpr MsgType type_of_v<SlcanReply> = MsgType::slcan_reply;
template <>
inline constexpr MsgType type_of_v<SlcanEventMsg> = MsgType::slcan_event;
template <class T>
constexpr MsgType type_of() {
  static_assert(type_of_v<T> != MsgType{}, "not a protocol message");
  return type_of_v<T>;
}

// A message of type T with its header filled in.
template <class T>
T make_message(uint32_t request_id = 0) {
  static_assert(std::is_trivially_copyable_v<T>);
  T m{};
  m.header.magic = kMagic;
  m.header.version = kProtocolVersion;
  m.header.type = static_cast<uint16_t>(type_of<T>());
  m.header.size = sizeof(T);
  m.header.request_id = request_id;
  return m;
}

// Checks a received packet's header: magic, version, the size it claims against the bytes that
// came and against the size of its type. ErrorCode::none when it may be read as its type.
ErrorCode check_message(const void* data, std::size_t bytes);

template <std::size_t N>
void copy_name(char (&dst)[N], std::string_view src) {
  const std::size_t n = src.size() < N - 1 ? src.size() : N - 1;
  std::memcpy(dst, src.data(), n);
  std::memset(dst + n, 0, N - n);
}

template <std::size_t N>
std::string name_of(const char (&src)[N]) {
  return std::string(src, strnlen(src, N));
}

// Text a peer chose, as canemud shows it: printable ASCII only, every other byte '?', so that
// no text can break a table, a log line or a terminal.
inline bool is_printable(char c) {
  return c >= 0x20 && c <= 0x7E;
}
inline std::string printable(std::string s) {
  for (char& c : s) {
    if (!is_printable(c)) {
      c = '?';
    }
  }
  return s;
}
// A name a peer chose (a client's name in its Hello), as canemud keeps and shows it.
template <std::size_t N>
std::string printable_name_of(const char (&src)[N]) {
  return printable(name_of(src));
}

}  // namespace canemu::ipc
