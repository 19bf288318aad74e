// The differential trace of the CAN bus engine (docs/bus-engine.md, "Speed"): random frames
// through the wire encoder and random bus scenarios through CanBus, each item written out as
// text lines of everything it shows, and hashed. engine_trace_test.cpp compares the hashes with
// the ones recorded in tests/data/engine_trace/ from the engine as it was when they were made, so
// that a change in the engine's internals that changes any outcome fails there, naming the item.
//
// Everything here is a function of the item's number: a generator of our own (splitmix64; no
// std:: distribution, whose results the standard leaves to the library), a fixed seed per kind,
// and the item's seed derived from it. A change to the generators changes every hash: it bumps
// kGeneratorVersion and re-records (tests/README.md).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "canemu/firmware_model/bus/frame.hpp"

namespace canemu::model::testing::engine_trace {

inline constexpr uint32_t kGeneratorVersion = 1;
inline constexpr uint64_t kFrameSeed = 0x6672616D65730001ull;     // "frames"
inline constexpr uint64_t kScenarioSeed = 0x7363656E61720001ull;  // "scenar"
inline constexpr std::size_t kFrames = 100'000;
inline constexpr std::size_t kFramesPerChunk = 1'000;
inline constexpr std::size_t kChunks = kFrames / kFramesPerChunk;
inline constexpr std::size_t kScenarios = 1'000;

// splitmix64: small, fast, and the same everywhere.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, n) for n > 0 (the modulo bias of a 64-bit draw is of no concern here).
  uint64_t below(uint64_t n) { return next() % n; }
  // Uniform in [lo, hi].
  int64_t between(int64_t lo, int64_t hi) {
    return lo + static_cast<int64_t>(below(static_cast<uint64_t>(hi - lo) + 1));
  }
  // True with probability percent / 100.
  bool chance(uint32_t percent) { return below(100) < percent; }

 private:
  uint64_t state_;
};

// The seed of item `k` of a kind whose seed is `base`.
inline uint64_t item_seed(uint64_t base, uint64_t k) {
  Rng r(base ^ (k * 0xD1B54A32D192ED03ull));
  return r.next();
}

// FNV-1a, 64 bits.
inline uint64_t fnv1a(std::string_view s, uint64_t h = 0xCBF29CE484222325ull) {
  for (const char c : s) {
    h ^= static_cast<uint8_t>(c);
    h *= 0x100000001B3ull;
  }
  return h;
}

// Counters over a whole run, written in the record's header so that it says what the trace
// covers (and checked against the run, so that the header cannot drift from it).
template <class Names>
struct Counts {
  std::array<uint64_t, Names::kCount> n{};
  uint64_t& operator[](typename Names::Id id) { return n[static_cast<std::size_t>(id)]; }
  uint64_t operator[](std::size_t i) const { return n[i]; }
  void add(const Counts& o) {
    for (std::size_t i = 0; i < n.size(); ++i) {
      n[i] += o.n[i];
    }
  }
  static constexpr std::size_t size() { return Names::kCount; }
  static std::string_view name(std::size_t i) { return Names::kNames[i]; }
};

// printf into the end of `out`.
void appendf(std::string& out, const char* format, ...) __attribute__((format(printf, 2, 3)));
// A frame in one word: identifier, format letters (x extended, r remote, f FD, b BRS, e ESI),
// DLC and the data in hex.
void append_frame(std::string& out, const Frame& frame);

// --- frames ---

struct FrameCountNames {
  enum class Id : std::size_t {
    frames,
    classic,
    fd,
    extended,
    remote,
    classic_dlc_over_8,
    brs,
    esi,
    fd_over_16_bytes,
    fd_64_bytes,
    stuff_bits,
    extended_fd_64_bytes,  // the longest frames
    kCount_,
  };
  static constexpr std::size_t kCount = static_cast<std::size_t>(Id::kCount_);
  static constexpr std::array<std::string_view, kCount> kNames{
      "frames",      "classic",    "fd",
      "extended",    "remote",     "classic_dlc_over_8",
      "brs",         "esi",        "fd_over_16_bytes",
      "fd_64_bytes", "stuff_bits", "extended_fd_64_bytes"};
};
using FrameCounts = Counts<FrameCountNames>;

// A random frame: classic (base or extended, data or remote, DLC 0..15) or CAN FD (with or
// without BRS and ESI, DLC 0..15, so up to 64 bytes), with identifiers and payloads drawn so
// that runs of equal bits (stuffing) are frequent.
Frame random_frame(Rng& rng);

// Chunk `k` of the frame trace: kFramesPerChunk random frames from item_seed(kFrameSeed, k),
// each encoded and written out. `text` gets what the encoding shows within its contract (every
// bit up to the frame's length and its stuff marks, the fields, indexes, CRC, lengths and
// durations); `raw` what it leaves beyond it (every word of the bits and the stuff marks over a
// sentinel fill, so which words it writes, and the fields it does not set for this kind of
// frame). Both are appended to.
void trace_frame_chunk(std::size_t k, std::string& text, std::string& raw, FrameCounts& counts);

// --- bus scenarios ---

struct ScenarioCountNames {
  enum class Id : std::size_t {
    frames,
    error_frames,
    dominant_holds,
    fd_frames,
    brs_frames,
    extended_frames,
    remote_frames,
    remote_replies,
    self_receptions,
    arbitration_losses,
    single_shots_dropped,
    bit_errors,
    stuff_errors,
    form_errors,
    crc_errors,
    ack_errors,
    data_phase_errors,
    errors_outside_frames,
    severe_counts,  // rules 2 and 6
    counters_written,
    warning_entries,
    error_passive_entries,
    bus_off_entries,
    recoveries,
    host_restarts,
    fault_rule_hits,
    withdrawn_before_start,
    withdrawn_on_the_wire,
    late_attaches,
    faults_at_arbitration,
    kCount_,
  };
  static constexpr std::size_t kCount = static_cast<std::size_t>(Id::kCount_);
  static constexpr std::array<std::string_view, kCount> kNames{
      "frames",
      "error_frames",
      "dominant_holds",
      "fd_frames",
      "brs_frames",
      "extended_frames",
      "remote_frames",
      "remote_replies",
      "self_receptions",
      "arbitration_losses",
      "single_shots_dropped",
      "bit_errors",
      "stuff_errors",
      "form_errors",
      "crc_errors",
      "ack_errors",
      "data_phase_errors",
      "errors_outside_frames",
      "severe_counts",
      "counters_written",
      "warning_entries",
      "error_passive_entries",
      "bus_off_entries",
      "recoveries",
      "host_restarts",
      "fault_rule_hits",
      "withdrawn_before_start",
      "withdrawn_on_the_wire",
      "late_attaches",
      "faults_at_arbitration",
  };
};
using ScenarioCounts = Counts<ScenarioCountNames>;

// Scenario `k`, from item_seed(kScenarioSeed, k): 2 to 8 nodes on one bus (classic at one of
// several bit rates, or CAN FD with and without bit-rate switch, some nodes at other rates or
// classic-only), random traffic, and a random plan of everything the engine lets a caller do to
// it while it runs; run for a random stretch of simulated time. Appends its trace to `text`.
void run_scenario(std::size_t k, std::string& text, ScenarioCounts& counts);

}  // namespace canemu::model::testing::engine_trace
