#ifdef CANEMU_HAVE_DDS

#include "dds_log.hpp"

#include <unistd.h>

#include <algorithm>
#include <mutex>
#include <vector>

#include <dds/dds.h>

#include "canemu/daemon/base/log.hpp"

namespace canemu::daemon {

namespace {

std::mutex& registry_mutex() {
  static std::mutex m;
  return m;
}

std::vector<UndecodableSamples*>& registry() {
  static std::vector<UndecodableSamples*> r;
  return r;
}

// On a thread of Cyclone's.
void sink(void*, const dds_log_data_t* data) {
  std::string_view text(data->message, data->size);
  text.remove_prefix(std::min(data->hdrsize, text.size()));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) {
    text.remove_suffix(1);
  }
  const log::Level level = (data->priority & (DDS_LC_FATAL | DDS_LC_ERROR)) != 0 ? log::Level::error
                           : (data->priority & DDS_LC_WARNING) != 0 ? log::Level::warning
                                                                    : log::Level::info;
  // One write of the whole line (log::write is the loop's alone).
  const std::string line = log::format_line(level, "Cyclone DDS: " + std::string(text)) + "\n";
  [[maybe_unused]] const auto n = ::write(STDERR_FILENO, line.data(), line.size());
  UndecodableSamples::on_line(text);
}

}  // namespace

void take_dds_log() {
  static std::once_flag once;
  std::call_once(once, [] { dds_set_log_sink(&sink, nullptr); });
}

UndecodableSamples::UndecodableSamples(uint32_t domain, std::string topic,
                                       std::function<void()> wake)
    : domain_(domain), topic_(std::move(topic)), wake_(std::move(wake)) {
  take_dds_log();
  std::lock_guard lock(registry_mutex());
  registry().push_back(this);
}

UndecodableSamples::~UndecodableSamples() {
  std::lock_guard lock(registry_mutex());
  std::erase(registry(), this);
}

void UndecodableSamples::on_line(std::string_view line) {
  // Cyclone 0.10: "data(application, ...): GUID #SEQ: deserialization TOPIC/TYPE failed (...)".
  constexpr std::string_view kStart = "deserialization ";
  constexpr std::string_view kEnd = " failed";
  const auto start = line.find(kStart);
  if (start == std::string_view::npos) {
    return;
  }
  const std::string_view rest = line.substr(start + kStart.size());
  const auto end = rest.find(kEnd);
  const auto slash = end == std::string_view::npos ? end : rest.substr(0, end).rfind('/');
  if (slash == std::string_view::npos) {
    return;
  }
  const std::string_view topic = rest.substr(0, slash);
  std::lock_guard lock(registry_mutex());
  for (UndecodableSamples* u : registry()) {
    // By the topic's name alone: Cyclone 0.10 gives such lines domain 0 whatever the domain
    // (two readers of one topic name in two domains or partitions: the first counts it).
    if (u->topic_ == topic) {
      u->count_.fetch_add(1);
      if (u->wake_) {
        u->wake_();
      }
      return;
    }
  }
}

}  // namespace canemu::daemon

#endif
