// canemu: the command-line tool. status and time talk to canemud over its control socket;
// send and dump open a channel on an ephemeral device; calc works offline on the wire model.
#include <cctype>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <toml++/toml.h>
#include <unistd.h>
#include <CLI/CLI.hpp>
#include <tl/expected.hpp>

#include "canemu/client/channel.hpp"
#include "canemu/client/connection.hpp"
#include "canemu/daemon/channel.hpp"
#include "canemu/daemon/config.hpp"
#include "canemu/daemon/frame_text.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace {

using namespace canemu;

constexpr const char* kStates[] = {"error-active", "warning", "error-passive", "bus-off"};
constexpr const char* kKinds[] = {"can", "can-fd", "lin"};
constexpr const char* kModes[] = {"realtime", "scaled", "stepped"};
constexpr const char* kModels[] = {"ixxat-usb-to-can", "ixxat-usb-to-can-fd", "ephemeral"};

int fail(const std::string& message) {
  std::fprintf(stderr, "canemu: %s\n", message.c_str());
  return 1;
}

// A positive duration for the command line (see daemon::parse_duration).
std::optional<int64_t> parse_duration(const std::string& text) {
  const auto ns = daemon::parse_duration(text);
  return ns && *ns > 0 ? ns : std::nullopt;
}

void print_faults(const ipc::FaultListReply& r);
std::string faults_json(const ipc::FaultListReply& r);
tl::expected<ipc::FaultListReply, std::string> fault_list(client::Connection& c);

