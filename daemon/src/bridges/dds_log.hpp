// Cyclone DDS's own log lines in canemud (builds with Cyclone DDS only). Cyclone writes them from
// threads of its own; canemud takes them (dds_set_log_sink) to write them as its own lines on
// stderr ("<4>canemud: Cyclone DDS: ..."), and to count the samples Cyclone could not decode:
// such a sample (another type of the same name, bytes that are no CDR of the type) never reaches
// a reader, and Cyclone's warning "deserialization TOPIC/TYPE failed" is the only trace of it.
#pragma once

#ifdef CANEMU_HAVE_DDS

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>

namespace canemu::daemon {

// Counts the samples of `topic` (in DDS domain `domain`) that Cyclone could not decode, from the
// moment it is made until it is destroyed; `wake` is called (on Cyclone's thread) after each, so
// that the loop takes the count. Installs the log sink on first use.
class UndecodableSamples {
 public:
  UndecodableSamples(uint32_t domain, std::string topic, std::function<void()> wake);
  ~UndecodableSamples();
  UndecodableSamples(const UndecodableSamples&) = delete;
  UndecodableSamples& operator=(const UndecodableSamples&) = delete;

  // The samples counted since the last take().
  uint64_t take() { return count_.exchange(0); }
  const std::string& topic() const { return topic_; }

  // For the sink: a line of Cyclone's.
  static void on_line(std::string_view line);

 private:
  uint32_t domain_;
  std::string topic_;
  std::function<void()> wake_;
  std::atomic<uint64_t> count_{0};
};

// Cyclone's log lines go to canemud's stderr as canemud's own lines (idempotent).
void take_dds_log();

}  // namespace canemu::daemon

#endif
