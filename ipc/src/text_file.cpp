#include "canemu/ipc/text_file.hpp"

#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "canemu/ipc/unique_fd.hpp"

namespace canemu::ipc {

namespace {

std::string size_text(std::size_t bytes) {
  if (bytes >= (std::size_t{1} << 20) && bytes % (std::size_t{1} << 20) == 0) {
    return std::to_string(bytes >> 20) + " MiB";
  }
  if (bytes >= 1024 && bytes % 1024 == 0) {
    return std::to_string(bytes >> 10) + " KiB";
  }
  return std::to_string(bytes) + " bytes";
}

}  // namespace

tl::expected<std::string, std::string> read_text_file(const std::string& path,
                                                      std::size_t max_bytes) {
  const UniqueFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY));
  if (!fd.valid()) {
    return tl::unexpected(path + ": cannot be read (" + std::strerror(errno) + ")");
  }
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) {
    return tl::unexpected(path + ": cannot be read (" + std::strerror(errno) + ")");
  }
  if (S_ISDIR(st.st_mode)) {
    return tl::unexpected(path + ": is a directory, not a file");
  }
  const std::string too_large =
      path + ": larger than " + size_text(max_bytes) + ", the most canemu reads from such a file";
  if (S_ISREG(st.st_mode) && static_cast<std::size_t>(st.st_size) > max_bytes) {
    return tl::unexpected(too_large);
  }
  std::string text;
  char buffer[16384];
  while (true) {
    const ssize_t n = ::read(fd.get(), buffer, sizeof buffer);
    if (n < 0) {
      if (errno == EINTR) {
        continue;
      }
      return tl::unexpected(path + ": cannot be read (" + std::strerror(errno) + ")");
    }
    if (n == 0) {
      return text;
    }
    if (text.size() + static_cast<std::size_t>(n) > max_bytes) {
      return tl::unexpected(too_large);  // a device or pipe without end
    }
    text.append(buffer, static_cast<std::size_t>(n));
  }
}

}  // namespace canemu::ipc
