// Reading [[lin_node]] tables (lin_config.hpp), checked with every problem reported.
#include "lin_config_reader.hpp"
#include "canemu/daemon/config/config.hpp"
#include "config/run_time_tables.hpp"

#include <set>

#include <fmt/format.h>

#include "canemu/firmware_model/bus/lin_frame.hpp"

namespace canemu::daemon::detail {

namespace {

constexpr int64_t kMaxDelayNs = 10'000'000'000;  // 10 s

std::optional<uint8_t> read_id(Checker& c, const toml::table& t, const std::string& path,
                               std::string_view name, bool required) {
  auto v = c.integer(t, path, name, required, 0, model::lin::kMaxId);
  return v ? std::optional<uint8_t>(static_cast<uint8_t>(*v)) : std::nullopt;
}

// An array of LIN identifiers (0..63), at least one.
std::optional<std::vector<uint8_t>> read_ids(Checker& c, const toml::table& t,
                                             const std::string& path, std::string_view name) {
  const toml::node* n = t.get(name);
  const toml::array* a = n != nullptr ? n->as_array() : nullptr;
  if (a == nullptr || a->empty()) {
    c.error(n != nullptr ? n->source() : t.source(), Checker::key(path, name),
            "must be an array of 1 or more LIN identifiers (0 to 63)");
    return std::nullopt;
  }
  std::vector<uint8_t> out;
  for (const toml::node& e : *a) {
    if (!e.is_integer() || e.as_integer()->get() < 0 ||
        e.as_integer()->get() > model::lin::kMaxId) {
      c.error(e, Checker::key(path, name), "a LIN identifier is an integer from 0 to 63");
      return std::nullopt;
    }
    out.push_back(static_cast<uint8_t>(e.as_integer()->get()));
  }
  return out;
}

std::optional<int64_t> read_delay(Checker& c, const toml::table& t, const std::string& path) {
  auto text = c.string(t, path, "delay", true);
  if (!text) {
    return std::nullopt;
  }
  auto ns = parse_duration(*text);
  if (!ns || *ns <= 0 || *ns > kMaxDelayNs) {
    c.error(*t.get("delay"), path + ".delay",
            fmt::format("\"{}\" is not a slot time from 1ns to 10s (examples: 10ms, 5ms)", *text));
    return std::nullopt;
  }
  return ns;
}

void read_response(Checker& c, const toml::table& t, const std::string& path, LinNodeConfig& node) {
  c.only_keys(t, path, {"id", "data", "checksum", "event_triggered"});
  LinResponseConfig r;
  auto id = read_id(c, t, path, "id", true);
  const toml::node* d = t.get("data");
  const toml::array* a = d != nullptr ? d->as_array() : nullptr;
  bool ok = id.has_value();
  if (a == nullptr || a->empty() || a->size() > model::lin::kMaxData) {
    c.error(d != nullptr ? d->source() : t.source(), path + ".data",
            "must be an array of 1 to 8 bytes (0 to 255)");
    ok = false;
  } else {
    for (const toml::node& e : *a) {
      if (!e.is_integer() || e.as_integer()->get() < 0 || e.as_integer()->get() > 255) {
        c.error(e, path + ".data", "a byte is an integer from 0 to 255");
        ok = false;
        break;
      }
      r.data.push_back(static_cast<uint8_t>(e.as_integer()->get()));
    }
  }
  if (auto kind = c.string(t, path, "checksum", false)) {
    if (*kind == "classic") {
      r.enhanced = false;
    } else if (*kind != "enhanced") {
      c.error(*t.get("checksum"), path + ".checksum",
              fmt::format("\"{}\" is not a checksum kind (enhanced, classic)", *kind));
    }
  }
  if (t.get("event_triggered") != nullptr) {
    r.event_triggered = read_id(c, t, path, "event_triggered", false);
  }
  if (!ok) {
    return;
  }
  r.id = *id;
  for (const LinResponseConfig& other : node.responses) {
    if (other.id == r.id) {
      c.error(*t.get("id"), path + ".id",
              fmt::format("the node has a response for {:#04x} already", r.id));
      return;
    }
  }
  node.responses.push_back(std::move(r));
}

void read_schedule(Checker& c, const toml::table& t, const std::string& path, LinNodeConfig& node) {
  c.only_keys(t, path, {"name", "slots"});
  LinScheduleConfig s;
  if (auto name = c.string(t, path, "name", true)) {
    if (!valid_name(*name)) {
      c.error(*t.get("name"), path + ".name", kNameRule);
    }
    for (const LinScheduleConfig& other : node.schedules) {
      if (other.name == *name) {
        c.error(*t.get("name"), path + ".name",
                fmt::format("the node has a schedule named \"{}\" already", *name));
      }
    }
    s.name = *name;
  }
  const toml::node* n = t.get("slots");
  const toml::array* a = n != nullptr ? n->as_array() : nullptr;
  if (a == nullptr || a->empty()) {
    c.error(n != nullptr ? n->source() : t.source(), path + ".slots",
            "must be an array of 1 or more slots ({ frame = ID, delay = \"10ms\" }, "
            "{ event_triggered = ID, frames = [...], delay = ... }, "
            "{ sporadic = [...], delay = ... })");
    return;
  }
  for (std::size_t i = 0; i < a->size(); ++i) {
    const std::string p = fmt::format("{}.slots[{}]", path, i);
    const toml::table* st = a->get(i)->as_table();
    if (st == nullptr) {
      c.error(*a->get(i), p, "must be a table");
      continue;
    }
    c.only_keys(*st, p, {"frame", "event_triggered", "frames", "sporadic", "delay"});
    LinSlotConfig slot;
    const int kinds = (st->get("frame") != nullptr) + (st->get("event_triggered") != nullptr) +
                      (st->get("sporadic") != nullptr);
    if (kinds != 1) {
      c.error(st->source(), p,
              "a slot has exactly one of frame, event_triggered (with frames) and sporadic");
      continue;
    }
    if (st->get("frame") != nullptr) {
      if (auto id = read_id(c, *st, p, "frame", true)) {
        slot.id = *id;
      }
    } else if (st->get("event_triggered") != nullptr) {
      slot.kind = LinSlotConfig::Kind::event_triggered;
      if (auto id = read_id(c, *st, p, "event_triggered", true)) {
        slot.id = *id;
      }
      if (auto frames = read_ids(c, *st, p, "frames")) {
        slot.frames = *frames;
      }
    } else {
      slot.kind = LinSlotConfig::Kind::sporadic;
      if (auto frames = read_ids(c, *st, p, "sporadic")) {
        slot.frames = *frames;
      }
    }
    if (st->get("frames") != nullptr && slot.kind != LinSlotConfig::Kind::event_triggered) {
      c.error(*st->get("frames"), p + ".frames", "only an event_triggered slot has frames");
    }
    if (auto delay = read_delay(c, *st, p)) {
      slot.delay_ns = *delay;
    }
    s.slots.push_back(std::move(slot));
  }
  node.schedules.push_back(std::move(s));
}

}  // namespace

void read_lin_nodes(Checker& c, const toml::table& root, Config& cfg) {
  std::set<std::string> names;
  std::set<std::string> commanders;  // buses with a commander running a schedule
  c.for_each_table(root, "lin_node", [&](const toml::table& t, const std::string& path) {
    c.only_keys(t, path,
                {"name", "bus", "bitrate", "powered", "schedule", "response", "schedules"});
    LinNodeConfig node;
    node.line = static_cast<uint32_t>(t.source().begin.line);
    const auto name = c.string(t, path, "name", true);
    const bool name_ok = name && valid_name(*name);
    if (name && !name_ok) {
      c.error(*t.get("name"), path + ".name", kNameRule);
    }
    if (name) {
      node.name = *name;
    }
    if (auto bus = c.string(t, path, "bus", true)) {
      const BusConfig* b = cfg.bus(*bus);
      if (b == nullptr) {
        c.error(*t.get("bus"), path + ".bus", fmt::format("no bus is named \"{}\"", *bus));
      } else if (b->kind != BusKind::lin) {
        c.error(*t.get("bus"), path + ".bus",
                fmt::format("\"{}\" is a {} bus; a LIN node needs a LIN bus", *bus,
                            to_string(b->kind)));
      }
      node.bus = *bus;
    }
    // Names are scoped by bus: two clusters (LDFs) may each have a node of one name.
    if (name_ok && !names.insert(node.bus + "/" + *name).second) {
      c.error(*t.get("name"), path + ".name",
              fmt::format("a LIN node named \"{}\" exists on \"{}\" already", *name, node.bus));
    }
    if (auto rate = c.integer(t, path, "bitrate", false, model::lin::kMinBitrate,
                              model::lin::kMaxBitrate)) {
      node.bitrate = static_cast<uint32_t>(*rate);
    }
    if (const toml::node* p = t.get("powered")) {
      if (!p->is_boolean()) {
        c.error(*p, path + ".powered", "must be true or false");
      } else {
        node.powered = p->as_boolean()->get();
      }
    }
    c.each_nested(t, path, "response", [&](const toml::table& r, const std::string& p) {
      read_response(c, r, p, node);
    });
    c.each_nested(t, path, "schedules", [&](const toml::table& s, const std::string& p) {
      read_schedule(c, s, p, node);
    });
    if (auto run = c.string(t, path, "schedule", false)) {
      const bool known = std::any_of(node.schedules.begin(), node.schedules.end(),
                                     [&](const LinScheduleConfig& s) { return s.name == *run; });
      if (!known) {
        c.error(*t.get("schedule"), path + ".schedule",
                fmt::format("the node has no schedule named \"{}\"", *run));
      } else if (!commanders.insert(node.bus).second) {
        c.error(*t.get("schedule"), path + ".schedule",
                fmt::format("another LIN node runs a schedule on \"{}\" already; a LIN bus has "
                            "one commander",
                            node.bus));
      }
      node.schedule = *run;
    }
    cfg.lin_nodes.push_back(std::move(node));
  });
}

}  // namespace canemu::daemon::detail

namespace canemu::daemon {

tl::expected<std::vector<LinNodeConfig>, std::vector<std::string>> parse_lin_nodes(
    std::string_view text, const std::string& source, const std::vector<BusConfig>& buses) {
  return detail::run_time_tables(text, source, buses, "lin_node", detail::read_lin_nodes,
                                 &Config::lin_nodes);
}

}  // namespace canemu::daemon
