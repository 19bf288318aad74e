// libFuzzer target: canemud's server layer (accepting, peer credentials, packets of any size and
// content, descriptors passed by clients, peers that half-close or vanish) and configuration
// reloads (SIGHUP with any file content). The input is a script of operations on up to eight
// clients of a daemon in stepped time, built afresh for each input. Every packet a client gets
// must be a valid message; when the input's script ends the clients close, the server is
// destroyed, and the process must hold exactly the descriptors it held before: nothing a client
// passed or opened may leak.
#include <fcntl.h>
#include <grp.h>
#include <poll.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/loop/server.hpp"
#include "canemu/ipc/protocol.hpp"
#include "fuzz_world.hpp"

// User and group names are answered from a fixed table instead of the C library's NSS: a
// reloaded file may name any group, and each NSS look-up (files, then systemd's userdb folders)
// took more time than the rest of an input. What is fuzzed is canemud's handling of the answer.
// These definitions take the place of the C library's for this program.
extern "C" group* getgrnam(const char* name) {
  static char members_none[] = "";
  static char* members[] = {members_none, nullptr};
  static group g{};
  static char stored[64];
  if (std::strcmp(name, "canemu") != 0 && std::strcmp(name, "wheel") != 0) {
    return nullptr;
  }
  std::snprintf(stored, sizeof stored, "%s", name);
  g.gr_name = stored;
  g.gr_passwd = members_none;
  g.gr_gid = name[0] == 'c' ? 990 : 10;
  g.gr_mem = members + 1;
  return &g;
}
extern "C" passwd* getpwnam(const char* name) {
  static passwd p{};
  static char stored[64];
  static char empty[] = "";
  if (std::strcmp(name, "canemu") != 0) {
    return nullptr;
  }
  std::snprintf(stored, sizeof stored, "%s", name);
  p.pw_name = stored;
  p.pw_passwd = p.pw_gecos = p.pw_dir = p.pw_shell = empty;
  p.pw_uid = 990;
  p.pw_gid = 990;
  return &p;
}

namespace {

using namespace canemu;

// No group names: resolving them through NSS (files, systemd's userdb) cost most of each input's
// time, and the clients are root anyway. Reloads may still name groups.
constexpr const char* kConfig = R"([simulation]
time = "stepped"

[security]
allowed_groups = []
socket_group = ""

[[bus]]
name = "can0"
bitrate = 500000

[[device]]
name = "ixxat0"
model = "ixxat-usb-to-can"
controllers = ["can0"]
)";

const daemon::Config& config() {
  static const daemon::Config c = fuzzing::parse_or_abort(kConfig);
  return c;
}

const std::string& folder() {
  static const std::string dir = [] {
    // In memory where there is /dev/shm: every input rewrites the configuration file, and on a
    // disk the file system's work (truncation, write-back) would take most of the time.
    char name[] = "/dev/shm/canemu-fuzz-server-XXXXXX";
    char fallback[] = "/tmp/canemu-fuzz-server-XXXXXX";
    const char* made = ::mkdtemp(name);
    made = made != nullptr ? made : ::mkdtemp(fallback);
    if (made == nullptr) {
      std::abort();
    }
    daemon::log::set_max_level(daemon::log::Level::error);  // quieter: the input is hostile
    return std::string(made);
  }();
  return dir;
}

std::size_t open_descriptors() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/fd")) {
    ++n;
  }
  return n;
}

// Connects as a client would, but without waiting: while the server does not run (this one
// thread plays both sides), connections the input made and closed stay in the listening
// socket's backlog, and once it is full a blocking connect would wait for ever. Then: none.
std::optional<ipc::UniqueFd> connect_now(const std::string& path) {
  ipc::UniqueFd fd(::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC | SOCK_NONBLOCK, 0));
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::memcpy(a.sun_path, path.c_str(), std::min(path.size(), sizeof a.sun_path - 1));
  if (!fd.valid() || ::connect(fd.get(), reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    return std::nullopt;
  }
  return fd;
}

