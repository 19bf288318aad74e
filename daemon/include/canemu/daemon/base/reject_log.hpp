// Why input was turned away (a bridge's rejected frames, the messages of other daemons dropped
// or rejected): a count per reason, the last reason with its details, and log lines, at most
// kBurst in any kWindowMs for one source so that a flood does not flood the journal (the lines
// left out are counted in the next one). Reasons are a small fixed set per source, numbered, so
// that the counts travel in fixed-layout replies. Thread: canemud's event loop only.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace canemu::daemon {

template <std::size_t N>
class RejectLog {
 public:
  static constexpr int kBurst = 5;
  static constexpr int64_t kWindowMs = 10'000;

  // `source` starts every log line ("LCM bridge of can0"); `names` are the reasons' short names.
  RejectLog(std::string source, std::array<std::string_view, N> names)
      : source_(std::move(source)), names_(names) {}

  // `n` inputs turned away for reason `reason` (< N); `detail` says which rule, which peer.
  void add(std::size_t reason, const std::string& detail, uint64_t n = 1) {
    counts_[reason] += n;
    last_ = detail;
    note(detail);
  }

  uint64_t count(std::size_t reason) const { return counts_[reason]; }
  const std::array<uint64_t, N>& counts() const { return counts_; }
  std::string_view name(std::size_t reason) const { return names_[reason]; }
  const std::array<std::string_view, N>& names() const { return names_; }
  // The last reason with its details ("" while nothing was turned away).
  const std::string& last() const { return last_; }
  const std::string& source() const { return source_; }

 private:
  void note(const std::string& detail);

  std::string source_;
  std::array<std::string_view, N> names_;
  std::array<uint64_t, N> counts_{};
  std::string last_;
  int64_t window_start_ms_ = -kWindowMs;
  int logged_ = 0;
  uint64_t unlogged_ = 0;
};

// The rate-limited line itself (reject_log.cpp): writes "SOURCE: DETAIL" as a warning unless
// kBurst lines were written since `window_start_ms`; then counts it in `unlogged`.
void reject_log_line(const std::string& source, const std::string& detail, int64_t& window_start_ms,
                     int& logged, uint64_t& unlogged, int burst, int64_t window_ms);

template <std::size_t N>
void RejectLog<N>::note(const std::string& detail) {
  reject_log_line(source_, detail, window_start_ms_, logged_, unlogged_, kBurst, kWindowMs);
}

}  // namespace canemu::daemon
