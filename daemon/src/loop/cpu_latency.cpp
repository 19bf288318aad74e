#include "canemu/daemon/loop/cpu_latency.hpp"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <utility>

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>

namespace canemu::daemon {

std::string CpuLatencyRequest::file() {
  const char* path = std::getenv("CANEMU_CPU_LATENCY_FILE");
  return path != nullptr && *path != '\0' ? path : "/dev/cpu_dma_latency";
}

std::string CpuLatencyRequest::hold(std::optional<uint32_t> us) {
  if (us == held_) {
    return {};
  }
  if (!us) {
    fd_.reset();  // closing the file ends the request held
    held_.reset();
    return {};
  }
  // The new request is made before the old one ends: one that cannot be made leaves the old
  // one held (held() says which).
  const std::string path = file();
  // Non-blocking: the loop must not wait on the open (a FIFO without a reader would hold it).
  ipc::UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CLOEXEC | O_NONBLOCK));
  if (!fd.valid()) {
    return fmt::format("{}: {} (docs/daemon.md, \"Latency\")", path, std::strerror(errno));
  }
  const int32_t value = static_cast<int32_t>(*us);
  const ssize_t n = ::write(fd.get(), &value, sizeof value);
  if (n != static_cast<ssize_t>(sizeof value)) {
    return fmt::format("{}: writing {} us: {}", path, *us,
                       n < 0 ? std::strerror(errno) : "the file took part of the value");
  }
  fd_ = std::move(fd);
  held_ = us;
  return {};
}

}  // namespace canemu::daemon