int cmd_status(const std::string& socket, bool json) {
  auto c = client::Connection::open(ipc::socket_path(socket), "canemu status");
  if (!c) {
    return fail(c.error().message);
  }
  auto reply =
      c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
  if (!reply) {
    return fail(reply.error().message);
  }
  const ipc::StatusReply& s = *reply;
  auto devices = c->call<ipc::DeviceListRequest, ipc::DeviceListReply>(
      ipc::make_message<ipc::DeviceListRequest>());
  auto clients = c->call<ipc::ClientListRequest, ipc::ClientListReply>(
      ipc::make_message<ipc::ClientListRequest>());
  if (!devices || !clients) {
    return fail(!devices ? devices.error().message : clients.error().message);
  }
  auto faults = fault_list(*c);
  if (!faults) {
    return fail(faults.error());
  }
  const auto device_buses = [](const ipc::DeviceEntry& d) {
    std::vector<std::string> buses;
    for (uint8_t k = 0; k < d.controller_count && k < ipc::kMaxDeviceControllers; ++k) {
      buses.push_back(ipc::name_of(d.buses[k]));
    }
    return buses;
  };
  const char* mode = s.time_mode < 3 ? kModes[s.time_mode] : "?";
  if (json) {
    std::string out = fmt::format(
        "{{\"server_pid\":{},\"time_mode\":\"{}\",\"time_scale\":{},\"sim_time_ns\":{},"
        "\"clients\":{},\"buses\":[",
        c->server_pid(), mode, s.time_scale, s.sim_time_ns, s.client_count);
    for (uint16_t i = 0; i < s.bus_count; ++i) {
      const ipc::StatusBus& b = s.buses[i];
      out += fmt::format(
          "{}{{\"name\":\"{}\",\"kind\":\"{}\",\"transceiver\":\"{}\",\"bitrate\":{},"
          "\"data_bitrate\":{},\"load_percent\":{:.1f},\"frames\":{},\"error_frames\":{}}}",
          i ? "," : "", ipc::name_of(b.name), b.kind < 3 ? kKinds[b.kind] : "?",
          b.low_speed ? "low-speed" : "high-speed", b.bitrate, b.data_bitrate,
          b.load_permille / 10.0, b.frames, b.error_frames);
    }
    out += "],\"nodes\":[";
    for (uint16_t i = 0; i < s.node_count; ++i) {
      const ipc::StatusNode& n = s.nodes[i];
      out += fmt::format(
          "{}{{\"name\":\"{}\",\"bus\":\"{}\",\"state\":\"{}\",\"tec\":{},\"rec\":{},"
          "\"frames_sent\":{},\"frames_received\":{},\"errors\":{}}}",
          i ? "," : "", ipc::name_of(n.name),
          n.bus < s.bus_count ? ipc::name_of(s.buses[n.bus].name) : "?",
          n.state < 4 ? kStates[n.state] : "?", n.tec, n.rec, n.frames_sent, n.frames_received,
          n.errors);
    }
    out += "],\"devices\":[";
    for (uint16_t i = 0; i < devices->count; ++i) {
      const ipc::DeviceEntry& d = devices->devices[i];
      std::string buses;
      for (const std::string& b : device_buses(d)) {
        buses += fmt::format("{}\"{}\"", buses.empty() ? "" : ",", b);
      }
      out += fmt::format(
          "{}{{\"name\":\"{}\",\"model\":\"{}\",\"ephemeral\":{},"
          "\"owner_pid\":{},\"buses\":[{}]}}",
          i ? "," : "", ipc::name_of(d.name), d.model < 3 ? kModels[d.model] : "?",
          d.ephemeral ? "true" : "false", d.owner_pid, buses);
    }
    out += "],\"client_list\":[";
    for (uint16_t i = 0; i < clients->count; ++i) {
      const ipc::ClientEntry& e = clients->clients[i];
      out += fmt::format("{}{{\"name\":\"{}\",\"pid\":{},\"uid\":{},\"channels\":{}}}",
                         i ? "," : "", ipc::name_of(e.name), e.pid, e.uid, e.channels);
    }
    out += "],\"faults\":" + faults_json(*faults) + "}\n";
    std::fputs(out.c_str(), stdout);
    return 0;
  }
  std::printf("canemud pid %u, time %s, simulated %.9f s, %u client%s\n", c->server_pid(), mode,
              static_cast<double>(s.sim_time_ns) / 1e9, s.client_count,
              s.client_count == 1 ? "" : "s");
  std::printf("%-12s %-7s %9s %9s %7s %10s %8s\n", "BUS", "KIND", "BITRATE", "DATA", "LOAD",
              "FRAMES", "ERRORS");
  for (uint16_t i = 0; i < s.bus_count; ++i) {
    const ipc::StatusBus& b = s.buses[i];
    const std::string kind =
        std::string(b.kind < 3 ? kKinds[b.kind] : "?") + (b.low_speed ? "-ls" : "");
    std::printf("%-12s %-7s %9u %9u %6.1f%% %10llu %8llu\n", ipc::name_of(b.name).c_str(),
                kind.c_str(), b.bitrate, b.data_bitrate, b.load_permille / 10.0,
                static_cast<unsigned long long>(b.frames),
                static_cast<unsigned long long>(b.error_frames));
  }
  std::printf("%-14s %-12s %-14s %4s %4s %10s %10s %8s\n", "NODE", "BUS", "STATE", "TEC", "REC",
              "SENT", "RECEIVED", "ERRORS");
  for (uint16_t i = 0; i < s.node_count; ++i) {
    const ipc::StatusNode& n = s.nodes[i];
    std::printf("%-14s %-12s %-14s %4u %4u %10llu %10llu %8llu\n", ipc::name_of(n.name).c_str(),
                n.bus < s.bus_count ? ipc::name_of(s.buses[n.bus].name).c_str() : "?",
                n.state < 4 ? kStates[n.state] : "?", n.tec, n.rec,
                static_cast<unsigned long long>(n.frames_sent),
                static_cast<unsigned long long>(n.frames_received),
                static_cast<unsigned long long>(n.errors));
  }
  std::printf("%-14s %-20s %-8s %s\n", "DEVICE", "MODEL", "OWNER", "BUSES");
  for (uint16_t i = 0; i < devices->count; ++i) {
    const ipc::DeviceEntry& d = devices->devices[i];
    std::string buses;
    for (const std::string& b : device_buses(d)) {
      buses += (buses.empty() ? "" : " ") + b;
    }
    std::printf("%-14s %-20s %-8s %s\n", ipc::name_of(d.name).c_str(),
                d.model < 3 ? kModels[d.model] : "?",
                d.ephemeral ? std::to_string(d.owner_pid).c_str() : "config", buses.c_str());
  }
  std::printf("%-20s %8s %8s %8s\n", "CLIENT", "PID", "UID", "CHANNELS");
  for (uint16_t i = 0; i < clients->count; ++i) {
    const ipc::ClientEntry& e = clients->clients[i];
    std::printf("%-20s %8u %8u %8u\n", ipc::name_of(e.name).c_str(), e.pid, e.uid, e.channels);
  }
  if (faults->total > 0) {
    print_faults(*faults);
  }
  return 0;
}

