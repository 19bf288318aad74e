// Reading [[can_node]] tables (can_node_config.hpp), checked with every problem reported. The
// bits a signal covers are worked out here (the config room includes no other room): the same
// numbering as restbus/signal_codec.hpp, as a set of payload bit positions.
#include "can_node_config_reader.hpp"

#include <bitset>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include <fmt/format.h>

#include "canemu/daemon/config/config.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "config/run_time_tables.hpp"

namespace canemu::daemon::detail {

namespace {

constexpr int64_t kMinCycleNs = 1'000'000;          // 1 ms
constexpr int64_t kMaxCycleNs = 3'600'000'000'000;  // 1 h: the longest cycle and delay
constexpr std::size_t kMaxNodeName = 28;            // fits the status's node names
constexpr std::size_t kMaxSignalName = 127;  // message and signal names: the protocol's 128 bytes

// Payload bit positions (byte * 8 + bit, bit 0 the least significant) of a 64-byte payload.
using Bits = std::bitset<model::kMaxFdLength * 8>;

constexpr NamedValue<CanMessageConfig::Send> kSends[] = {
    {CanMessageConfig::Send::cyclic, "cyclic"},
    {CanMessageConfig::Send::on_change, "on_change"},
    {CanMessageConfig::Send::cyclic_if_active, "cyclic_if_active"},
    {CanMessageConfig::Send::cyclic_and_on_change, "cyclic_and_on_change"},
};
constexpr NamedValue<SignalLayout::ByteOrder> kOrders[] = {
    {SignalLayout::ByteOrder::little_endian, "little_endian"},
    {SignalLayout::ByteOrder::big_endian, "big_endian"},
};
constexpr NamedValue<SignalLayout::Type> kTypes[] = {
    {SignalLayout::Type::integer, "integer"},
    {SignalLayout::Type::float32, "float32"},
    {SignalLayout::Type::float64, "float64"},
};
constexpr NamedValue<ChecksumKind> kChecksums[] = {
    {ChecksumKind::crc8_sae_j1850, "crc8_sae_j1850"},
    {ChecksumKind::xor8, "xor8"},
    {ChecksumKind::sum8, "sum8"},
};

// A node's name: a DBC node name, 1 to 28 letters, digits, '_' and '-'.
bool node_name_ok(std::string_view s) {
  if (s.empty() || s.size() > kMaxNodeName) {
    return false;
  }
  return std::all_of(s.begin(), s.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) != 0 || ch == '_' || ch == '-';
  });
}

// A message's or signal's name: a DBC identifier of 1 to 127 characters.
bool identifier_ok(std::string_view s) {
  if (s.empty() || s.size() > kMaxSignalName || std::isdigit(static_cast<unsigned char>(s[0]))) {
    return false;
  }
  return std::all_of(s.begin(), s.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) != 0 || ch == '_';
  });
}
constexpr std::string_view kIdentifierRule =
    "must be 1 to 127 letters, digits and '_', not starting with a digit (a DBC name)";

// The payload bits the signal covers, or nothing if one of them lies past `bytes` bytes.
// Little endian: `start` is the least significant bit, the signal goes up through the bytes.
// Big endian (DBC Motorola numbering): `start` is the most significant bit; from a byte's bit 0
// the next lower bit is bit 7 of the next byte.
std::optional<Bits> covered_bits(const SignalLayout& s, uint32_t bytes) {
  Bits bits;
  int64_t pos = s.start;
  for (uint32_t i = 0; i < s.length; ++i) {
    if (pos < 0 || pos >= int64_t{bytes} * 8) {
      return std::nullopt;
    }
    bits.set(static_cast<std::size_t>(pos));
    if (s.byte_order == SignalLayout::ByteOrder::little_endian) {
      ++pos;
    } else {
      pos = pos % 8 == 0 ? pos + 15 : pos - 1;
    }
  }
  return bits;
}

// Whether the integer signal's bits hold the physical value `v`.
bool holds(const SignalLayout& s, double v) {
  if (s.type == SignalLayout::Type::float32) {
    return std::isfinite(v) && std::fabs(v) <= std::numeric_limits<float>::max();
  }
  if (s.type == SignalLayout::Type::float64) {
    return std::isfinite(v);
  }
  const double raw = std::nearbyint((v - s.offset) / s.scale);
  const double span = std::ldexp(1.0, static_cast<int>(s.length));
  const double lo = s.is_signed ? -span / 2 : 0;
  const double hi = s.is_signed ? span / 2 - 1 : span - 1;
  return std::isfinite(raw) && raw >= lo && raw <= hi;
}

