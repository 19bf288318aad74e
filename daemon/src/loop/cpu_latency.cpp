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
  fd_.reset();  // closing the file ends the request held
  held_.reset();
  if (!us) {
    return {};
  }
  const std::string path = file();
  ipc::UniqueFd fd(::open(path.c_str(), O_WRONLY | O_CLOEXEC));
  if (!fd.valid()) {
    return fmt::format("{}: {} (docs/daemon.md, \"Latency\")", path, std::strerror(errno));
  }
  const int32_t value = static_cast<int32_t>(*us);
  if (::write(fd.get(), &value, sizeof value) != static_cast<ssize_t>(sizeof value)) {
    return fmt::format("{}: writing {} us: {}", path, *us, std::strerror(errno));
  }
  fd_ = std::move(fd);
  held_ = us;
  return {};
}

}  // namespace canemu::daemon
