#include "fault_table.hpp"

#include <cstdio>
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

namespace canemu::cli {

namespace {

std::string state_name(uint8_t state) {
  return std::string(ipc::to_string(static_cast<ipc::WireFaultState>(state)));
}

}  // namespace

tl::expected<ipc::FaultListReply, std::string> fault_list(client::Connection& c) {
  auto r = c.call<ipc::FaultListRequest, ipc::FaultListReply>(
      ipc::make_message<ipc::FaultListRequest>());
  if (!r) {
    return tl::unexpected(r.error().message);
  }
  return *r;
}

void print_faults(const ipc::FaultListReply& r) {
  std::printf("%-24s %5s %-15s %-12s %14s %14s %8s %8s %s\n", "SCENARIO", "LINE", "EFFECT",
              "TARGET", "AT", "UNTIL", "SEEN", "HITS", "STATE");
  for (uint16_t i = 0; i < r.count; ++i) {
    const ipc::FaultEntry& e = r.faults[i];
    const std::string until =
        e.has_until ? fmt::format("{:.6f}", static_cast<double>(e.until_ns) / 1e9) : "-";
    std::printf("%-24s %5u %-15s %-12s %14.6f %14s %8llu %8llu %s\n",
                ipc::name_of(e.scenario).c_str(), e.line, ipc::name_of(e.effect).c_str(),
                ipc::name_of(e.target).c_str(), static_cast<double>(e.at_ns) / 1e9, until.c_str(),
                static_cast<unsigned long long>(e.seen), static_cast<unsigned long long>(e.hits),
                state_name(e.state).c_str());
  }
  if (r.total > r.count) {
    std::printf("(%u more not shown)\n", r.total - r.count);
  }
}

toml::array faults_array(const ipc::FaultListReply& r) {
  toml::array faults;
  for (uint16_t i = 0; i < r.count; ++i) {
    const ipc::FaultEntry& e = r.faults[i];
    toml::table t{{"scenario", ipc::name_of(e.scenario)},
                  {"line", static_cast<int64_t>(e.line)},
                  {"effect", ipc::name_of(e.effect)},
                  {"target", ipc::name_of(e.target)},
                  {"at_ns", e.at_ns},
                  {"seen", static_cast<int64_t>(e.seen)},
                  {"hits", static_cast<int64_t>(e.hits)},
                  {"state", state_name(e.state)}};
    if (e.has_until) {
      t.insert("until_ns", e.until_ns);
    }
    faults.push_back(std::move(t));
  }
  return faults;
}

std::string faults_json(const ipc::FaultListReply& r) {
  return one_line_json(faults_array(r));
}

}  // namespace canemu::cli