std::string number_text(double v) {
  return fmt::format("{}", v);
}

// A physical value key (`initial`, `inactive`): inside what the bits hold. Not checked against
// minimum..maximum: DBC files often start a signal at a code outside its range ("init", "not
// available"); the range is what values set at run time are checked against.
void check_value(Checker& c, const toml::table& t, const std::string& path, std::string_view key,
                 const CanSignalConfig& s, double v) {
  if (!holds(s.layout, v)) {
    c.error(*t.get(key), Checker::key(path, key),
            fmt::format("{} does not fit the signal's {} bits", number_text(v), s.layout.length));
  }
}

std::optional<bool> boolean(Checker& c, const toml::table& t, const std::string& path,
                            std::string_view key) {
  const toml::node* n = t.get(key);
  if (n == nullptr) {
    return std::nullopt;
  }
  if (!n->is_boolean()) {
    c.error(*n, Checker::key(path, key), "must be true or false");
    return std::nullopt;
  }
  return n->as_boolean()->get();
}

std::optional<int64_t> duration(Checker& c, const toml::table& t, const std::string& path,
                                std::string_view key, int64_t lo) {
  auto text = c.string(t, path, key, false);
  if (!text) {
    return std::nullopt;
  }
  auto ns = parse_duration(*text);
  if (!ns || *ns < lo || *ns > kMaxCycleNs) {
    c.error(*t.get(key), Checker::key(path, key),
            fmt::format("\"{}\" is not a duration from {} to 1h (examples: 10ms, 1s)", *text,
                        lo == 0 ? "0ms" : "1ms"));
    return std::nullopt;
  }
  return ns;
}

