// The control protocol between canemud and its clients: fixed-layout messages over an AF_UNIX
// SOCK_SEQPACKET socket, one message per packet, every one starting with MsgHeader.
//
// Layouts are part of the ABI: sizes are checked with static_assert, integers are the host's
// (both ends are on one machine), strings are NUL-padded fixed arrays. A client says Hello
// first; the daemon answers HelloReply or ErrorReply. Every other request gets its reply type or
// ErrorReply with the same request_id.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>

namespace canemu::ipc {

inline constexpr uint32_t kMagic = 0x454E4143;  // "CANE" in memory on little-endian machines
inline constexpr uint16_t kProtocolVersion = 1;
inline constexpr std::size_t kMaxMessageSize = 16384;
inline constexpr std::size_t kNameSize = 32;
inline constexpr std::size_t kMaxStatusBuses = 16;
inline constexpr std::size_t kMaxStatusNodes = 64;

enum class MsgType : uint16_t {
  hello = 1,
  hello_reply = 2,
  error_reply = 3,
  status_request = 10,
  status_reply = 11,
  time_step_request = 20,
  time_step_reply = 21,
};

// Why a request failed. Values are stable: clients show them by name.
enum class ErrorCode : uint32_t {
  none = 0,
  bad_magic = 1,
  bad_version = 2,
  bad_size = 3,
  unknown_type = 4,
  not_hello = 5,    // a request before the handshake
  not_stepped = 6,  // time step outside stepped mode
  bad_argument = 7,
  permission_denied = 8,
};
std::string_view to_string(ErrorCode code);

struct MsgHeader {
  uint32_t magic = kMagic;
  uint16_t version = kProtocolVersion;
  uint16_t type = 0;
  uint32_t size = 0;        // of the whole message, header included
  uint32_t request_id = 0;  // echoed in the reply
};
static_assert(sizeof(MsgHeader) == 16);

struct Hello {
  MsgHeader header;
  uint32_t client_pid = 0;
  char client_name[kNameSize] = {};
};
static_assert(sizeof(Hello) == 52);

struct HelloReply {
  MsgHeader header;
  uint32_t server_pid = 0;
  uint16_t server_version = kProtocolVersion;
  uint16_t reserved = 0;
};
static_assert(sizeof(HelloReply) == 24);

struct ErrorReply {
  MsgHeader header;
  uint32_t code = 0;  // ErrorCode
  char message[96] = {};
};
static_assert(sizeof(ErrorReply) == 116);

struct StatusRequest {
  MsgHeader header;
};

enum class WireTimeMode : uint8_t { realtime = 0, scaled = 1, stepped = 2 };
enum class WireBusKind : uint8_t { can = 0, can_fd = 1, lin = 2 };
enum class WireErrorState : uint8_t { active = 0, warning = 1, passive = 2, bus_off = 3 };

struct StatusBus {
  char name[kNameSize] = {};
  uint8_t kind = 0;  // WireBusKind
  uint8_t reserved[3] = {};
  uint32_t bitrate = 0;
  uint32_t data_bitrate = 0;
  uint32_t load_permille = 0;  // over the last second
  uint64_t frames = 0;
  uint64_t error_frames = 0;
};
static_assert(sizeof(StatusBus) == 64);

struct StatusNode {
  char name[kNameSize] = {};  // "device:N"
  uint16_t bus = 0;           // index into the reply's buses
  uint8_t state = 0;          // WireErrorState
  uint8_t reserved = 0;
  uint16_t tec = 0;
  uint16_t rec = 0;
  uint64_t frames_sent = 0;
  uint64_t frames_received = 0;
  uint64_t errors = 0;
};
static_assert(sizeof(StatusNode) == 64);

struct StatusReply {
  MsgHeader header;
  int64_t sim_time_ns = 0;
  double time_scale = 1.0;
  uint8_t time_mode = 0;  // WireTimeMode
  uint8_t reserved = 0;
  uint16_t bus_count = 0;
  uint16_t node_count = 0;
  uint16_t client_count = 0;
  StatusBus buses[kMaxStatusBuses];
  StatusNode nodes[kMaxStatusNodes];
};
static_assert(sizeof(StatusReply) == 16 + 24 + 64 * kMaxStatusBuses + 64 * kMaxStatusNodes);
static_assert(sizeof(StatusReply) <= kMaxMessageSize);

struct TimeStepRequest {
  MsgHeader header;
  int64_t step_ns = 0;  // > 0
};
static_assert(sizeof(TimeStepRequest) == 24);

struct TimeStepReply {
  MsgHeader header;
  int64_t sim_time_ns = 0;  // after the step
  uint64_t events_run = 0;
};
static_assert(sizeof(TimeStepReply) == 32);

template <class T>
constexpr MsgType type_of();
template <>
constexpr MsgType type_of<Hello>() {
  return MsgType::hello;
}
template <>
constexpr MsgType type_of<HelloReply>() {
  return MsgType::hello_reply;
}
template <>
constexpr MsgType type_of<ErrorReply>() {
  return MsgType::error_reply;
}
template <>
constexpr MsgType type_of<StatusRequest>() {
  return MsgType::status_request;
}
template <>
constexpr MsgType type_of<StatusReply>() {
  return MsgType::status_reply;
}
template <>
constexpr MsgType type_of<TimeStepRequest>() {
  return MsgType::time_step_request;
}
template <>
constexpr MsgType type_of<TimeStepReply>() {
  return MsgType::time_step_reply;
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

}  // namespace canemu::ipc
