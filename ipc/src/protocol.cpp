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
  }
  return "unknown";
}

namespace {

std::size_t size_of(MsgType type) {
  switch (type) {
    case MsgType::hello:
      return sizeof(Hello);
    case MsgType::hello_reply:
      return sizeof(HelloReply);
    case MsgType::error_reply:
      return sizeof(ErrorReply);
    case MsgType::status_request:
      return sizeof(StatusRequest);
    case MsgType::status_reply:
      return sizeof(StatusReply);
    case MsgType::time_step_request:
      return sizeof(TimeStepRequest);
    case MsgType::time_step_reply:
      return sizeof(TimeStepReply);
  }
  return 0;
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