// One [[can_node.message.signal]]; its bits are checked by the message.
std::optional<CanSignalConfig> read_signal(Checker& c, const toml::table& t,
                                           const std::string& path) {
  c.only_keys(t, path,
              {"name", "start", "length", "byte_order", "signed", "type", "scale", "offset",
               "minimum", "maximum", "initial", "inactive", "unit", "multiplexer",
               "multiplexer_ids", "counter", "checksum", "data_id"});
  CanSignalConfig s;
  bool ok = true;
  if (auto name = c.string(t, path, "name", true)) {
    if (!identifier_ok(*name)) {
      c.error(*t.get("name"), path + ".name", kIdentifierRule);
    }
    s.name = *name;
  } else {
    ok = false;
  }
  SignalLayout& l = s.layout;
  if (auto type = c.choice(t, path, "type", false, kTypes, "signal type")) {
    l.type = *type;
  }
  const uint32_t width = l.type == SignalLayout::Type::float32   ? 32
                         : l.type == SignalLayout::Type::float64 ? 64
                                                                 : 0;
  auto start = c.integer(t, path, "start", true, 0, model::kMaxFdLength * 8 - 1);
  auto length = c.integer(t, path, "length", true, 1, 64);
  ok = ok && start && length;
  if (start) {
    l.start = static_cast<uint32_t>(*start);
  }
  if (length) {
    l.length = static_cast<uint32_t>(*length);
    if (width != 0 && l.length != width) {
      c.error(*t.get("length"), path + ".length",
              fmt::format("a {} signal has {} bits", name_of(l.type, kTypes), width));
      ok = false;
    }
  }
  if (auto order = c.choice(t, path, "byte_order", false, kOrders, "byte order")) {
    l.byte_order = *order;
  } else if (t.get("byte_order") != nullptr) {
    ok = false;
  }
  if (auto sign = boolean(c, t, path, "signed")) {
    l.is_signed = *sign;
    if (*sign && width != 0) {
      c.error(*t.get("signed"), path + ".signed", "only an integer signal is signed");
    }
  }
  if (auto scale = c.number(t, path, "scale")) {
    if (*scale == 0 || !std::isfinite(*scale)) {
      c.error(*t.get("scale"), path + ".scale", "must be a finite number other than 0");
      ok = false;
    }
    l.scale = *scale;
  }
  if (auto offset = c.number(t, path, "offset")) {
    l.offset = *offset;
  }
  s.minimum = c.number(t, path, "minimum");
  s.maximum = c.number(t, path, "maximum");
  if (s.minimum.has_value() != s.maximum.has_value()) {
    c.error(t.source(), path, "minimum and maximum go together (the range signal set checks)");
    s.minimum.reset();
    s.maximum.reset();
  } else if (s.minimum && *s.minimum > *s.maximum) {
    c.error(*t.get("minimum"), path + ".minimum",
            fmt::format("{} is greater than maximum {}", number_text(*s.minimum),
                        number_text(*s.maximum)));
    s.minimum.reset();
    s.maximum.reset();
  }
  if (auto unit = c.string(t, path, "unit", false)) {
    s.unit = *unit;
  }
  s.multiplexer = boolean(c, t, path, "multiplexer").value_or(false);
  if (const toml::node* n = t.get("multiplexer_ids")) {
    const toml::array* a = n->as_array();
    bool ids_ok = a != nullptr && !a->empty();
    if (ids_ok) {
      for (const toml::node& e : *a) {
        ids_ok = ids_ok && e.is_integer() && e.as_integer()->get() >= 0;
        if (ids_ok) {
          s.multiplexer_ids.push_back(static_cast<uint64_t>(e.as_integer()->get()));
        }
      }
    }
    if (!ids_ok) {
      c.error(*n, path + ".multiplexer_ids",
              "must be an array of 1 or more multiplexor values (integers from 0)");
      s.multiplexer_ids.clear();
    }
  }
  s.counter = boolean(c, t, path, "counter").value_or(false);
  if (auto kind = c.choice(t, path, "checksum", false, kChecksums, "checksum kind")) {
    s.checksum = *kind;
  }
  if (auto id = c.integer(t, path, "data_id", false, 0, 65535)) {
    s.data_id = static_cast<uint16_t>(*id);
    if (s.checksum != ChecksumKind::crc8_sae_j1850) {
      c.error(*t.get("data_id"), path + ".data_id",
              "only a checksum = \"crc8_sae_j1850\" signal has a data ID");
    }
  }
  const int roles = int{s.multiplexer} + int{s.counter} + int{s.checksum != ChecksumKind::none};
  if (roles > 1) {
    c.error(t.source(), path, "a signal is at most one of multiplexer, counter and checksum");
  }
  if (roles > 0 && (width != 0 || l.is_signed)) {
    c.error(t.source(), path,
            "a multiplexer, counter or checksum is an unsigned integer signal (signed = false, "
            "type = \"integer\")");
  }
  if ((s.multiplexer || s.counter || s.checksum != ChecksumKind::none) &&
      !s.multiplexer_ids.empty()) {
    c.error(*t.get("multiplexer_ids"), path + ".multiplexer_ids",
            "a multiplexer, counter or checksum is in every frame; it has no multiplexer_ids");
  }
  if (s.checksum != ChecksumKind::none && ok) {
    const uint32_t lsb = l.byte_order == SignalLayout::ByteOrder::little_endian ? 0 : 7;
    if (l.length != 8 || l.start % 8 != lsb) {
      c.error(t.source(), path,
              fmt::format("a checksum is one whole byte: length = 8 and start a multiple of 8{}",
                          lsb == 0 ? "" : " plus 7 (big_endian)"));
    }
  }
  if (!ok) {
    return std::nullopt;
  }
  if (auto initial = c.number(t, path, "initial")) {
    s.initial = *initial;
    check_value(c, t, path, "initial", s, *initial);
  }
  if (auto inactive = c.number(t, path, "inactive")) {
    s.inactive = *inactive;
    check_value(c, t, path, "inactive", s, *inactive);
  }
  return s;
}

// Whether two signals of one message can be in one frame: both always, or a multiplexor value
// for which both are.
bool together(const CanSignalConfig& a, const CanSignalConfig& b) {
  if (a.multiplexer_ids.empty() || b.multiplexer_ids.empty()) {
    return true;
  }
  return std::any_of(a.multiplexer_ids.begin(), a.multiplexer_ids.end(), [&](uint64_t v) {
    return std::find(b.multiplexer_ids.begin(), b.multiplexer_ids.end(), v) !=
           b.multiplexer_ids.end();
  });
}

