#include "canemu/ipc/capture_writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace canemu::ipc {

namespace {

constexpr std::size_t kWriteThreshold = 64 * 1024;

std::string system_error(const std::string& what, const std::string& path, int error_number) {
  return what + " " + path + ": " + std::strerror(error_number);
}

}  // namespace

std::string candump_has_no_lin(std::string_view bus) {
  return "a candump log holds CAN frames only; LIN bus " + std::string(bus) +
         " is recorded as pcap (LINKTYPE_LIN)";
}

std::string_view to_string(CaptureFormat f) {
  return f == CaptureFormat::pcap ? "pcap" : "candump";
}

std::optional<CaptureFormat> parse_capture_format(std::string_view text) {
  if (text == "candump") {
    return CaptureFormat::candump;
  }
  if (text == "pcap") {
    return CaptureFormat::pcap;
  }
  return std::nullopt;
}

IpcResult<CaptureWriter> CaptureWriter::open(CaptureOptions options) {
  if (options.path.empty()) {
    return tl::unexpected(IpcError{0, "a recording needs a file name"});
  }
  if (options.lin && options.format == CaptureFormat::candump) {
    return tl::unexpected(IpcError{0, candump_has_no_lin(options.bus)});
  }
  CaptureWriter w(std::move(options));
  auto started = w.start_file();
  if (!started) {
    return tl::unexpected(started.error());
  }
  return w;
}

CaptureWriter::~CaptureWriter() {
  if (fd_.valid()) {
    flush();
  }
}

IpcResult<void> CaptureWriter::start_file() {
  const bool to_stdout = options_.path == "-";
  const int fd =
      to_stdout ? ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 0)
                : ::open(options_.path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int e = errno;
    return tl::unexpected(IpcError{e, system_error("open", options_.path, e)});
  }
  fd_.reset(fd);
  file_bytes_ = 0;
  file_records_ = 0;
  if (options_.format == CaptureFormat::pcap) {
    const auto header = file_header();
    pending_.insert(pending_.begin(), header.begin(), header.end());
  }
  return {};
}

std::vector<uint8_t> CaptureWriter::file_header() const {
  return options_.lin ? lin_pcap::pcap_file_header() : socketcan::pcap_file_header();
}

void CaptureWriter::record(int64_t ns, const socketcan::Frame& f) {
  record(ns, options_.bus, f);
}

void CaptureWriter::record(int64_t ns, std::string_view bus, const socketcan::Frame& f) {
  if (options_.lin) {
    return;
  }
  std::vector<uint8_t> one;
  if (options_.format == CaptureFormat::pcap) {
    socketcan::append_pcap_record(one, ns, f);
  } else {
    const std::string line = socketcan::candump_line(ns, bus, f) + "\n";
    one.assign(line.begin(), line.end());
  }
  append(one);
}

void CaptureWriter::record(int64_t ns, const lin_pcap::Message& m) {
  if (!options_.lin) {
    return;
  }
  std::vector<uint8_t> one;
  lin_pcap::append_pcap_record(one, ns, m);
  append(one);
}

void CaptureWriter::append(const std::vector<uint8_t>& one) {
  if (options_.max_bytes != 0 && options_.path != "-" && file_records_ != 0 &&
      file_bytes_ + pending_.size() + one.size() > options_.max_bytes) {
    flush();
    rotate();
  }
  pending_.insert(pending_.end(), one.begin(), one.end());
  ++pending_frames_;
  ++file_records_;
  if (pending_.size() >= kWriteThreshold) {
    flush();
  }
}

bool CaptureWriter::flush() {
  if (pending_.empty()) {
    return true;
  }
  if (!fd_.valid()) {
    // A rotation could not open the new file: try again now.
    auto started = start_file();
    if (!started) {
      error_ = started.error().message;
      lost_ += pending_frames_;
      pending_frames_ = 0;
      pending_.clear();
      return false;
    }
  }
  return write_pending();
}

bool CaptureWriter::write_pending() {
  std::size_t done = 0;
  while (done < pending_.size()) {
    const ssize_t n = ::write(fd_.get(), pending_.data() + done, pending_.size() - done);
    if (n < 0 && errno == EINTR) {
      continue;
    }
    if (n <= 0) {
      const int e = n < 0 ? errno : ENOSPC;
      error_ = system_error("write", options_.path, e);
      lost_ += pending_frames_;
      pending_frames_ = 0;
      // Cut the file back to its last whole record (not possible on a pipe: then it ends short).
      if (::ftruncate(fd_.get(), static_cast<off_t>(file_bytes_)) == 0) {
        ::lseek(fd_.get(), static_cast<off_t>(file_bytes_), SEEK_SET);
      }
      pending_.clear();
      if (file_bytes_ == 0 && options_.format == CaptureFormat::pcap) {
        pending_ = file_header();
      }
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  file_bytes_ += pending_.size();
  bytes_ += pending_.size();
  frames_ += pending_frames_;
  pending_frames_ = 0;
  pending_.clear();
  return true;
}

bool CaptureWriter::rotate() {
  fd_.reset();
  bool ok = true;
  const std::string& path = options_.path;
  const auto numbered = [&](uint32_t n) { return path + "." + std::to_string(n); };
  if (options_.max_files == 0) {
    ok = ::unlink(path.c_str()) == 0 || errno == ENOENT;
  } else {
    ::unlink(numbered(options_.max_files).c_str());
    for (uint32_t n = options_.max_files; n > 1; --n) {
      ::rename(numbered(n - 1).c_str(), numbered(n).c_str());
    }
    if (::rename(path.c_str(), numbered(1).c_str()) != 0) {
      error_ = system_error("rename", path, errno);
      ok = false;
    }
  }
  ++rotations_;
  pending_.clear();  // only what a failed flush left, already counted as lost
  auto started = start_file();
  if (!started) {
    error_ = started.error().message;  // flush() tries again
    return false;
  }
  return ok;
}

}  // namespace canemu::ipc
