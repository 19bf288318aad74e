#include "fault_inject.hpp"

#include <cctype>
#include <sstream>
#include <tuple>

#include <fmt/format.h>
#include <toml++/toml.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

namespace canemu::cli {

namespace {

// A non-negative integer option, "0x1A0" (hexadecimal) or "416" (decimal).
tl::expected<int64_t, std::string> option_integer(const char* option, const std::string& text) {
  const bool hex = text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X');
  const std::string digits = hex ? text.substr(2) : text;
  std::size_t used = 0;
  int64_t value = -1;
  try {
    value = std::stoll(digits, &used, hex ? 16 : 10);
  } catch (const std::exception&) {
    used = 0;
  }
  if (digits.empty() || used != digits.size() || value < 0 || !std::isxdigit(digits[0])) {
    return tl::unexpected(fmt::format(
        "{} '{}': not a number (0x1A0 for hexadecimal, 416 for decimal)", option, text));
  }
  return value;
}

// An identifier or mask, in hex as candump writes identifiers (and as `send` and `gen -I` read
// them): "123" or "0x123" is 0x123, at most `max`.
tl::expected<int64_t, std::string> option_identifier(const char* option, const std::string& text,
                                                     uint32_t max, const char* why) {
  const bool prefixed = text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X');
  const std::string digits = prefixed ? text.substr(2) : text;
  if (digits.empty() || digits.size() > 8 ||
      digits.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos) {
    return tl::unexpected(fmt::format(
        "{} '{}': not a hex identifier (123 or 0x123, as candump writes it)", option, text));
  }
  const int64_t value = std::stoll(digits, nullptr, 16);
  if (value > max) {
    return tl::unexpected(fmt::format("{} '{}': above {:X}{}", option, text, max, why));
  }
  return value;
}

}  // namespace

void add_inject_options(CLI::App& inject, InjectOptions& o) {
  inject.add_option("--effect", o.effect, "bit_error, ack_suppress, node_off, ...")->required();
  inject.add_option("--at", o.at, "from now (default 0s)");
  inject.add_option("--until", o.until, "end of the window");
  inject.add_option("--bus", o.bus, "bus (frame and bus effects)");
  inject.add_option("--node", o.node, "node, DEVICE:N or a device's name");
  inject.add_option("--duration", o.duration, "ack_suppress, stuck_dominant, babble");
  inject.add_option("--from", o.from, "match: transmitting node");
  inject.add_option("--id", o.id, "match: identifier in hex (100 or 0x100); babble: its frame's");
  inject.add_option("--mask", o.mask, "match: identifier mask in hex (7FF or 0x7FF)");
  inject.add_flag("--ext", o.ext, "match: extended frames only; babble: 29-bit id");
  inject.add_flag("--std", o.std_id, "match: standard frames only");
  inject.add_flag("--rtr", o.rtr, "match: remote frames only");
  inject.add_flag("--data-frame", o.data_frame, "match: data frames only");
  inject.add_option("--bit", o.bit, "frame bit where the error hits (SOF = 0)");
  inject.add_option("--count", o.count, "matching frames to hit, or all (default)");
  inject.add_option("--probability", o.probability, "per matching frame");
  inject.add_option("--bit-error-rate", o.bit_error_rate, "random_errors, per bit");
  inject.add_option("--tec", o.tec, "error_counters");
  inject.add_option("--rec", o.rec, "error_counters");
  inject.add_option("--ppm", o.ppm, "oscillator");
  inject.add_option("--data", o.data, "babble: data bytes in hex (1122AABB)");
  inject.add_option("--wire", o.wire, "line_error: one (default) or both");
  inject.add_option("--where", o.where, "lin_bit_error: header or response (default)");
  inject.add_option("--pulse", o.pulse, "lin_wakeup: 250us (default) to 5ms");
  inject.add_option("--message", o.message,
                    "a simulated CAN node's message (message_timeout, ...)");
  inject.add_option("--signal", o.signal, "MESSAGE.SIGNAL (counter_freeze, signal_step, ...)");
  inject.add_option("--value", o.value, "signal_step, signal_invalid: physical value");
  inject.add_option("--raw", o.raw, "signal_invalid: the signal's bits (255 or 0xFF)");
  inject.add_option("--to", o.to, "signal_ramp: the value at --until");
  inject.add_option("--by", o.by, "counter_jump: values skipped");
  inject.footer(
      "Examples:\n"
      "  canemu fault inject --effect bit_error --bus can0 --id 1A0 --count 3\n"
      "  canemu fault inject --effect random_errors --bus can0 --bit-error-rate 1e-4 --until 2s\n"
      "  canemu fault inject --effect node_off --node ixxat0:1 --at 1s --until 1.5s\n"
      "  canemu fault inject --effect babble --node ixxat0:0 --id 0 --data DEADBEEF "
      "--duration 500ms\n"
      "  canemu fault inject --effect lin_checksum_error --bus lin0 --id 20 --count 1\n"
      "  canemu fault inject --effect lin_wakeup --node ixxat0:2 --at 10ms\n"
      "  canemu fault inject --effect checksum_error --bus can0 --message ENGINE_DATA --count 2\n"
      "  canemu fault inject --effect signal_ramp --bus can0 --signal ENGINE_DATA.SPEED --to 3000 "
      "--until 2s");
}

// Made with toml++ so that every value is quoted and escaped as TOML wants it.
tl::expected<std::string, std::string> inject_scenario(const InjectOptions& o) {
  toml::table fault{{"effect", o.effect}, {"at", o.at}};
  const auto put = [&](const char* key, const auto& v) {  // an option that was given
    if (v) {
      fault.insert(key, *v);
    }
  };
  put("until", o.until);
  put("bus", o.bus);
  put("node", o.node);
  put("duration", o.duration);
  put("wire", o.wire);
  put("where", o.where);
  put("pulse", o.pulse);
  put("bit", o.bit);
  put("tec", o.tec);
  put("rec", o.rec);
  put("ppm", o.ppm);
  put("probability", o.probability);
  put("bit_error_rate", o.bit_error_rate);
  put("message", o.message);
  put("signal", o.signal);
  put("value", o.value);
  put("to", o.to);
  put("by", o.by);
  if (o.raw) {
    auto n = option_integer("--raw", *o.raw);
    if (!n) {
      return tl::unexpected(n.error());
    }
    fault.insert("raw", *n);
  }
  if (o.count) {
    if (*o.count == "all") {
      fault.insert("count", "all");
    } else {
      auto n = option_integer("--count", *o.count);
      if (!n) {
        return tl::unexpected(n.error());
      }
      fault.insert("count", *n);
    }
  }
  // Identifiers and masks in hex; at most 29 bits, 11 for babble's standard frame, 6 on LIN.
  const bool lin = o.effect.starts_with("lin_");
  const bool standard_babble = o.effect == "babble" && !o.ext;
  const uint32_t id_max = lin ? 0x3F : standard_babble ? 0x7FF : 0x1FFFFFFF;
  const char* id_why = lin ? ", the largest LIN identifier"
                       : standard_babble
                           ? ", the largest 11-bit identifier (29-bit ones with --ext)"
                           : ", the largest 29-bit identifier";
  std::optional<int64_t> id, mask;
  for (auto [option, given, out, max, why] :
       {std::tuple{"--id", &o.id, &id, id_max, id_why},
        {"--mask", &o.mask, &mask, uint32_t{0x1FFFFFFF}, ", the largest 29-bit mask"}}) {
    if (*given) {
      auto n = option_identifier(option, **given, max, why);
      if (!n) {
        return tl::unexpected(n.error());
      }
      *out = *n;
    }
  }
  if (o.ext && o.std_id) {
    return tl::unexpected(std::string("--ext and --std: one or the other"));
  }
  if (o.rtr && o.data_frame) {
    return tl::unexpected(std::string("--rtr and --data-frame: one or the other"));
  }
  if (o.effect == "babble") {  // --id, --ext and --data describe the flooding frame
    if (o.std_id || o.rtr || o.data_frame || o.from || o.mask) {
      return tl::unexpected(std::string(
          "babble's frame is given by --id, --ext and --data; --std, --rtr, --data-frame, "
          "--from and --mask match frames of other effects"));
    }
    put("id", id);
    if (o.ext) {
      fault.insert("ext", true);
    }
    if (o.data) {
      const std::string& hex = *o.data;
      const auto bad = [&] {
        return tl::unexpected(
            fmt::format("--data '{}': hexadecimal bytes, two digits each (1122AABB)", hex));
      };
      if (hex.size() % 2 != 0) {
        return bad();
      }
      toml::array bytes;
      for (std::size_t i = 0; i < hex.size(); i += 2) {
        auto byte = option_integer("--data", "0x" + hex.substr(i, 2));
        if (!byte) {
          return bad();
        }
        bytes.push_back(*byte);
      }
      fault.insert("data", std::move(bytes));
    }
  } else {
    if (o.data) {
      return tl::unexpected(std::string("--data: only babble sends a frame of its own"));
    }
    toml::table match;
    if (id) {
      match.insert("id", *id);
    }
    if (mask) {
      match.insert("mask", *mask);
    }
    if (o.ext || o.std_id) {
      match.insert("ext", o.ext);
    }
    if (o.rtr || o.data_frame) {
      match.insert("rtr", o.rtr);
    }
    if (o.from) {
      match.insert("from", *o.from);
    }
    if (!match.empty()) {
      match.is_inline(true);
      fault.insert("match", std::move(match));
    }
  }
  toml::table scenario{{"scenario", toml::table{{"name", fmt::format("inject-{}", ::getpid())}}},
                       {"fault", toml::array{std::move(fault)}}};
  std::ostringstream out;
  out << scenario << "\n";
  return out.str();
}

}  // namespace canemu::cli