volatile std::sig_atomic_t g_stop = 0;

void on_stop_signal(int) {
  g_stop = 1;
}

struct SendOptions {
  std::string bus;
  std::vector<std::string> frames;
  uint32_t bitrate = 0;
  std::string step;
  int timeout_ms = 2000;
};

int cmd_send(const std::string& socket, const SendOptions& o) {
  std::vector<ipc::ChannelMessage> messages;
  for (const std::string& text : o.frames) {
    std::string error;
    auto m = daemon::parse_cansend(text, error);
    if (!m) {
      return fail(fmt::format("'{}': {}", text, error));
    }
    messages.push_back(*m);
  }
  std::optional<int64_t> step_ns;
  if (!o.step.empty()) {
    step_ns = parse_duration(o.step);
    if (!step_ns) {
      return fail(fmt::format("'{}' is not a duration (examples: 150ns, 20us, 10ms, 2s)", o.step));
    }
  }
  auto c = client::Connection::open(ipc::socket_path(socket), "canemu send");
  if (!c) {
    return fail(c.error().message);
  }
  auto s = c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
  if (!s) {
    return fail(s.error().message);
  }
  const bool stepped = s->time_mode == static_cast<uint8_t>(ipc::WireTimeMode::stepped);
  if (stepped && !step_ns) {
    return fail(
        "simulated time is stepped: frames go out only while time moves; add --step "
        "DURATION to step after queueing them");
  }
  if (!stepped && step_ns) {
    return fail("--step needs stepped time; canemud runs " + std::string(kModes[s->time_mode]));
  }
  client::ChannelOptions co;
  co.bus = o.bus;
  co.bitrate = o.bitrate;
  co.flags = ipc::kChannelReportTx;
  co.tx_capacity = static_cast<uint32_t>(messages.size());
  auto ch = client::Channel::open(*c, co);
  if (!ch) {
    return fail(ch.error().message);
  }
  for (const ipc::ChannelMessage& m : messages) {
    auto sent = ch->send(m, o.timeout_ms);
    if (!sent) {
      return fail(sent.error().message);
    }
  }
  if (step_ns) {
    auto req = ipc::make_message<ipc::TimeStepRequest>();
    req.step_ns = *step_ns;
    auto r = c->call<ipc::TimeStepRequest, ipc::TimeStepReply>(req);
    if (!r) {
      return fail(r.error().message);
    }
  }
  // One confirmation per frame: sent (printed as candump would log it) or given up.
  int failed = 0;
  for (std::size_t done = 0; done < messages.size();) {
    auto m = ch->receive(stepped ? 0 : o.timeout_ms);
    if (!m) {
      return fail(
          fmt::format("{} of {} frame(s) not sent {}: is a node on {} acknowledging at "
                      "{} bit/s?",
                      messages.size() - done, messages.size(),
                      stepped ? "within the step" : "in time", o.bus, ch->info().bitrate));
    }
    if (m->kind == static_cast<uint8_t>(ipc::ChannelMessageKind::tx_done)) {
      m->kind = static_cast<uint8_t>(ipc::ChannelMessageKind::frame);
      std::printf("%s\n", daemon::candump_line(*m, o.bus).c_str());
      ++done;
    } else if (m->kind == static_cast<uint8_t>(ipc::ChannelMessageKind::tx_dropped)) {
      m->kind = static_cast<uint8_t>(ipc::ChannelMessageKind::frame);
      std::fprintf(stderr,
                   "canemu: %s: not sent (given up after an error, or a CAN FD frame on a classic "
                   "CAN bus)\n",
                   daemon::candump_frame(*m).c_str());
      ++failed;
      ++done;
    }
  }
  return failed == 0 ? 0 : 1;
}

