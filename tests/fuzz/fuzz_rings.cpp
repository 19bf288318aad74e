// libFuzzer target: what a client can write into a channel's shared ring memory. Each input gets
// a fresh simulation (the embedded default configuration, stepped time) and one client session
// that opens an ephemeral channel on can0; the input is then a sequence of patches
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

#include "canemu/daemon/control_dispatcher.hpp"
#include "fuzz_world.hpp"

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
  auto sim = fuzzing::fresh_simulation(config());
  daemon::ControlDispatcher dispatcher(*sim, daemon::TimeSetting{daemon::TimeMode::stepped, 1.0});
  dispatcher.client_count = [] { return uint16_t{1}; };
  daemon::Doorbell* bell = nullptr;
  dispatcher.channel_opened = [&bell](daemon::Doorbell& d) { bell = &d; };
  dispatcher.channel_closing = [&bell](daemon::Doorbell&) { bell = nullptr; };
  daemon::Session session;
  std::vector<int> fds;
  const auto send = [&fds](const void* reply, std::size_t bytes, std::span<const int> passed) {
    check(reply, bytes);
    for (int fd : passed) {
      fds.push_back(::dup(fd));
    }
  };
  auto hello = ipc::make_message<ipc::Hello>(1);
  dispatcher.handle(session, reinterpret_cast<const uint8_t*>(&hello), sizeof hello, send);
  auto open = ipc::make_message<ipc::OpenChannelRequest>(2);
  ipc::copy_name(open.bus, "can0");
  open.rx_capacity = 16;
  open.tx_capacity = 16;
  dispatcher.handle(session, reinterpret_cast<const uint8_t*>(&open), sizeof open, send);
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
    std::size_t at = 0;
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
      dispatcher.handle(session, reinterpret_cast<const uint8_t*>(&step), sizeof step, send);
    }
  }
  dispatcher.end_session(session);
  for (int fd : fds) {
    ::close(fd);
  }
  return 0;
}
