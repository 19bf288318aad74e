#include "fault_table.hpp"

#include <cstdio>
#include <optional>
#include <sstream>
#include <utility>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "canemu/client/lists.hpp"
#include "text_table.hpp"

namespace canemu::cli {

namespace {

std::string state_name(uint8_t state) {
  return std::string(ipc::to_string(static_cast<ipc::WireFaultState>(state)));
}

ipc::WireFaultMatch match_kind(const ipc::FaultEntry& e) {
  return static_cast<ipc::WireFaultMatch>(e.match);
}
ipc::WireMatchFlag flag(uint8_t v) {
  return static_cast<ipc::WireMatchFlag>(v);
}

}  // namespace

std::string match_text(const ipc::FaultEntry& e) {
  const bool ext = flag(e.match_ext) == ipc::WireMatchFlag::yes;
  switch (match_kind(e)) {
    case ipc::WireFaultMatch::none:
      return "-";
    case ipc::WireFaultMatch::babble:
      return fmt::format("sends 0x{:X}{}", e.match_id, ext ? " ext" : "");
    case ipc::WireFaultMatch::can:
    case ipc::WireFaultMatch::lin:
      break;
  }
  std::string text;
  const auto add = [&text](const std::string& part) { text += (text.empty() ? "" : " ") + part; };
  if (e.match_mask != 0) {
    const uint32_t all = match_kind(e) == ipc::WireFaultMatch::lin ? 0x3F : 0x1FFFFFFF;
    add(fmt::format("id 0x{:X}", e.match_id));
    if (e.match_mask != all) {
      add(fmt::format("mask 0x{:X}", e.match_mask));
    }
  }
  if (flag(e.match_ext) != ipc::WireMatchFlag::any) {
    add(ext ? "ext" : "std");
  }
  if (flag(e.match_rtr) != ipc::WireMatchFlag::any) {
    add(flag(e.match_rtr) == ipc::WireMatchFlag::yes ? "rtr" : "data");
  }
  if (const std::string from = ipc::printable_name_of(e.match_from); !from.empty()) {
    add("from " + from);
  }
  return text.empty() ? "any" : text;
}

tl::expected<FaultList, std::string> fault_list(client::Connection& c) {
  auto r = client::fetch_fault_list(c);
  if (!r) {
    return tl::unexpected(r.error().message);
  }
  return std::move(*r);
}

void print_faults(const FaultList& faults) {
  using Align = TextTable::Align;
  TextTable table({{"SCENARIO", Align::left, 24},
                   {"LINE", Align::right, 5},
                   {"EFFECT", Align::left, 15},
                   {"TARGET", Align::left, 12},
                   {"AT", Align::right, 14},
                   {"UNTIL", Align::right, 14},
                   {"SEEN", Align::right, 8},
                   {"HITS", Align::right, 8},
                   {"STATE", Align::left, 7},
                   {"MATCH"}});
  for (const ipc::FaultEntry& e : faults) {
    const auto seconds = [](int64_t ns) {
      return fmt::format("{:.6f}", static_cast<double>(ns) / 1e9);
    };
    table.add({ipc::name_of(e.scenario), std::to_string(e.line), ipc::name_of(e.effect),
               ipc::name_of(e.target), seconds(e.at_ns), e.has_until ? seconds(e.until_ns) : "-",
               std::to_string(e.seen), std::to_string(e.hits), state_name(e.state), match_text(e)});
  }
  table.print();
}

namespace {

// A frame effect's "match" (the keys of the scenario language's match, each where it is set), or
// babble's "frame" (id, ext); nothing for other effects.
std::optional<toml::table> match_json(const ipc::FaultEntry& e) {
  const auto as_bool = [](uint8_t v) { return flag(v) == ipc::WireMatchFlag::yes; };
  switch (match_kind(e)) {
    case ipc::WireFaultMatch::none:
      return std::nullopt;
    case ipc::WireFaultMatch::babble:
      return toml::table{{"id", static_cast<int64_t>(e.match_id)}, {"ext", as_bool(e.match_ext)}};
    case ipc::WireFaultMatch::can:
    case ipc::WireFaultMatch::lin:
      break;
  }
  toml::table m;
  if (e.match_mask != 0) {
    m.insert("id", static_cast<int64_t>(e.match_id));
    m.insert("mask", static_cast<int64_t>(e.match_mask));
  }
  if (flag(e.match_ext) != ipc::WireMatchFlag::any) {
    m.insert("ext", as_bool(e.match_ext));
  }
  if (flag(e.match_rtr) != ipc::WireMatchFlag::any) {
    m.insert("rtr", as_bool(e.match_rtr));
  }
  if (const std::string from = ipc::printable_name_of(e.match_from); !from.empty()) {
    m.insert("from", from);
  }
  return m;
}

}  // namespace

toml::array faults_array(const FaultList& list) {
  toml::array faults;
  for (const ipc::FaultEntry& e : list) {
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
    if (auto m = match_json(e)) {
      t.insert(match_kind(e) == ipc::WireFaultMatch::babble ? "frame" : "match", std::move(*m));
    }
    faults.push_back(std::move(t));
  }
  return faults;
}

std::string faults_json(const FaultList& faults) {
  return one_line_json(faults_array(faults));
}

}  // namespace canemu::cli