// Sends a scenario's text; prints what was applied or every problem.
int load_scenario_text(const std::string& socket, const std::string& source,
                       const std::string& text) {
  if (text.size() > ipc::kMaxScenarioText) {
    return fail(fmt::format("{}: {} bytes; a scenario sent to canemud is at most {}", source,
                            text.size(), ipc::kMaxScenarioText));
  }
  auto c = client::Connection::open(ipc::socket_path(socket), "canemu fault");
  if (!c) {
    return fail(c.error().message);
  }
  auto m = std::make_unique<ipc::FaultLoadRequest>(ipc::make_message<ipc::FaultLoadRequest>());
  ipc::copy_name(m->source, source);
  m->length = static_cast<uint32_t>(text.size());
  std::memcpy(m->text, text.data(), text.size());
  auto r = c->call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(*m);
  if (!r) {
    return fail(r.error().message);
  }
  if (!r->applied) {
    std::fputs(ipc::name_of(r->errors).c_str(), stderr);
    return fail("scenario rejected; nothing of it applied");
  }
  std::printf("scenario \"%s\": %u fault%s applied\n", ipc::name_of(r->name).c_str(), r->faults,
              r->faults == 1 ? "" : "s");
  return 0;
}

int cmd_fault_load(const std::string& socket, const std::string& file) {
  auto text = daemon::read_text_file(file);
  if (!text) {
    return fail(fmt::format("{}: cannot be read", file));
  }
  return load_scenario_text(socket, file, *text);
}

constexpr const char* kFaultStates[] = {"pending", "active", "done", "cleared"};

// Every fault canemud applied, one line each (canemu fault list, canemu status).
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
                e.state < 4 ? kFaultStates[e.state] : "?");
  }
  if (r.total > r.count) {
    std::printf("(%u more not shown)\n", r.total - r.count);
  }
}

// The same as a JSON array (toml++ writes it: names are escaped as JSON wants them).
std::string faults_json(const ipc::FaultListReply& r) {
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
                  {"state", e.state < 4 ? kFaultStates[e.state] : "?"}};
    if (e.has_until) {
      t.insert("until_ns", e.until_ns);
    }
    faults.push_back(std::move(t));
  }
  std::ostringstream out;
  out << toml::json_formatter{faults, toml::format_flags::none};
  std::string text = out.str();
  std::erase(text, '\n');
  return text;
}

tl::expected<ipc::FaultListReply, std::string> fault_list(client::Connection& c) {
  auto r = c.call<ipc::FaultListRequest, ipc::FaultListReply>(
      ipc::make_message<ipc::FaultListRequest>());
  if (!r) {
    return tl::unexpected(r.error().message);
  }
  return *r;
}

int cmd_fault_list(const std::string& socket) {
  auto c = client::Connection::open(ipc::socket_path(socket), "canemu fault");
  if (!c) {
    return fail(c.error().message);
  }
  auto r = fault_list(*c);
  if (!r) {
    return fail(r.error());
  }
  print_faults(*r);
  return 0;
}

int cmd_fault_clear(const std::string& socket, const std::string& name) {
  auto c = client::Connection::open(ipc::socket_path(socket), "canemu fault");
  if (!c) {
    return fail(c.error().message);
  }
  auto m = ipc::make_message<ipc::FaultClearRequest>();
  ipc::copy_name(m.scenario, name == "all" ? std::string() : name);
  auto r = c->call<ipc::FaultClearRequest, ipc::FaultClearReply>(m);
  if (!r) {
    return fail(r.error().message);
  }
  std::printf("%u scenario%s cleared\n", r->cleared, r->cleared == 1 ? "" : "s");
  return 0;
}

// One fault from the command line, in the scenario language's own keys. Strings stay as typed
// (canemud checks them as it checks a file); numbers are read here.
struct InjectOptions {
  std::string effect;
  std::string at = "0s";
  std::optional<std::string> until, bus, node, duration, from, wire;
  std::optional<std::string> id, mask;  // 0x1A0 or 416
  bool ext = false;
  bool std_id = false;
  bool rtr = false;
  bool data_frame = false;
  std::optional<int64_t> bit, tec, rec, ppm;
  std::optional<std::string> count;  // a number or "all"
  std::optional<double> probability, bit_error_rate;
  std::optional<std::string> data;  // babble: hex bytes
};

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

