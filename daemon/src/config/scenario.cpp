#include "canemu/daemon/config/scenario.hpp"

#include <algorithm>
#include <string_view>

#include <fmt/format.h>

#include "canemu/daemon/config/config.hpp"
#include "canemu/ipc/protocol.hpp"
#include "toml_checker.hpp"

namespace canemu::daemon {

namespace {

using detail::Checker;
using detail::NamedValue;

constexpr NamedValue<FaultEffect> kEffects[] = {
    {FaultEffect::bit_error, "bit_error"},
    {FaultEffect::stuff_error, "stuff_error"},
    {FaultEffect::form_error, "form_error"},
    {FaultEffect::crc_error, "crc_error"},
    {FaultEffect::ack_error, "ack_error"},
    {FaultEffect::ack_suppress, "ack_suppress"},
    {FaultEffect::stuck_dominant, "stuck_dominant"},
    {FaultEffect::random_errors, "random_errors"},
    {FaultEffect::node_off, "node_off"},
    {FaultEffect::node_on, "node_on"},
    {FaultEffect::bus_off, "bus_off"},
    {FaultEffect::error_counters, "error_counters"},
    {FaultEffect::oscillator, "oscillator"},
    {FaultEffect::babble, "babble"},
    {FaultEffect::line_error, "line_error"},
    {FaultEffect::lin_bit_error, "lin_bit_error"},
    {FaultEffect::lin_checksum_error, "lin_checksum_error"},
    {FaultEffect::lin_parity_error, "lin_parity_error"},
    {FaultEffect::lin_sync_error, "lin_sync_error"},
    {FaultEffect::lin_no_response, "lin_no_response"},
    {FaultEffect::lin_short_break, "lin_short_break"},
    {FaultEffect::lin_responder_off, "lin_responder_off"},
    {FaultEffect::lin_wakeup, "lin_wakeup"},
    {FaultEffect::message_timeout, "message_timeout"},
    {FaultEffect::checksum_error, "checksum_error"},
    {FaultEffect::counter_freeze, "counter_freeze"},
    {FaultEffect::counter_jump, "counter_jump"},
    {FaultEffect::signal_step, "signal_step"},
    {FaultEffect::signal_ramp, "signal_ramp"},
    {FaultEffect::signal_invalid, "signal_invalid"},
};
constexpr NamedValue<bool> kLinWhere[] = {{true, "header"}, {false, "response"}};
constexpr NamedValue<bool> kWires[] = {{false, "one"}, {true, "both"}};

bool is_frame_effect(FaultEffect e) {
  return e <= FaultEffect::ack_error;
}
bool is_bus_effect(FaultEffect e) {
  return e == FaultEffect::ack_suppress || e == FaultEffect::stuck_dominant;
}
// Node effects name a node; all others a bus.
bool is_node_effect(FaultEffect e) {
  return (e >= FaultEffect::node_off && e <= FaultEffect::line_error) ||
         e == FaultEffect::lin_responder_off || e == FaultEffect::lin_wakeup;
}

// A name a scenario gives (its own, a bus's, a node's): shown in tables and logs, so printable
// ASCII only (docs/security.md, "Text a client chose").
std::optional<std::string> name(Checker& c, const toml::table& t, const std::string& path,
                                std::string_view key, bool required) {
  auto text = c.string(t, path, key, required);
  if (!text) {
    return std::nullopt;
  }
  const auto bad = std::find_if_not(text->begin(), text->end(), ipc::is_printable);
  if (bad != text->end()) {
    c.error(
        *t.get(key), Checker::key(path, key),
        fmt::format("\"{}\" has byte {:#04x} at {}: names are printable ASCII",
                    ipc::printable(*text), static_cast<unsigned char>(*bad), bad - text->begin()));
    return std::nullopt;
  }
  return text;
}

// A duration key ("2s", "150ms", "20us", "10ns").
std::optional<int64_t> duration(Checker& c, const toml::table& t, const std::string& path,
                                std::string_view name, bool required) {
  auto text = c.string(t, path, name, required);
  if (!text) {
    return std::nullopt;
  }
  auto ns = parse_duration(*text);
  if (!ns) {
    c.error(*t.get(name), Checker::key(path, name),
            fmt::format("\"{}\" is not a duration (examples: 2s, 150ms, 20us, 10ns)", *text));
  }
  return ns;
}

std::optional<bool> boolean(Checker& c, const toml::table& t, const std::string& path,
                            std::string_view name) {
  const toml::node* n = t.get(name);
  if (n == nullptr) {
    return std::nullopt;
  }
  if (!n->is_boolean()) {
    c.error(*n, Checker::key(path, name), "must be true or false");
    return std::nullopt;
  }
  return n->as_boolean()->get();
}

// A fault's `match` table, if it has one; anything else in its place is an error that shows
// `example`.
const toml::table* match_table(Checker& c, const toml::table& t, const std::string& mpath,
                               std::string_view example) {
  const toml::node* n = t.get("match");
  if (n == nullptr) {
    return nullptr;
  }
  const toml::table* m = n->as_table();
  if (m == nullptr) {
    c.error(*n, mpath, fmt::format("must be a table, e.g. {}", example));
  }
  return m;
}

void read_match(Checker& c, const toml::table& t, const std::string& path, FaultSpec& f) {
  const std::string mpath = path + ".match";
  const toml::table* m = match_table(c, t, mpath, "{ id = 0x100, mask = 0x7FF }");
  if (m == nullptr) {
    return;
  }
  c.only_keys(*m, mpath, {"id", "mask", "ext", "rtr", "from"});
  if (auto id = c.integer(*m, mpath, "id", false, 0, 0x1FFFFFFF)) {
    f.match.id = static_cast<uint32_t>(*id);
    f.match.mask = 0x1FFFFFFF;
  }
  if (auto mask = c.integer(*m, mpath, "mask", false, 0, 0x1FFFFFFF)) {
    f.match.mask = static_cast<uint32_t>(*mask);
  }
  f.match.ext = boolean(c, *m, mpath, "ext");
  f.match.rtr = boolean(c, *m, mpath, "rtr");
  if (auto from = name(c, *m, mpath, "from", false)) {
    f.match.from = *from;
  }
}

// count = N or "all" (the default: every matching frame in the window).
void read_count(Checker& c, const toml::table& t, const std::string& path, FaultSpec& f) {
  if (const toml::node* n = t.get("count")) {
    if (n->is_string() && n->as_string()->get() == "all") {
      f.count.reset();
    } else if (auto count = c.integer(t, path, "count", false, 1, INT64_MAX)) {
      f.count = static_cast<uint64_t>(*count);
    }
  }
}

// A LIN frame's match: its identifier (0..3Fh) and the commander that sends its header.
void read_lin_match(Checker& c, const toml::table& t, const std::string& path, FaultSpec& f) {
  const std::string mpath = path + ".match";
  const toml::table* m = match_table(c, t, mpath, "{ id = 0x10, from = \"ixxat0:2\" }");
  if (m == nullptr) {
    return;
  }
  c.only_keys(*m, mpath, {"id", "from"});
  if (auto id = c.integer(*m, mpath, "id", false, 0, 0x3F)) {
    f.match.id = static_cast<uint32_t>(*id);
    f.match.mask = 0x3F;
  }
  if (auto from = name(c, *m, mpath, "from", false)) {
    f.match.from = *from;
  }
}

// babble's frame: id (11 bits, or 29 with ext = true), data (up to 8 bytes).
void read_babble_frame(Checker& c, const toml::table& t, const std::string& path, FaultSpec& f) {
  f.ext = boolean(c, t, path, "ext").value_or(false);
  if (auto id = c.integer(t, path, "id", true, 0, f.ext ? 0x1FFFFFFF : 0x7FF)) {
    f.id = static_cast<uint32_t>(*id);
  }
  const toml::node* n = t.get("data");
  if (n == nullptr) {
    return;  // no data bytes
  }
  const toml::array* a = n->as_array();
  if (a == nullptr || a->size() > 8) {
    c.error(*n, path + ".data", "must be an array of at most 8 bytes, e.g. [0x11, 0x22]");
    return;
  }
  for (const toml::node& e : *a) {
    const auto* v = e.as_integer();
    if (v == nullptr || v->get() < 0 || v->get() > 255) {
      c.error(e, path + ".data", "each element must be a byte (0..255)");
      return;
    }
    f.data.push_back(static_cast<uint8_t>(v->get()));
  }
}

// The keys of an effect on a simulated CAN node's message or signal.
std::vector<std::string_view> restbus_keys(FaultEffect e) {
  switch (e) {
    case FaultEffect::message_timeout:
      return {"bus", "message", "until"};
    case FaultEffect::checksum_error:
      return {"bus", "message", "count", "until"};
    case FaultEffect::counter_freeze:
      return {"bus", "signal", "until"};
    case FaultEffect::counter_jump:
      return {"bus", "signal", "by"};
    case FaultEffect::signal_step:
      return {"bus", "signal", "value"};
    case FaultEffect::signal_ramp:
      return {"bus", "signal", "to", "until"};
    default:
      return {"bus", "signal", "value", "raw", "until"};
  }
}

// `message = "NAME"` or `signal = "MESSAGE.SIGNAL"`, and the value keys of the effect.
void read_restbus(Checker& c, const toml::table& t, const std::string& path, FaultSpec& f) {
  const FaultEffect e = f.effect;
  if (e == FaultEffect::message_timeout || e == FaultEffect::checksum_error) {
    if (auto m = name(c, t, path, "message", true)) {
      f.message = *m;
    }
    if (e == FaultEffect::checksum_error) {
      read_count(c, t, path, f);
    }
    return;
  }
  if (auto sig = name(c, t, path, "signal", true)) {
    const std::size_t dot = sig->find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == sig->size()) {
      c.error(
          *t.get("signal"), path + ".signal",
          fmt::format("\"{}\" is not MESSAGE.SIGNAL (e.g. \"ENGINE_DATA.ENGINE_SPEED\")", *sig));
    } else {
      f.message = sig->substr(0, dot);
      f.signal = sig->substr(dot + 1);
    }
  }
  const auto required = [&](std::string_view key, std::string_view what) {
    if (t.get(key) == nullptr) {
      c.error(t.source(), Checker::key(path, key), fmt::format("missing ({})", what));
    }
  };
  switch (e) {
    case FaultEffect::counter_jump:
      if (auto by = c.integer(t, path, "by", true, 1, INT64_MAX)) {
        f.by = static_cast<uint64_t>(*by);
      }
      break;
    case FaultEffect::signal_step:
      required("value", "the physical value the signal takes");
      f.value = c.number(t, path, "value");
      break;
    case FaultEffect::signal_ramp:
      required("to", "the physical value the ramp ends at");
      required("until", "the instant the ramp reaches its value");
      f.value = c.number(t, path, "to");
      break;
    case FaultEffect::signal_invalid:
      if ((t.get("value") != nullptr) == (t.get("raw") != nullptr)) {
        c.error(t.source(), path,
                "needs either value (a physical value) or raw (the signal's bits), not both");
        break;
      }
      f.value = c.number(t, path, "value");
      if (auto raw = c.integer(t, path, "raw", false, 0, INT64_MAX)) {
        f.raw = static_cast<uint64_t>(*raw);
      }
      break;
    default:
      break;
  }
}

void read_fault(Checker& c, const toml::table& t, const std::string& path, Scenario& s) {
  FaultSpec f;
  f.line = t.source().begin.line;
  // The effect decides which keys belong.
  auto effect_text = c.string(t, path, "effect", true);
  if (!effect_text) {
    return;
  }
  auto effect = c.choice(t, path, "effect", true, kEffects, "fault effect");
  if (!effect) {
    return;
  }
  f.effect = *effect;
  std::vector<std::string_view> keys = {"at", "effect"};
  const auto allow = [&](std::initializer_list<std::string_view> more) {
    keys.insert(keys.end(), more.begin(), more.end());
  };
  if (is_frame_effect(f.effect)) {
    allow({"until", "bus", "match", "count", "probability"});
    if (f.effect != FaultEffect::ack_error) {
      allow({"bit"});
    }
  } else if (f.effect == FaultEffect::lin_responder_off) {
    allow({"node", "until", "match", "count"});
  } else if (f.effect == FaultEffect::lin_wakeup) {
    allow({"node", "pulse"});
  } else if (is_lin_frame_effect(f.effect)) {
    allow({"until", "bus", "match", "count"});
    if (f.effect == FaultEffect::lin_bit_error) {
      allow({"where"});
    }
  } else if (is_restbus_effect(f.effect)) {
    const std::vector<std::string_view> more = restbus_keys(f.effect);
    keys.insert(keys.end(), more.begin(), more.end());
  } else if (is_bus_effect(f.effect)) {
    allow({"bus", "duration"});
  } else if (f.effect == FaultEffect::random_errors) {
    allow({"bus", "until", "bit_error_rate"});
  } else {
    allow({"node"});
    if (f.effect == FaultEffect::node_off || f.effect == FaultEffect::oscillator ||
        f.effect == FaultEffect::line_error) {
      allow({"until"});
    }
    if (f.effect == FaultEffect::line_error) {
      allow({"wire"});
    }
    if (f.effect == FaultEffect::error_counters) {
      allow({"tec", "rec"});
    }
    if (f.effect == FaultEffect::oscillator) {
      allow({"ppm"});
    }
    if (f.effect == FaultEffect::babble) {
      allow({"id", "ext", "data", "duration"});
    }
  }
  c.only_keys(t, path, keys, fmt::format("not a key of {} (known: ", to_string(f.effect)));
  if (auto at = duration(c, t, path, "at", true)) {
    f.at_ns = *at;
  }
  if (t.get("until") != nullptr) {
    f.until_ns = duration(c, t, path, "until", false);
    if (f.until_ns && *f.until_ns <= f.at_ns) {
      c.error(*t.get("until"), path + ".until", "must be later than at");
    }
  }
  if (!is_node_effect(f.effect)) {
    if (auto bus = name(c, t, path, "bus", true)) {
      f.bus = *bus;
    }
  } else if (auto node = name(c, t, path, "node", true)) {
    f.node = *node;
  }
  if (is_lin_frame_effect(f.effect)) {
    read_lin_match(c, t, path, f);
    read_count(c, t, path, f);
    if (f.effect == FaultEffect::lin_bit_error) {
      f.lin_header = c.choice(t, path, "where", false, kLinWhere, "place").value_or(false);
    }
  }
  if (f.effect == FaultEffect::lin_wakeup) {
    if (t.get("pulse") != nullptr) {
      if (auto pulse = duration(c, t, path, "pulse", false)) {
        f.pulse_ns = *pulse;
        if (*pulse < 250'000 || *pulse > 5'000'000) {
          c.error(*t.get("pulse"), path + ".pulse",
                  "a LIN wake-up pulse lasts 250 us to 5 ms (LIN 2.x)");
        }
      }
    }
  }
  if (is_frame_effect(f.effect)) {
    read_match(c, t, path, f);
    read_count(c, t, path, f);
    if (auto bit = c.integer(t, path, "bit", false, 0, 735)) {
      f.bit = static_cast<uint16_t>(*bit);
    }
    if (auto p = c.number(t, path, "probability")) {
      if (!(*p > 0.0 && *p <= 1.0)) {
        c.error(*t.get("probability"), path + ".probability", "must be above 0 and at most 1");
      } else {
        f.probability = *p;
      }
    }
  }
  if (is_bus_effect(f.effect) || f.effect == FaultEffect::babble) {
    if (auto d = duration(c, t, path, "duration", true)) {
      f.duration_ns = *d;
      if (*d <= 0) {
        c.error(*t.get("duration"), path + ".duration", "must be above 0");
      }
    }
  }
  if (f.effect == FaultEffect::random_errors) {
    const toml::node* n = t.get("bit_error_rate");
    if (n == nullptr) {
      c.error(t.source(), path + ".bit_error_rate", "missing (a number is required)");
    } else if (auto rate = c.number(t, path, "bit_error_rate")) {
      if (!(*rate > 0.0 && *rate <= 0.1)) {
        c.error(*n, path + ".bit_error_rate", "must be above 0 and at most 0.1");
      } else {
        f.bit_error_rate = *rate;
      }
    }
  }
  if (f.effect == FaultEffect::error_counters) {
    if (auto tec = c.integer(t, path, "tec", true, 0, 255)) {
      f.tec = static_cast<uint16_t>(*tec);
    }
    if (auto rec = c.integer(t, path, "rec", true, 0, 255)) {
      f.rec = static_cast<uint16_t>(*rec);
    }
  }
  if (f.effect == FaultEffect::oscillator) {
    if (auto ppm = c.integer(t, path, "ppm", true, -500'000, 500'000)) {
      f.ppm = static_cast<int32_t>(*ppm);
    }
  }
  if (f.effect == FaultEffect::babble) {
    read_babble_frame(c, t, path, f);
  }
  if (f.effect == FaultEffect::line_error) {
    f.both_wires = c.choice(t, path, "wire", false, kWires, "wire fault").value_or(false);
  }
  if (is_restbus_effect(f.effect)) {
    read_restbus(c, t, path, f);
  }
  s.faults.push_back(f);
}

}  // namespace

