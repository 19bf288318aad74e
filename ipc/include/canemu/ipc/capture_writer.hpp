// A bus recording on disk, in candump log or pcap format (socketcan.hpp; a LIN bus: pcap with
// LINKTYPE_LIN, lin_pcap.hpp), with size-based rotation: canemud's [[recorder]] and
// `canemu record` / `canemu dump -o` write through it.
//
// Records are gathered in memory and written with write(2) by flush() (and by record() when
// 64 KiB are pending). Nothing is lost silently: a failed write (a full disk, a removed
// directory) counts the frames it held in `lost()`, keeps the reason in `error()`, cuts the file
// back to its last whole record, and the next flush tries again.
//
// Rotation: before a record would take the file past `max_bytes`, the file is closed and renamed
// PATH.1 (PATH.1 to PATH.2, and so on; at most `max_files` old files are kept, the oldest is
// removed) and a new PATH starts with its own pcap header. A single file never holds less than
// one record.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "canemu/ipc/lin_pcap.hpp"
#include "canemu/ipc/seqpacket.hpp"
#include "canemu/ipc/socketcan.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::ipc {

enum class CaptureFormat : uint8_t { candump = 0, pcap = 1 };

std::string_view to_string(CaptureFormat f);
// "candump" or "pcap"; nothing otherwise.
std::optional<CaptureFormat> parse_capture_format(std::string_view text);

// Why a LIN bus cannot go into a candump log, naming the bus: what canemud's configuration,
// canemu record and canemu dump say when asked to.
std::string candump_has_no_lin(std::string_view bus);

struct CaptureOptions {
  std::string path;  // "-": standard output (no rotation)
  CaptureFormat format = CaptureFormat::candump;
  std::string bus;          // the interface name of candump lines
  uint64_t max_bytes = 0;   // rotate before a file grows past this; 0: never
  uint32_t max_files = 10;  // old files kept by rotation (PATH.1 .. PATH.max_files)
  bool lin = false;         // a LIN bus: pcap with LINKTYPE_LIN (candump logs have no LIN)
};

class CaptureWriter {
 public:
  // Opens (creates or truncates) the file and writes the pcap header; the error names the path.
  // A LIN recording in candump format is refused (the error names the bus).
  static IpcResult<CaptureWriter> open(CaptureOptions options);

  CaptureWriter(CaptureWriter&&) noexcept = default;
  CaptureWriter& operator=(CaptureWriter&&) noexcept = default;
  ~CaptureWriter();

  // Queues one frame stamped `ns` (nanoseconds); writes when enough is pending. A CAN frame goes
  // into a CAN recording only, a LIN message into a LIN recording only (others are ignored).
  void record(int64_t ns, const socketcan::Frame& f);
  void record(int64_t ns, const lin_pcap::Message& m);
  // A CAN frame whose candump line names `bus` rather than options().bus (a dump of several
  // buses into one log); a pcap record is the same either way.
  void record(int64_t ns, std::string_view bus, const socketcan::Frame& f);
  // Writes what is pending; false when the write failed (see error() and lost()).
  bool flush();

  const CaptureOptions& options() const { return options_; }
  uint64_t frames() const { return frames_; }  // written to disk (LIN: records)
  uint64_t bytes() const { return bytes_; }    // in all files, headers included
  uint64_t lost() const { return lost_; }      // frames a failed write took with it
  uint32_t rotations() const { return rotations_; }
  const std::string& error() const { return error_; }  // the last failure, empty if none

 private:
  explicit CaptureWriter(CaptureOptions options) : options_(std::move(options)) {}
  IpcResult<void> start_file();
  std::vector<uint8_t> file_header() const;
  void append(const std::vector<uint8_t>& one);
  bool rotate();
  bool write_pending();

  CaptureOptions options_;
  UniqueFd fd_;
  std::vector<uint8_t> pending_;  // whole records (and a pcap header first in a new file)
  uint64_t pending_frames_ = 0;
  uint64_t file_bytes_ = 0;    // on disk in the current file
  uint64_t file_records_ = 0;  // records in the current file, written or pending
  uint64_t frames_ = 0;
  uint64_t bytes_ = 0;
  uint64_t lost_ = 0;
  uint32_t rotations_ = 0;
  std::string error_;
};

}  // namespace canemu::ipc