void read_message(Checker& c, const toml::table& t, const std::string& path, const BusConfig* bus,
                  CanNodeConfig& node) {
  c.only_keys(
      t, path,
      {"name", "id", "extended", "fd", "brs", "length", "send", "cycle", "delay", "signal"});
  CanMessageConfig m;
  if (auto name = c.string(t, path, "name", true)) {
    if (!identifier_ok(*name)) {
      c.error(*t.get("name"), path + ".name", kIdentifierRule);
    }
    for (const CanMessageConfig& other : node.messages) {
      if (other.name == *name) {
        c.error(*t.get("name"), path + ".name",
                fmt::format("the node has a message named \"{}\" already", *name));
      }
    }
    m.name = *name;
  }
  m.extended = boolean(c, t, path, "extended").value_or(false);
  if (auto id = c.integer(t, path, "id", true, 0, m.extended ? 0x1FFFFFFF : 0x7FF)) {
    m.id = static_cast<uint32_t>(*id);
    for (const CanMessageConfig& other : node.messages) {
      if (other.id == m.id && other.extended == m.extended) {
        c.error(*t.get("id"), path + ".id",
                fmt::format("the node sends message {} with {} identifier {:#x} already",
                            other.name, m.extended ? "extended" : "standard", m.id));
      }
    }
  }
  m.fd = boolean(c, t, path, "fd").value_or(false);
  m.brs = boolean(c, t, path, "brs").value_or(false);
  if (m.fd && bus != nullptr && bus->kind != BusKind::can_fd) {
    c.error(
        *t.get("fd"), path + ".fd",
        fmt::format("\"{}\" is a classic CAN bus; a CAN FD message needs a can-fd bus", bus->name));
  }
  if (m.brs && !m.fd) {
    c.error(*t.get("brs"), path + ".brs", "only a CAN FD message (fd = true) switches bit rate");
  }
  bool length_ok = false;
  if (t.get("length") == nullptr) {
    length_ok = true;  // 8 bytes
  } else if (auto length = c.integer(t, path, "length", true, 0, model::kMaxFdLength)) {
    length_ok = model::length_to_dlc(static_cast<std::size_t>(*length), m.fd).has_value();
    if (!length_ok) {
      c.error(
          *t.get("length"), path + ".length",
          m.fd ? fmt::format("{} is not a CAN FD length (0 to 8, 12, 16, 20, 24, 32, 48, 64)",
                             *length)
               : fmt::format("{} bytes: a classic frame has 0 to 8 (fd = true for more)", *length));
    }
    m.length = static_cast<uint32_t>(*length);
  }
  if (auto send = c.choice(t, path, "send", false, kSends, "send kind")) {
    m.send = *send;
  }
  const bool cyclic = m.send != CanMessageConfig::Send::on_change;
  if (auto cycle = duration(c, t, path, "cycle", kMinCycleNs)) {
    m.cycle_ns = *cycle;
    if (!cyclic) {
      c.error(*t.get("cycle"), path + ".cycle", "an on_change message has no cycle");
    }
  } else if (cyclic && t.get("cycle") == nullptr) {
    c.error(t.source(), path + ".cycle",
            fmt::format("missing (a {} message needs its cycle, e.g. \"100ms\")",
                        name_of(m.send, kSends)));
  }
  if (auto delay = duration(c, t, path, "delay", 0)) {
    m.delay_ns = *delay;
  }
  std::vector<std::pair<Bits, std::string>> placed;  // each signal's bits, its path
  c.each_nested(t, path, "signal", [&](const toml::table& st, const std::string& p) {
    auto s = read_signal(c, st, p);
    if (!s) {
      return;
    }
    for (const CanSignalConfig& other : m.signals) {
      if (other.name == s->name) {
        c.error(*st.get("name"), p + ".name",
                fmt::format("the message has a signal named \"{}\" already", s->name));
      }
    }
    if (s->multiplexer && std::any_of(m.signals.begin(), m.signals.end(),
                                      [](const CanSignalConfig& o) { return o.multiplexer; })) {
      c.error(*st.get("multiplexer"), p + ".multiplexer", "the message has a multiplexer already");
    }
    if (s->checksum != ChecksumKind::none &&
        std::any_of(m.signals.begin(), m.signals.end(),
                    [](const CanSignalConfig& o) { return o.checksum != ChecksumKind::none; })) {
      c.error(*st.get("checksum"), p + ".checksum", "the message has a checksum already");
    }
    if (length_ok) {
      const auto bits = covered_bits(s->layout, m.length);
      if (!bits) {
        c.error(st.source(), p,
                fmt::format("signal {} ({} bits from bit {}, {}) does not fit the message's {} "
                            "bytes",
                            s->name, s->layout.length, s->layout.start,
                            name_of(s->layout.byte_order, kOrders), m.length));
      } else {
        for (std::size_t i = 0; i < placed.size(); ++i) {
          if ((placed[i].first & *bits).any() && together(m.signals[i], *s)) {
            c.error(st.source(), p,
                    fmt::format("signal {} shares bits with signal {} ({}) in the same frames",
                                s->name, m.signals[i].name, placed[i].second));
            break;
          }
        }
      }
      placed.emplace_back(bits.value_or(Bits{}), p);
    } else {
      placed.emplace_back(Bits{}, p);
    }
    m.signals.push_back(std::move(*s));
  });
  const bool has_mux = std::any_of(m.signals.begin(), m.signals.end(),
                                   [](const CanSignalConfig& s) { return s.multiplexer; });
  const bool has_inactive = std::any_of(m.signals.begin(), m.signals.end(),
                                        [](const CanSignalConfig& s) { return s.inactive; });
  for (std::size_t i = 0; i < m.signals.size(); ++i) {
    if (!has_mux && !m.signals[i].multiplexer_ids.empty()) {
      c.error(t.source(), placed[i].second + ".multiplexer_ids",
              "the message has no multiplexer (multiplexer = true on one signal)");
    }
  }
  if (m.send == CanMessageConfig::Send::cyclic_if_active && !has_inactive) {
    c.error(*t.get("send"), path + ".send",
            "a cyclic_if_active message needs a signal with an inactive value (inactive = ...)");
  }
  node.messages.push_back(std::move(m));
}

}  // namespace