bool is_lin_frame_effect(FaultEffect e) {
  return e >= FaultEffect::lin_bit_error && e <= FaultEffect::lin_responder_off;
}

bool is_restbus_effect(FaultEffect e) {
  return e >= FaultEffect::message_timeout && e <= FaultEffect::signal_invalid;
}

std::string_view to_string(FaultEffect effect) {
  return detail::name_of(effect, kEffects);
}

tl::expected<Scenario, std::vector<std::string>> parse_scenario(std::string_view text,
                                                                const std::string& source) {
  auto parsed = detail::parse_toml(text, source);
  if (!parsed) {
    return tl::unexpected(parsed.error());
  }
  const toml::table& root = *parsed;
  Checker c(source);
  Scenario s;
  s.source = source;
  c.only_keys(root, "", {"scenario", "fault"});
  if (const toml::table* head = c.section(root, "scenario")) {
    c.only_keys(*head, "scenario", {"name", "seed"});
    if (auto given = name(c, *head, "scenario", "name", false)) {
      s.name = *given;
    }
    if (auto seed = c.integer(*head, "scenario", "seed", false, 0, INT64_MAX)) {
      s.seed = static_cast<uint64_t>(*seed);
    }
  }
  c.for_each_table(root, "fault", [&](const toml::table& t, const std::string& path) {
    read_fault(c, t, path, s);
  });
  if (!c.errors().empty()) {
    return tl::unexpected(c.errors());
  }
  if (s.faults.empty()) {
    return tl::unexpected(std::vector<std::string>{
        fmt::format("{}: no [[fault]] tables: a scenario needs at least one", source)});
  }
  if (s.name.empty()) {
    const std::size_t slash = source.find_last_of('/');
    s.name = ipc::printable(source.substr(slash == std::string::npos ? 0 : slash + 1));
  }
  if (s.name.size() >= ipc::kScenarioNameSize) {  // the name `fault list` and `clear` use
    return tl::unexpected(std::vector<std::string>{
        fmt::format("{}: scenario name \"{}\": {} bytes; at most {} (the file name serves "
                    "when [scenario] has no name)",
                    source, s.name, s.name.size(), ipc::kScenarioNameSize - 1)});
  }
  return s;
}

tl::expected<Scenario, std::vector<std::string>> load_scenario_file(const std::string& path) {
  auto text = read_text_file(path);
  if (!text) {
    return tl::unexpected(std::vector<std::string>{text.error()});
  }
  return parse_scenario(*text, path);
}

}  // namespace canemu::daemon
