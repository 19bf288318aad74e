#include "canemu/ipc/protocol.hpp"

namespace canemu::ipc {

std::string_view to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::none:
      return "none";
    case ErrorCode::bad_magic:
      return "bad_magic";
    case ErrorCode::bad_version:
      return "bad_version";
    case ErrorCode::bad_size:
      return "bad_size";
    case ErrorCode::unknown_type:
      return "unknown_type";
    case ErrorCode::not_hello:
      return "not_hello";
    case ErrorCode::not_stepped:
      return "not_stepped";
    case ErrorCode::bad_argument:
      return "bad_argument";
    case ErrorCode::permission_denied:
      return "permission_denied";
    case ErrorCode::no_such_bus:
      return "no_such_bus";
    case ErrorCode::no_such_channel:
      return "no_such_channel";
    case ErrorCode::name_in_use:
      return "name_in_use";
    case ErrorCode::bad_bit_timing:
      return "bad_bit_timing";
    case ErrorCode::no_resources:
      return "no_resources";
    case ErrorCode::bad_scenario:
      return "bad_scenario";
  }
  return "unknown";
}

namespace {

template <class... T>
std::size_t size_among(MsgType type) {
  std::size_t size = 0;
  ((type == type_of<T>() ? size = sizeof(T) : 0), ...);
  return size;
}

std::size_t size_of(MsgType type) {
  return size_among<
      Hello, HelloReply, ErrorReply, StatusRequest, StatusReply, TimeStepRequest, TimeStepReply,
      OpenChannelRequest, OpenChannelReply, CloseChannelRequest, CloseChannelReply,
      ChannelStatusRequest, ChannelStatusReply, DeviceListRequest, DeviceListReply,
      ClientListRequest, ClientListReply, SubscribeRequest, SubscribeReply, Notification,
      FaultLoadRequest, FaultLoadReply, FaultListRequest, FaultListReply, FaultClearRequest,
      FaultClearReply, VciRequest, VciReply, XcanRequest, XcanReply, XcanCallbackMsg,
      RecorderListRequest, RecorderListReply, BridgeAddRequest, BridgeAddReply, BridgeRemoveRequest,
      BridgeRemoveReply, BridgeRestartRequest, BridgeRestartReply, BridgeListRequest,
      BridgeListReply, SlcanRequest, SlcanReply, SlcanEventMsg, TimelineRequest, TimelineReply,
      LinNodeRequest, LinNodeReply, CanNodeRequest, CanNodeReply, LoadHistoryReply, PeerListRequest,
      PeerListReply>(type);
}

}  // namespace

ErrorCode check_message(const void* data, std::size_t bytes) {
  if (bytes < sizeof(MsgHeader)) {
    return ErrorCode::bad_size;
  }
  MsgHeader h;
  std::memcpy(&h, data, sizeof h);
  if (h.magic != kMagic) {
    return ErrorCode::bad_magic;
  }
  if (h.version != kProtocolVersion) {
    return ErrorCode::bad_version;
  }
  const std::size_t expected = size_of(static_cast<MsgType>(h.type));
  if (expected == 0) {
    return ErrorCode::unknown_type;
  }
  if (h.size != bytes || bytes != expected) {
    return ErrorCode::bad_size;
  }
  return ErrorCode::none;
}

}  // namespace canemu::ipc
