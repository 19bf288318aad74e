// canemu dump --summary MS: instead of a line per frame, a line per bus and identifier every MS
// milliseconds, for the identifiers that had frames since the lines before (what cansniffer
// shows, and what `canemu web`'s ID tables read: a busy bus costs the reader a line per
// identifier and interval, not one per frame). Each line is a JSON object:
//
//   {"bus":"can0","id":"123","count":12,"first_ns":...,"last_ns":...,"data":"0102","changed":2}
//   {"bus":"can0","error_frames":3}
//
// `id` is candump's identifier text (3 hex digits, or 8 for a 29-bit identifier), `data` the
// last frame's data as candump writes it without flags and DLC suffix (upper-case hex pairs, `R`
// for a remote frame), `first_ns`/`last_ns` the time stamps of the first and last frame of the
// interval, `changed` a bit for each byte that differed between two frames in a row of that
// identifier (the interval's first frame against the last one before it). Error frames are
// counted per bus.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "canemu/ipc/socketcan.hpp"

namespace canemu::cli {

class DumpSummary {
 public:
  // `buses`: the name of each target index add() is given.
  explicit DumpSummary(std::vector<std::string> buses) : buses_(std::move(buses)) {}

  void add(std::size_t target, int64_t ns, const ipc::socketcan::Frame& f);
  // The lines for what came since the last call (each ending in '\n'), by target and
  // identifier; empty when nothing came.
  std::string take();

 private:
  struct Row {
    uint64_t count = 0;  // in this interval
    int64_t first_ns = 0;
    int64_t last_ns = 0;
    uint64_t changed = 0;
    ipc::socketcan::Frame last;  // kept across intervals: the next frame is compared with it
  };
  std::vector<std::string> buses_;
  std::vector<std::string> quoted_;  // as JSON strings, made at the first take()
  // (target, identifier with kEffFlag for a 29-bit one) -> its row; rows stay once seen.
  std::map<std::pair<std::size_t, uint32_t>, Row> rows_;
  std::vector<uint64_t> error_frames_;  // per target, this interval
};

// The bytes (a bit each) in which two frames of one identifier differ, as their data texts do:
// beyond the shorter one's length every byte differs; a remote frame differs from a data frame
// in each byte of it (at least one), and not from another remote frame.
uint64_t changed_bytes(const ipc::socketcan::Frame& a, const ipc::socketcan::Frame& b);

}  // namespace canemu::cli
