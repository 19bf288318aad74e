#include "dump_summary.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "fault_table.hpp"

namespace canemu::cli {

namespace {

namespace sc = ipc::socketcan;

bool remote(const sc::Frame& f) {
  return !f.fd && (f.can_id & sc::kRtrFlag) != 0;
}

std::string data_text(const sc::Frame& f) {
  return remote(f) ? "R" : sc::candump_data(f);
}

}  // namespace

uint64_t changed_bytes(const sc::Frame& a, const sc::Frame& b) {
  const bool ra = remote(a);
  const bool rb = remote(b);
  if (ra && rb) {
    return 0;
  }
  const auto first = [](std::size_t n) { return n >= 64 ? ~uint64_t{0} : (uint64_t{1} << n) - 1; };
  if (ra || rb) {
    return first(std::max<std::size_t>(ra ? b.len : a.len, 1));
  }
  const std::size_t common = std::min(a.len, b.len);
  uint64_t mask = first(std::max(a.len, b.len)) & ~first(common);
  for (std::size_t i = 0; i < common; ++i) {
    if (a.data[i] != b.data[i]) {
      mask |= uint64_t{1} << i;
    }
  }
  return mask;
}

void DumpSummary::add(std::size_t target, int64_t ns, const sc::Frame& f) {
  if ((f.can_id & sc::kErrFlag) != 0) {
    if (error_frames_.size() <= target) {
      error_frames_.resize(target + 1);
    }
    ++error_frames_[target];
    return;
  }
  const uint32_t id = (f.can_id & sc::kEffFlag) != 0 ? (f.can_id & (sc::kEffFlag | sc::kEffMask))
                                                     : (f.can_id & sc::kSffMask);
  auto [it, added] = rows_.try_emplace({target, id});
  Row& row = it->second;
  if (!added) {
    row.changed |= changed_bytes(row.last, f);
  }
  if (row.count == 0) {
    row.first_ns = ns;
  }
  ++row.count;
  row.last_ns = ns;
  row.last = f;
}

std::string DumpSummary::take() {
  if (quoted_.empty()) {
    for (const std::string& bus : buses_) {
      // A JSON string as toml++ escapes it ("[\"can0\"]" without its brackets).
      const std::string array = one_line_json(toml::array{bus});
      quoted_.push_back(array.substr(1, array.size() - 2));
    }
  }
  std::string out;
  for (auto& [key, row] : rows_) {
    if (row.count == 0) {
      continue;
    }
    out += fmt::format(
        "{{\"bus\":{},\"id\":\"{}\",\"count\":{},\"first_ns\":{},\"last_ns\":{},\"data\":\"{}\","
        "\"changed\":{}}}\n",
        quoted_[key.first], sc::candump_id(key.second), row.count, row.first_ns, row.last_ns,
        data_text(row.last), row.changed);
    row.count = 0;
    row.changed = 0;
  }
  for (std::size_t t = 0; t < error_frames_.size(); ++t) {
    if (error_frames_[t] != 0) {
      out += fmt::format("{{\"bus\":{},\"error_frames\":{}}}\n", quoted_[t], error_frames_[t]);
      error_frames_[t] = 0;
    }
  }
  return out;
}

}  // namespace canemu::cli