// The scenario text of one injected fault: a file of the language (docs/faults.md), made with
// toml++ so that every value is quoted and escaped as TOML wants it.
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
  put("bit", o.bit);
  put("tec", o.tec);
  put("rec", o.rec);
  put("ppm", o.ppm);
  put("probability", o.probability);
  put("bit_error_rate", o.bit_error_rate);
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
  std::optional<int64_t> id, mask;
  for (auto [option, given, out] : {std::tuple{"--id", &o.id, &id}, {"--mask", &o.mask, &mask}}) {
    if (*given) {
      auto n = option_integer(option, **given);
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

int cmd_fault_inject(const std::string& socket, const InjectOptions& o) {
  auto text = inject_scenario(o);
  if (!text) {
    return fail(text.error());
  }
  return load_scenario_text(socket, "<command line>", *text);
}

struct DumpOptions {
  std::string bus;
  uint32_t bitrate = 0;
  uint64_t count = 0;  // 0: until interrupted
  bool errors = true;
};

int cmd_dump(const std::string& socket, const DumpOptions& o) {
  auto c = client::Connection::open(ipc::socket_path(socket), "canemu dump");
  if (!c) {
    return fail(c.error().message);
  }
  client::ChannelOptions co;
  co.bus = o.bus;
  co.bitrate = o.bitrate;
  co.flags = ipc::kChannelListenOnly | (o.errors ? ipc::kChannelReportErrors : 0);
  co.rx_capacity = 4096;
  auto ch = client::Channel::open(*c, co);
  if (!ch) {
    return fail(ch.error().message);
  }
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  std::fprintf(stderr, "canemu: listening on %s as %s (listen-only, %u bit/s)\n", o.bus.c_str(),
               ch->device().c_str(), ch->info().bitrate);
  uint64_t printed = 0;
  while (!g_stop && (o.count == 0 || printed < o.count)) {
    auto m = ch->receive(200);
    if (!m) {
      continue;
    }
    if (m->lost_before != 0) {
      std::fprintf(stderr, "canemu: %u message(s) lost: the output did not keep up\n",
                   m->lost_before);
    }
    const std::string frame = daemon::candump_frame(*m);
    if (frame.empty()) {
      continue;
    }
    std::printf("%s\n", daemon::candump_line(*m, o.bus).c_str());
    std::fflush(stdout);
    ++printed;
  }
  return 0;
}

int cmd_time_step(const std::string& socket, const std::string& duration) {
  const auto ns = parse_duration(duration);
  if (!ns) {
    return fail(fmt::format("'{}' is not a duration (examples: 150ns, 20us, 10ms, 2s)", duration));
  }
  auto c = client::Connection::open(ipc::socket_path(socket), "canemu time");
  if (!c) {
    return fail(c.error().message);
  }
  auto req = ipc::make_message<ipc::TimeStepRequest>();
  req.step_ns = *ns;
  auto reply = c->call<ipc::TimeStepRequest, ipc::TimeStepReply>(req);
  if (!reply) {
    return fail(reply.error().message);
  }
  std::printf("simulated time %.9f s (%llu events)\n",
              static_cast<double>(reply->sim_time_ns) / 1e9,
              static_cast<unsigned long long>(reply->events_run));
  return 0;
}

int cmd_calc_frame(const std::string& text, uint32_t bitrate, uint32_t data_bitrate) {
  std::string error;
  auto message = daemon::parse_cansend(text, error);
  if (!message) {
    return fail(fmt::format("'{}': {}", text, error));
  }
  const model::EncodedFrame e = model::encode(daemon::to_tx_frame(*message)->frame);
  std::array<model::FieldSpan, 19> fields;
  const uint8_t n = e.fields(fields);
  for (uint8_t k = 0; k < n; ++k) {
    const uint16_t end = k + 1 < n ? fields[k + 1].begin : e.length;
    std::string bits;
    for (uint16_t i = fields[k].begin; i < end; ++i) {
      bits += e.is_stuff(i) ? (e.level_at(i) ? "[1]" : "[0]") : (e.level_at(i) ? "1" : "0");
    }
    std::printf("%-8s %s\n", std::string(model::to_string(fields[k].field)).c_str(), bits.c_str());
  }
  const model::BitCounts counts = model::bit_counts(e);
  std::printf("bits: %u (+%u intermission), stuff bits: %u dynamic, %u fixed; CRC-%u 0x%X\n",
              e.length, model::kIntermissionBits, e.dynamic_stuff_bits, e.fixed_stuff_bits,
              e.crc_bits, e.crc);
  if (bitrate == 0 || data_bitrate == 0) {
    return fail("bit rates must be above 0");
  }
  // Durations depend only on the rates: ten quanta per bit at exactly that rate.
  const auto at_rate = [](uint32_t bps) {
    return model::BitTiming{uint64_t{bps} * 10, 1, 7, 2, 1, 1};
  };
  const auto nominal = std::optional<model::BitTiming>(at_rate(bitrate));
  const auto data = std::optional<model::BitTiming>(at_rate(data_bitrate));
  std::printf(
      "at %u bit/s%s: %lld ns (%u nominal + %u data-phase bits), %lld ns with "
      "intermission\n",
      bitrate, e.brs ? fmt::format(" / {} bit/s", data_bitrate).c_str() : "",
      static_cast<long long>(model::frame_duration(e, *nominal, *data).ns()), counts.nominal,
      counts.data,
      static_cast<long long>(
          (model::frame_duration(e, *nominal, *data) + model::intermission_duration(*nominal))
              .ns()));
  return 0;
}

int cmd_calc_btr(const std::string& btr0, const std::string& btr1) {
  const auto t = model::sja1000::decode_btr(static_cast<uint8_t>(std::stoul(btr0, nullptr, 16)),
                                            static_cast<uint8_t>(std::stoul(btr1, nullptr, 16)));
  if (!t) {
    return fail(t.error().message);
  }
  std::printf(
      "SJA1000 at 16 MHz: %.3f bit/s, tq %.3f ns, %u quanta (1 + %u + %u), sample point "
      "%.1f %%, SJW %u, %u sample%s per bit\n",
      t->bit_rate().bps(), static_cast<double>(t->quantum_ps()) / 1000.0, t->quanta_per_bit(),
      t->tseg1, t->tseg2, t->sample_point_permille() / 10.0, t->sjw, t->samples,
      t->samples == 1 ? "" : "s");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"canemu: talk to canemud, and calculate CAN frames and bit timings"};
  app.require_subcommand(1);
  std::string socket;
  app.add_option("--socket", socket, "canemud's control socket (default: $CANEMU_SOCKET, ...)");

  auto* status = app.add_subcommand("status", "buses with load, nodes with state and counters");
  bool json = false;
  status->add_flag("--json", json, "one JSON object instead of tables");

  auto* send = app.add_subcommand("send", "send frames on a bus, e.g. 'send can0 123#1122'");
  SendOptions send_options;
  send->add_option("BUS", send_options.bus, "bus name")->required();
  send->add_option("FRAME", send_options.frames,
                   "cansend syntax: 123#1122, 12345678#R4, 123##1AABB")
      ->required();
  send->add_option("--bitrate", send_options.bitrate, "the sender's bit/s (default: the bus's)");
  send->add_option("--step", send_options.step, "stepped time: step this long after queueing");
  send->add_option("--timeout", send_options.timeout_ms,
                   "ms to wait for the frames (default 2000)");

  auto* dump = app.add_subcommand("dump", "print a bus's frames and errors as a candump -L log");
  DumpOptions dump_options;
  dump->add_option("BUS", dump_options.bus, "bus name")->required();
  dump->add_option("--bitrate", dump_options.bitrate, "the listener's bit/s (default: the bus's)");
  dump->add_option("-n,--count", dump_options.count, "stop after this many lines");
  bool no_errors = false;
  dump->add_flag("--no-errors", no_errors, "frames only, no error frames");

  auto* fault = app.add_subcommand("fault", "fault scenarios (docs/faults.md)");
  fault->require_subcommand(1);
  auto* fault_load = fault->add_subcommand("load", "apply a scenario file from now on");
  std::string fault_file;
  fault_load->add_option("FILE", fault_file, "scenario (TOML)")->required();
  auto* fault_list = fault->add_subcommand("list", "every fault applied, with its hits and state");
  auto* fault_clear = fault->add_subcommand("clear", "stop a scenario's faults (NAME or all)");
  std::string fault_name = "all";
  fault_clear->add_option("NAME", fault_name, "scenario name, or all (default)");
  auto* fault_inject = fault->add_subcommand("inject", "one fault from the command line");
  InjectOptions inject;
  fault_inject->add_option("--effect", inject.effect, "bit_error, ack_suppress, node_off, ...")
      ->required();
  fault_inject->add_option("--at", inject.at, "from now (default 0s)");
  fault_inject->add_option("--until", inject.until, "end of the window");
  fault_inject->add_option("--bus", inject.bus, "bus (frame and bus effects)");
  fault_inject->add_option("--node", inject.node, "node, DEVICE:N or a device's name");
  fault_inject->add_option("--duration", inject.duration, "ack_suppress, stuck_dominant, babble");
  fault_inject->add_option("--from", inject.from, "match: transmitting node");
  fault_inject->add_option("--id", inject.id, "match: identifier (0x100); babble: its frame's");
  fault_inject->add_option("--mask", inject.mask, "match: identifier mask (0x7FF)");
  fault_inject->add_flag("--ext", inject.ext, "match: extended frames only; babble: 29-bit id");
  fault_inject->add_flag("--std", inject.std_id, "match: standard frames only");
  fault_inject->add_flag("--rtr", inject.rtr, "match: remote frames only");
  fault_inject->add_flag("--data-frame", inject.data_frame, "match: data frames only");
  fault_inject->add_option("--bit", inject.bit, "frame bit where the error hits (SOF = 0)");
  fault_inject->add_option("--count", inject.count, "matching frames to hit, or all (default)");
  fault_inject->add_option("--probability", inject.probability, "per matching frame");
  fault_inject->add_option("--bit-error-rate", inject.bit_error_rate, "random_errors, per bit");
  fault_inject->add_option("--tec", inject.tec, "error_counters");
  fault_inject->add_option("--rec", inject.rec, "error_counters");
  fault_inject->add_option("--ppm", inject.ppm, "oscillator");
  fault_inject->add_option("--data", inject.data, "babble: data bytes in hex (1122AABB)");
  fault_inject->add_option("--wire", inject.wire, "line_error: one (default) or both");
  fault_inject->footer(
      "Examples:\n"
      "  canemu fault inject --effect bit_error --bus can0 --id 0x1A0 --count 3\n"
      "  canemu fault inject --effect random_errors --bus can0 --bit-error-rate 1e-4 --until 2s\n"
      "  canemu fault inject --effect node_off --node ixxat0:1 --at 1s --until 1.5s\n"
      "  canemu fault inject --effect babble --node ixxat0:0 --id 0 --data DEADBEEF "
      "--duration 500ms");

  auto* time = app.add_subcommand("time", "simulated time (stepped mode)");
  time->require_subcommand(1);
  auto* step = time->add_subcommand("step", "advance simulated time, e.g. 'time step 10ms'");
  std::string duration;
  step->add_option("DURATION", duration, "150ns, 20us, 10ms, 2s")->required();

  auto* calc = app.add_subcommand("calc", "offline calculations on the wire model");
  calc->require_subcommand(1);
  auto* frame = calc->add_subcommand("frame", "exact bits and duration of a frame, e.g. 123#1122");
  std::string frame_text;
  uint32_t bitrate = 500000;
  uint32_t data_bitrate = 2000000;
  frame->add_option("FRAME", frame_text, "cansend syntax: 123#1122, 12345678#R, 123##1AABB")
      ->required();
  frame->add_option("--bitrate", bitrate, "nominal bit/s (default 500000)");
  frame->add_option("--data-bitrate", data_bitrate, "data-phase bit/s for BRS (default 2000000)");
  auto* bt = calc->add_subcommand("bittiming", "decode SJA1000 BTR0 BTR1 (hex), e.g. 00 1C");
  std::string btr0, btr1;
  bt->add_option("BTR0", btr0, "hex")->required();
  bt->add_option("BTR1", btr1, "hex")->required();

  CLI11_PARSE(app, argc, argv);
  try {
    if (*status) {
      return cmd_status(socket, json);
    }
    if (*step) {
      return cmd_time_step(socket, duration);
    }
    if (*send) {
      return cmd_send(socket, send_options);
    }
    if (*fault_load) {
      return cmd_fault_load(socket, fault_file);
    }
    if (*fault_list) {
      return cmd_fault_list(socket);
    }
    if (*fault_clear) {
      return cmd_fault_clear(socket, fault_name);
    }
    if (*fault_inject) {
      return cmd_fault_inject(socket, inject);
    }
    if (*dump) {
      dump_options.errors = !no_errors;
      return cmd_dump(socket, dump_options);
    }
    if (*frame) {
      return cmd_calc_frame(frame_text, bitrate, data_bitrate);
    }
    if (*bt) {
      return cmd_calc_btr(btr0, btr1);
    }
  } catch (const std::exception& e) {
    return fail(std::string("bad argument: ") + e.what());
  }
  return 1;
}
