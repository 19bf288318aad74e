// libFuzzer target: what a client can write into a channel's shared ring memory. Each input gets
// a fresh simulation (the embedded default configuration, stepped time) and one client session
// that opens, by the input's first byte, an ephemeral channel on can0, or a VCI v1 or v2 channel
// on ixxat0's first controller (initialized, activated, the line started); the rest of the
// input is a sequence of patches
// (16-bit little-endian offset, 8-bit length, that many bytes) written anywhere into the mapped
// transmit ring (header, positions, flags, slots) and the receive ring (by the offset's top
// bit), each followed by a kick of the channel's doorbell and a step of 1 ms. Nothing may crash,
// every reply must be well formed, and a kick must end (libFuzzer's timeout catches a loop).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fuzz_world.hpp"
#include "vci/cantype.h"

namespace {

using namespace canemu;

const daemon::Config& config() {
  static const daemon::Config c = fuzzing::parse_or_abort(daemon::embedded_default_config());
  return c;
}

// A shared mapping of a ring's memfd, as the client has it.
struct Mapping {
  uint8_t* bytes = nullptr;
  std::size_t size = 0;
  explicit Mapping(int fd) {
    struct stat st {};
    if (fd < 0 || ::fstat(fd, &st) != 0 || st.st_size <= 0) {
      return;
    }
    void* p = ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ | PROT_WRITE,
                     MAP_SHARED, fd, 0);
    if (p != MAP_FAILED) {
      bytes = static_cast<uint8_t*>(p);
      size = static_cast<std::size_t>(st.st_size);
    }
  }
  Mapping(const Mapping&) = delete;
  Mapping& operator=(const Mapping&) = delete;
  ~Mapping() {
    if (bytes != nullptr) {
      ::munmap(bytes, size);
    }
  }
};

void check(const void* reply, std::size_t bytes) {
  if (ipc::check_message(reply, bytes) != ipc::ErrorCode::none) {
    std::abort();  // the daemon must only ever send well-formed messages
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzzing::OneClient client(config());
  daemon::Doorbell*& bell = client.loop.bell;  // of the channel opened
  std::vector<int> fds;
  uint32_t last_handle = 0;  // of the last VCI reply
  const auto send = [&fds, &last_handle](const void* reply, std::size_t bytes,
                                         std::span<const int> passed) {
    check(reply, bytes);
    if (bytes == sizeof(ipc::VciReply) && static_cast<const ipc::MsgHeader*>(reply)->type ==
                                              static_cast<uint16_t>(ipc::MsgType::vci_reply)) {
      last_handle = static_cast<const ipc::VciReply*>(reply)->handle;
    }
    for (int fd : passed) {
      fds.push_back(::dup(fd));
    }
  };
  const auto ask = [&](const auto& request) { client.handle(&request, sizeof request, send); };
  ask(ipc::make_message<ipc::Hello>(1));
  const uint8_t kind = size > 0 ? data[0] % 3 : 0;  // ephemeral, VCI v1, VCI v2
  std::size_t at = size > 0 ? 1 : 0;
  if (kind == 0) {
    auto open = ipc::make_message<ipc::OpenChannelRequest>(2);
    ipc::copy_name(open.bus, "can0");
    open.rx_capacity = 16;
    open.tx_capacity = 16;
    ask(open);
  } else {
    const auto vci = [&](ipc::VciOp op, uint32_t handle) {
      auto m = ipc::make_message<ipc::VciRequest>(2);
      m.op = static_cast<uint16_t>(op);
      m.flags = kind == 2 ? ipc::kVciV2 : 0;
      m.handle = handle;
      ipc::copy_name(m.device, "ixxat0");
      return m;
    };
    ask(vci(ipc::VciOp::control_open, 0));
    const uint32_t control = last_handle;
    auto init = vci(ipc::VciOp::control_init, control);
    init.flags = 0;  // the v1 layout for both: 500 kbit/s as can0
    CANINITLINE line{};
    line.bOpMode = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED;
    line.bBtReg0 = CAN_BT0_500KB;
    line.bBtReg1 = CAN_BT1_500KB;
    std::memcpy(init.payload, &line, sizeof line);
    ask(init);
    ask(vci(ipc::VciOp::control_start, control));
    ask(vci(ipc::VciOp::channel_open, 0));
    const uint32_t channel = last_handle;
    auto channel_init = vci(ipc::VciOp::channel_init, channel);
    channel_init.args[0] = 16;
    channel_init.args[1] = 16;
    channel_init.args[3] = CAN_FILTER_PASS;
    ask(channel_init);
    ask(vci(ipc::VciOp::channel_activate, channel));
  }
  if (fds.size() != ipc::kChannelFdCount || bell == nullptr) {
    std::abort();  // the channel must open
  }
  {
    Mapping rx(fds[0]);
    Mapping tx(fds[1]);
    if (rx.bytes == nullptr || tx.bytes == nullptr) {
      std::abort();
    }
    auto step = ipc::make_message<ipc::TimeStepRequest>(3);
    step.step_ns = 1'000'000;
    while (at + 3 <= size) {
      const uint16_t where = static_cast<uint16_t>(data[at] | (data[at + 1] << 8));
      std::size_t length = data[at + 2];
      at += 3;
      length = length < size - at ? length : size - at;
      Mapping& ring = (where & 0x8000) != 0 ? rx : tx;
      const std::size_t offset = (where & 0x7FFF) % ring.size;
      const std::size_t n = length < ring.size - offset ? length : ring.size - offset;
      std::memcpy(ring.bytes + offset, data + at, n);
      at += length;
      if (bell != nullptr && !bell->broken()) {
        bell->kick();
      }
      client.handle(&step, sizeof step, send);
    }
  }
  client.end();
  for (int fd : fds) {
    ::close(fd);
  }
  return 0;
}