class Script {
 public:
  Script(const uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool done() const { return at_ >= size_; }
  uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
  std::vector<uint8_t> bytes(std::size_t n) {
    n = std::min(n, size_ - at_);
    std::vector<uint8_t> out(data_ + at_, data_ + at_ + n);
    at_ += n;
    return out;
  }

 private:
  const uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

// Reads everything waiting for `fd` without blocking: each packet must be a valid message; the
// descriptors that come with replies are closed.
void drain(int fd) {
  std::vector<uint8_t> buffer;
  std::vector<ipc::UniqueFd> fds;
  while (true) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 0) <= 0) {
      return;
    }
    auto n = ipc::receive_packet(fd, buffer, 0, &fds);
    if (!n || *n == 0) {
      return;  // closed by canemud (refused, or it misbehaved)
    }
    if (ipc::check_message(buffer.data(), buffer.size()) != ipc::ErrorCode::none) {
      std::abort();  // canemud sends well-formed messages only
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string socket = folder() + "/canemud.sock";
  const std::string file = folder() + "/canemud.toml";
  static bool file_changed = true;  // a reload wrote it; the first input writes it
  if (file_changed) {
    std::ofstream(file, std::ios::trunc) << kConfig;
    file_changed = false;
  }
  const std::size_t before = open_descriptors();
  {
    auto sim = fuzzing::fresh_simulation(config());
    daemon::Server server(*sim, {socket, {daemon::TimeMode::stepped, 1.0}, file, std::nullopt});
    if (!server.open()) {
      std::abort();
    }
    std::vector<ipc::UniqueFd> clients;
    Script s(data, size);
    while (!s.done()) {
      const uint8_t op = s.byte();
      ipc::UniqueFd* c = clients.empty() ? nullptr : &clients[s.byte() % clients.size()];
      switch (op % 8) {
        case 0:
          if (clients.size() < 8) {
            if (auto fd = connect_now(socket)) {
              clients.push_back(std::move(*fd));
            }
          }
          break;
        case 1:    // a packet of any size and content
        case 2: {  // the same after a proper hello
          if (c == nullptr) {
            break;
          }
          if (op % 8 == 2) {
            auto hello = ipc::make_message<ipc::Hello>();
            ipc::copy_name(hello.client_name, "fuzz");
            (void)ipc::send_message(c->get(), hello);
          }
          const std::size_t n = static_cast<std::size_t>(s.byte()) * 64 + s.byte();
          const auto packet = s.bytes(n);
          (void)::send(c->get(), packet.data(), packet.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
          break;
        }
        case 3: {  // a packet with descriptors attached
          if (c == nullptr) {
            break;
          }
          int pipe_fds[2];
          if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
            break;
          }
          auto m = ipc::make_message<ipc::StatusRequest>();
          const int passed[2] = {pipe_fds[0], pipe_fds[1]};
          (void)ipc::send_packet(c->get(), &m, sizeof m, passed);
          ::close(pipe_fds[0]);
          ::close(pipe_fds[1]);
          break;
        }
        case 4:
          if (c != nullptr) {
            drain(c->get());
            clients.erase(clients.begin() + (c - clients.data()));
          }
          break;
        case 5:
          if (c != nullptr) {
            ::shutdown(c->get(), SHUT_WR);
          }
          break;
        case 6: {  // a reload with whatever the file says
          const auto text = s.bytes(s.byte() * 4);
          file_changed = true;
          std::ofstream(file, std::ios::trunc)
              .write(reinterpret_cast<const char*>(text.data()),
                     static_cast<std::streamsize>(text.size()));
          std::raise(SIGHUP);  // blocked: the server's signalfd takes it
          if (!server.run_once(0)) {
            std::abort();
          }
          break;
        }
        default:
          if (!server.run_once(0)) {
            std::abort();
          }
          if (c != nullptr) {
            drain(c->get());
          }
          break;
      }
    }
    for (int k = 0; k < 3; ++k) {
      if (!server.run_once(0)) {
        std::abort();
      }
      for (auto& c : clients) {
        drain(c.get());
      }
    }
    clients.clear();
    if (!server.run_once(0) || !server.running()) {
      std::abort();  // no client may stop the daemon
    }
  }
  if (open_descriptors() != before) {
    std::abort();  // a descriptor leaked
  }
  return 0;
}