void read_can_nodes(Checker& c, const toml::table& root, Config& cfg) {
  std::set<std::string> names;
  // Per bus: each message's name and identifier, and which node sends it.
  std::map<std::string, std::string> message_names;
  std::map<std::pair<std::string, uint64_t>, std::string> message_ids;
  c.for_each_table(root, "can_node", [&](const toml::table& t, const std::string& path) {
    c.only_keys(t, path, {"name", "bus", "powered", "message"});
    CanNodeConfig node;
    node.line = static_cast<uint32_t>(t.source().begin.line);
    const auto name = c.string(t, path, "name", true);
    const bool name_ok = name && node_name_ok(*name);
    if (name && !name_ok) {
      c.error(*t.get("name"), path + ".name",
              "must be 1 to 28 letters, digits, '_' and '-' (a DBC node name)");
    }
    if (name) {
      node.name = *name;
    }
    const BusConfig* bus = nullptr;
    if (auto b = c.string(t, path, "bus", true)) {
      bus = cfg.bus(*b);
      if (bus == nullptr) {
        c.error(*t.get("bus"), path + ".bus", fmt::format("no bus is named \"{}\"", *b));
      } else if (bus->kind == BusKind::lin) {
        c.error(*t.get("bus"), path + ".bus",
                fmt::format("\"{}\" is a LIN bus; a CAN node needs a CAN or CAN FD bus "
                            "([[lin_node]] simulates LIN nodes)",
                            *b));
        bus = nullptr;
      }
      node.bus = *b;
    }
    // Names are scoped by bus, as [[lin_node]]'s.
    if (name_ok && !names.insert(node.bus + "/" + *name).second) {
      c.error(*t.get("name"), path + ".name",
              fmt::format("a CAN node named \"{}\" exists on \"{}\" already", *name, node.bus));
    }
    node.powered = boolean(c, t, path, "powered").value_or(true);
    c.each_nested(t, path, "message", [&](const toml::table& m, const std::string& p) {
      const std::size_t before = node.messages.size();
      read_message(c, m, p, bus, node);
      if (node.messages.size() == before || node.name.empty() || m.get("name") == nullptr ||
          m.get("id") == nullptr) {
        return;
      }
      // A bus's messages are found by name (`canemu signal set BUS MESSAGE.SIGNAL`), and two
      // nodes sending one identifier would collide on the wire.
      const CanMessageConfig& msg = node.messages.back();
      const auto by_name = message_names.emplace(node.bus + "/" + msg.name, node.name);
      if (!by_name.second && by_name.first->second != node.name) {
        c.error(*m.get("name"), p + ".name",
                fmt::format("node {} sends a message named \"{}\" on \"{}\" already",
                            by_name.first->second, msg.name, node.bus));
      }
      const uint64_t key = (uint64_t{msg.extended} << 32) | msg.id;
      const auto by_id = message_ids.emplace(std::make_pair(node.bus, key), node.name);
      if (!by_id.second && by_id.first->second != node.name) {
        c.error(*m.get("id"), p + ".id",
                fmt::format("node {} sends identifier {:#x} on \"{}\" already (two senders "
                            "of one identifier collide on the wire)",
                            by_id.first->second, msg.id, node.bus));
      }
    });
    cfg.can_nodes.push_back(std::move(node));
  });
}

}  // namespace canemu::daemon::detail

namespace canemu::daemon {

tl::expected<std::vector<CanNodeConfig>, std::vector<std::string>> parse_can_nodes(
    std::string_view text, const std::string& source, const std::vector<BusConfig>& buses) {
  return detail::run_time_tables(text, source, buses, "can_node", detail::read_can_nodes,
                                 &Config::can_nodes);
}

}  // namespace canemu::daemon
