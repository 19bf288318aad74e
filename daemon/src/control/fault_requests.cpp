// Fault scenarios loaded, listed and cleared at run time (`canemu fault`).
#include <cstring>
#include <memory>

#include <fmt/format.h>

#include "canemu/daemon/control/control_dispatcher.hpp"
#include "control/requests.hpp"

namespace canemu::daemon {

void ControlDispatcher::on_fault_load(Session& c, const uint8_t* data, uint32_t request_id,
                                      const Send& send) {
  auto m = std::make_unique<ipc::FaultLoadRequest>(read_as<ipc::FaultLoadRequest>(data));
  auto r =
      std::make_unique<ipc::FaultLoadReply>(ipc::make_message<ipc::FaultLoadReply>(request_id));
  const std::string source =
      ipc::name_of(m->source).empty() ? std::string("<client>") : ipc::printable_name_of(m->source);
  std::vector<std::string> problems;
  if (m->length > ipc::kMaxScenarioText) {
    problems.push_back(fmt::format("{}: {} bytes of text claimed, at most {}", source, m->length,
                                   ipc::kMaxScenarioText));
  } else {
    auto scenario = parse_scenario(std::string_view(m->text, m->length), source);
    if (!scenario) {
      problems = scenario.error();
    } else if (auto applied = sim_.scenarios().apply(*scenario, sim_.scheduler().now(), c.uid);
               !applied) {
      problems = applied.error();
    } else {
      r->applied = 1;
      r->faults = static_cast<uint32_t>(scenario->faults.size());
      ipc::copy_name(r->name, scenario->name);
    }
  }
  std::string text;
  for (const std::string& p : problems) {
    text += ipc::printable(p) + "\n";  // a problem may quote the client's text
  }
  ipc::copy_name(r->errors, text);
  send_reply(send, *r);
}

void ControlDispatcher::on_fault_list(Session&, const uint8_t* data, uint32_t request_id,
                                      const Send& send) {
  const auto req = read_as<ipc::FaultListRequest>(data);
  auto r =
      std::make_unique<ipc::FaultListReply>(ipc::make_message<ipc::FaultListReply>(request_id));
  const auto faults = sim_.scenarios().status();
  r->total = static_cast<uint16_t>(std::min<std::size_t>(faults.size(), UINT16_MAX));
  r->first = req.first;
  r->generation = sim_.scenarios().generation();
  for (std::size_t k = req.first; k < r->total && r->count < ipc::kFaultPage; ++k) {
    const ScenarioRunner::FaultStatus& f = faults[k];
    ipc::FaultEntry& e = r->faults[r->count++];
    ipc::copy_name(e.scenario, f.scenario);
    ipc::copy_name(e.effect, to_string(f.effect));
    if (f.target.size() < ipc::kFaultTargetSize) {
      ipc::copy_name(e.target, f.target);
    } else {  // longer than an entry holds: cut, and the cut shown
      ipc::copy_name(e.target, f.target.substr(0, ipc::kFaultTargetSize - 4) + "...");
    }
    e.line = f.line;
    e.state = static_cast<uint8_t>(f.state);
    e.has_until = f.until_ns ? 1 : 0;
    e.at_ns = f.at_ns;
    e.until_ns = f.until_ns.value_or(0);
    e.seen = f.seen;
    e.hits = f.hits;
    // The match, so that a rule that never hits shows why.
    const auto flag = [](const std::optional<bool>& v) {
      return static_cast<uint8_t>(!v   ? ipc::WireMatchFlag::any
                                  : *v ? ipc::WireMatchFlag::yes
                                       : ipc::WireMatchFlag::no);
    };
    using Frames = ScenarioRunner::FaultStatus::Frames;
    e.match = static_cast<uint8_t>(f.frames == Frames::can      ? ipc::WireFaultMatch::can
                                   : f.frames == Frames::lin    ? ipc::WireFaultMatch::lin
                                   : f.frames == Frames::babble ? ipc::WireFaultMatch::babble
                                                                : ipc::WireFaultMatch::none);
    e.match_id = f.match.id;
    e.match_mask = f.match.mask;
    e.match_ext = flag(f.match.ext);
    e.match_rtr = flag(f.match.rtr);
    ipc::copy_name(e.match_from, f.match.from);
  }
  send_reply(send, *r);
}

void ControlDispatcher::on_fault_clear(Session& c, const uint8_t* data, uint32_t request_id,
                                       const Send& send) {
  const auto m = read_as<ipc::FaultClearRequest>(data);
  const std::string name = ipc::name_of(m.scenario);
  // A client clears its own user's scenarios; an admin clears every one.
  const auto may = [&c](const ScenarioRunner::Owner& owner) {
    return c.admin || (owner && *owner == c.uid);
  };
  std::size_t refused = 0;
  const std::size_t cleared = sim_.scenarios().clear(name, may, &refused);
  if (cleared == 0 && refused > 0 && !name.empty()) {
    error(send, request_id, ipc::ErrorCode::permission_denied,
          fmt::format("scenario \"{}\" is not yours to clear: only the user who loaded it, "
                      "root, canemud's own user and members of [security] admin_groups may",
                      name));
    return;
  }
  if (cleared == 0 && !name.empty()) {
    error(send, request_id, ipc::ErrorCode::bad_argument,
          fmt::format("no scenario named \"{}\" to clear", name));
    return;
  }
  auto r = ipc::make_message<ipc::FaultClearReply>(request_id);
  r.cleared = static_cast<uint32_t>(cleared);
  r.refused = static_cast<uint32_t>(refused);
  send_reply(send, r);
}

}  // namespace canemu::daemon
