// libFuzzer target: canemud's control-message handling. The input is a sequence of packets,
// each a 16-bit little-endian length and that many bytes, fed to one client session of a daemon
// built from the embedded default configuration and an X-CAN-2i "xcan0" on its buses, in stepped
// time, built afresh for each input (nothing one input did can hide or cause another's crash).
// Every reply must be a valid
// message, with ring descriptors exactly when it opens a channel (or initializes a VCI one),
// and nothing may crash. The session ends with each input, so the channels and VCI objects it
// opened close again.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "fuzz_world.hpp"

namespace {

using namespace canemu;

const daemon::Config& config() {
  static const daemon::Config c =
      fuzzing::parse_or_abort(std::string(daemon::embedded_default_config()) +
                              "\n[[device]]\nname = \"xcan0\"\nmodel = \"sorcus-x-can-2i\"\n"
                              "controllers = [\"can0\", \"can1\"]\n");
  return c;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzzing::OneClient client(config());
  const auto check_reply = [](const void* reply, size_t bytes, std::span<const int> fds) {
    if (ipc::check_message(reply, bytes) != ipc::ErrorCode::none) {
      std::abort();  // the daemon must only ever send well-formed messages
    }
    ipc::MsgHeader h;
    std::memcpy(&h, reply, sizeof h);
    const bool opened = h.type == static_cast<uint16_t>(ipc::MsgType::open_channel_reply);
    const bool vci = h.type == static_cast<uint16_t>(ipc::MsgType::vci_reply);
    if (h.type == static_cast<uint16_t>(ipc::MsgType::xcan_reply) ||
        h.type == static_cast<uint16_t>(ipc::MsgType::xcan_callback)) {
      if (!fds.empty()) {
        std::abort();  // X-CAN services never pass descriptors
      }
      return;
    }
    if (vci && !fds.empty()) {
      ipc::VciReply r;
      std::memcpy(&r, reply, sizeof r);
      if ((fds.size() != ipc::kChannelFdCount && fds.size() != ipc::kFifoFdCount) ||
          r.hresult != 0) {
        std::abort();  // rings come with a successful channel or FIFO call only
      }
    } else if (fds.size() != (opened ? ipc::kChannelFdCount : 0)) {
      std::abort();  // descriptors come with an opened channel, and only then
    }
  };
  size_t at = 0;
  while (at + 2 <= size) {
    const size_t length = data[at] | (size_t{data[at + 1]} << 8);
    at += 2;
    const size_t n = length < size - at ? length : size - at;
    client.handle(data + at, n, check_reply);
    at += n;
  }
  client.end();
  return 0;
}
