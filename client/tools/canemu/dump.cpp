// canemu dump: the frames and errors of one or more buses as a candump -L log (or a pcap
// capture of one bus; a LIN bus: lin_dump.hpp, text lines or LINKTYPE_LIN pcap), from a channel
// of an ephemeral device on each bus, until interrupted or --count frames. The buses are given
// as candump takes them: <bus>[,filter]* or any (dump_filter.hpp), the filters applied here to
// what each channel receives.
// Like candump on a real interface, its controllers are active and acknowledge what they
// receive; --listen-only makes them silent observers. -l logs into a file named as candump -l
// names it. run_capture() also serves canemu record. --dbc FILE pipes the printed lines through
// canemu.dbc_decode, which appends each known frame's decoding (docs/restbus.md).
#include <poll.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/channel.hpp"
#include "canemu/client/connection.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/ipc/capture_writer.hpp"
#include "canemu/ipc/socketcan.hpp"
#include "command.hpp"
#include "dump_filter.hpp"
#include "dump_summary.hpp"
#include "frame_text.hpp"
#include "lin_dump.hpp"
#include "python_tool.hpp"

namespace canemu::cli {

namespace {

volatile std::sig_atomic_t g_stop = 0;

// canemud opens at most this many channels on one connection (docs/daemon.md): a dump of more
// buses opens a connection more for each further 16.
constexpr std::size_t kChannelsPerConnection = 16;
// The most messages taken from the rings before they are written out.
constexpr std::size_t kBatch = 4096;
// How often a --summary dump reads its rings: a busy bus's 4096-message ring holds far longer.
constexpr std::chrono::milliseconds kSummaryDrain{10};

void on_stop_signal(int) {
  g_stop = 1;
}

// A bus the dump listens on, with the arguments that named it (candump opens a socket per
// argument: a bus named twice prints a frame once per argument that lets it through).
struct Target {
  std::string bus;
  bool lin = false;
  std::vector<const BusFilter*> specs;
};

// The buses of `specs` (`any`: every CAN bus) in order, or why one is not there.
client::Result<std::vector<Target>> targets_of(const std::vector<BusFilter>& specs,
                                               const client::Status& s) {
  std::vector<Target> targets;
  const auto add = [&targets](const std::string& bus, bool lin, const BusFilter* spec) {
    auto t = std::find_if(targets.begin(), targets.end(),
                          [&bus](const Target& x) { return x.bus == bus; });
    if (t == targets.end()) {
      targets.push_back({bus, lin, {}});
      t = targets.end() - 1;
    }
    t->specs.push_back(spec);
  };
  std::string names;
  for (const auto& b : s.buses) {
    names += (names.empty() ? "" : ", ") + ipc::name_of(b.name);
  }
  for (const BusFilter& spec : specs) {
    bool found = false;
    for (const auto& b : s.buses) {
      const bool lin = b.kind == static_cast<uint8_t>(ipc::WireBusKind::lin);
      if (spec.bus == "any" ? !lin : ipc::name_of(b.name) == spec.bus) {
        add(ipc::name_of(b.name), lin, &spec);
        found = true;
      }
    }
    if (!found) {
      return tl::unexpected(client::IpcError{
          0, spec.bus == "any"
                 ? fmt::format("canemud has no CAN bus (buses: {})", names.empty() ? "none" : names)
                 : fmt::format("no bus named \"{}\" (buses: {})", spec.bus,
                               names.empty() ? "none" : names)});
    }
  }
  return targets;
}

// Waits up to `timeout_ms` until a message waits in one of the channels' receive rings; false
// when none came.
bool wait_any(std::vector<client::Channel>& channels, int timeout_ms) {
  if (channels.size() == 1) {
    return channels[0].rx().wait(timeout_ms) || channels[0].rx().fill_count() > 0;
  }
  std::vector<pollfd> fds;
  bool filled = false;
  for (client::Channel& ch : channels) {
    if (!ch.rx().arm_unless_filled()) {
      filled = true;
      break;
    }
    fds.push_back({ch.rx_event_fd(), POLLIN, 0});
  }
  const int n = filled ? 1 : ::poll(fds.data(), fds.size(), timeout_ms);
  for (client::Channel& ch : channels) {
    ch.rx().disarm();
  }
  return n > 0;
}

}  // namespace

int run_capture(const std::string& socket, const CaptureRun& o) {
  std::vector<BusFilter> specs;
  if (o.bus_args.empty()) {
    specs.emplace_back();
    specs.back().text = specs.back().bus = o.bus;
  }
  for (const std::string& arg : o.bus_args) {
    std::string error;
    auto spec = parse_bus_filter(arg, error);
    if (!spec) {
      return fail(error);
    }
    specs.push_back(std::move(*spec));
  }
  if (o.no_errors) {
    for (BusFilter& spec : specs) {
      spec.error_mask = 0;
    }
  }
  auto c = connect(socket, o.record ? "canemu record" : "canemu dump");
  if (!c) {
    return fail(c.error().message);
  }
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  auto s = client::fetch_status(*c);
  if (!s) {
    return fail(s.error().message);
  }
  auto targets = targets_of(specs, *s);
  if (!targets) {
    return fail(targets.error().message);
  }
  const std::string output = o.log_file ? candump_log_name(std::time(nullptr)) : o.output;
  for (const Target& t : *targets) {
    if (!t.lin) {
      continue;
    }
    if (targets->size() > 1 || specs.size() > 1) {
      return fail(fmt::format("{} is a LIN bus: dump it alone (canemu dump {})", t.bus, t.bus));
    }
    if (specs[0].filtered) {
      return fail(fmt::format("{} is a LIN bus: candump's filters are for CAN buses", t.bus));
    }
    // A LIN bus: text lines on the terminal, pcap (LINKTYPE_LIN) in files.
    CaptureRun lin = o;
    lin.bus = t.bus;
    lin.output = output;
    const bool to_file = o.record || output != "-" || o.format == "pcap";
    if (to_file && (o.format == "candump" || o.log_file)) {
      return fail(ipc::candump_has_no_lin(t.bus));
    }
    const auto base = time_base(*c, o.sim_time);
    if (!base) {
      return fail(base.error().message);
    }
    return to_file ? run_lin_record(*c, lin, *base, g_stop)
                   : run_lin_dump(*c, t.bus, o.bitrate, o.count, *base, g_stop);
  }
  // Without --format: pcap for a .pcap file (as [[recorder]] does), else candump.
  const bool pcap_path = output.size() > 5 && output.ends_with(".pcap");
  const auto format = o.format.empty()
                          ? (pcap_path ? ipc::CaptureFormat::pcap : ipc::CaptureFormat::candump)
                          : ipc::parse_capture_format(o.format);
  if (!format) {
    return fail("--format must be candump or pcap, not '" + o.format + "'");
  }
  if (o.log_file && *format == ipc::CaptureFormat::pcap) {
    return fail("-l writes a candump log, as candump -l does; a pcap capture needs -o FILE");
  }
  if (o.summary_ms != 0 && (*format == ipc::CaptureFormat::pcap || o.log_file)) {
    return fail("--summary writes JSON lines, not a pcap capture or a candump log");
  }
  if (targets->size() > 1 && *format == ipc::CaptureFormat::pcap) {
    return fail(
        "a pcap capture (LINKTYPE_CAN_SOCKETCAN) does not say which bus a frame was on: one bus "
        "per pcap capture");
  }
  // Declared before the channels, which close through them: a deque keeps their addresses.
  std::deque<client::Connection> more;
  std::vector<client::Channel> channels;
  for (const Target& t : *targets) {
    client::Connection* on = &*c;
    if (channels.size() >= kChannelsPerConnection) {
      if (channels.size() % kChannelsPerConnection == 0) {
        auto extra = connect(socket, o.record ? "canemu record" : "canemu dump");
        if (!extra) {
          return fail(extra.error().message);
        }
        more.push_back(std::move(*extra));
      }
      on = &more.back();
    }
    const bool errors = std::any_of(t.specs.begin(), t.specs.end(),
                                    [](const BusFilter* f) { return f->error_mask != 0; });
    client::ChannelOptions co;
    co.bus = t.bus;
    co.bitrate = o.bitrate;
    co.flags = static_cast<uint16_t>((o.listen_only ? ipc::kChannelListenOnly : 0) |
                                     (errors ? ipc::kChannelReportErrors : 0));
    co.rx_capacity = 4096;
    auto ch = client::Channel::open(*on, co);
    if (!ch) {
      return fail(ch.error().message);
    }
    channels.push_back(std::move(*ch));
  }
  const auto base = time_base(*c, o.sim_time);
  if (!base) {
    return fail(base.error().message);
  }
  auto out =
      ipc::CaptureWriter::open({output, *format, targets->front().bus, o.max_bytes, o.max_files});
  if (!out) {
    return fail(out.error().message);
  }
  if (o.log_file) {
    std::fprintf(stderr, "canemu: logging into %s\n", output.c_str());
  }
  for (std::size_t i = 0; i < targets->size(); ++i) {
    const Target& t = (*targets)[i];
    std::fprintf(stderr, "canemu: listening on %s as %s (%s, %u bit/s, time stamps in %s)\n",
                 t.bus.c_str(), channels[i].device().c_str(),
                 o.listen_only ? "listen-only" : "acknowledging", channels[i].info().bitrate,
                 base->wall_clock ? "wall-clock seconds" : "simulated seconds");
    for (const BusFilter* spec : t.specs) {
      if (const std::string what = spec->describe(); !what.empty()) {
        const std::string as = t.specs.size() > 1 ? " (as " + spec->text + ")" : "";
        std::fprintf(stderr, "canemu: on %s%s: %s\n", t.bus.c_str(), as.c_str(), what.c_str());
      }
    }
  }
  struct Received {
    int64_t ns;
    std::size_t target;
    ipc::socketcan::Frame frame;
  };
  std::vector<Received> batch;
  uint64_t written = 0;
  std::optional<client::IpcError> gone;
  std::vector<std::string> names;
  for (const Target& t : *targets) {
    names.push_back(t.bus);
  }
  DumpSummary summary(std::move(names));
  using Clock = std::chrono::steady_clock;
  const auto every = std::chrono::milliseconds(o.summary_ms);
  auto summary_due = Clock::now() + every;
  // The summary's lines so far, written as the candump lines are (a failed write ends the dump).
  const auto write_summary = [&] {
    const std::string lines = summary.take();
    return lines.empty() || std::fwrite(lines.data(), 1, lines.size(), stdout) == lines.size();
  };
  while (!g_stop && (o.count == 0 || written < o.count)) {
    if (o.summary_ms != 0 && Clock::now() >= summary_due) {
      if (!write_summary() || std::fflush(stdout) != 0) {
        return fail("cannot write the summary to standard output");
      }
      summary_due = Clock::now() + every;
    }
    // What waits in every ring, then in time order: the buses' lines interleave as they
    // happened.
    batch.clear();
    for (std::size_t i = 0; i < channels.size(); ++i) {
      while (batch.size() < kBatch) {
        auto m = channels[i].receive(0);
        if (!m) {
          break;
        }
        if (m->lost_before != 0) {
          if (channels.size() == 1) {
            std::fprintf(stderr, "canemu: %u message(s) lost: the output did not keep up\n",
                         m->lost_before);
          } else {
            std::fprintf(stderr, "canemu: %u message(s) of %s lost: the output did not keep up\n",
                         m->lost_before, (*targets)[i].bus.c_str());
          }
        }
        if (const auto f = ipc::socketcan::from_message(*m)) {
          batch.push_back({m->timestamp_ns, i, *f});
        }
      }
    }
    if (o.summary_ms != 0 && batch.size() < kBatch) {
      // A summary is not in a hurry: the rings are read every kSummaryDrain (a wake-up each,
      // instead of one for nearly every delivery of a busy bus), and the lines written when due.
      if (batch.empty() && (gone = c->lost())) {
        break;
      }
      const auto until = std::min(summary_due, Clock::now() + kSummaryDrain);
      std::this_thread::sleep_until(until);
    } else if (batch.empty()) {
      // Nothing came: canemud may have closed the connection (it stopped, or a reload no
      // longer allows this user), and then nothing comes any more.
      if (!wait_any(channels, 200) && (gone = c->lost())) {
        break;
      }
      continue;
    }
    std::stable_sort(batch.begin(), batch.end(),
                     [](const Received& a, const Received& b) { return a.ns < b.ns; });
    for (const Received& r : batch) {
      const Target& t = (*targets)[r.target];
      for (const BusFilter* spec : t.specs) {
        if ((o.count == 0 || written < o.count) && spec->matches(r.frame)) {
          if (o.summary_ms != 0) {
            summary.add(r.target, r.ns + base->offset_ns, r.frame);
          } else {
            out->record(r.ns + base->offset_ns, t.bus, r.frame);
          }
          ++written;
        }
      }
    }
    if (!out->flush()) {
      return fail(out->error() + fmt::format(" ({} frame(s) lost)", out->lost()));
    }
  }
  if (o.summary_ms != 0 && (!write_summary() || std::fflush(stdout) != 0)) {
    return fail("cannot write the summary to standard output");
  }
  if (o.record) {
    std::fprintf(stderr, "canemu: %llu frame(s) recorded in %s (%s)\n",
                 static_cast<unsigned long long>(out->frames()), output.c_str(),
                 std::string(ipc::to_string(*format)).c_str());
  }
  return gone ? fail(gone->message) : 0;
}

Command add_dump(CLI::App& app, const std::string& socket) {
  auto* dump = app.add_subcommand(
      "dump", "print the frames and errors of buses as a candump -L log (candump's filters)");
  auto o = std::make_shared<CaptureRun>();
  o->output = "-";
  dump->add_option("BUS", o->bus_args,
                   "buses as candump takes them: BUS[,FILTER]... with FILTER <id>:<mask>, "
                   "<id>~<mask>, #<error mask> or j (join); any: every CAN bus")
      ->required();
  dump->add_option("--bitrate", o->bitrate,
                   "the listener's bit/s (default: the bus's; on a LIN bus each header's)");
  dump->add_option("-n,--count", o->count, "stop after this many frames (LIN: lines)");
  dump->add_flag("--no-errors", o->no_errors, "frames only, no error frames");
  dump->add_flag("--listen-only", o->listen_only,
                 "a silent observer: no acknowledgements, no error flags");
  dump->add_flag("--sim-time", o->sim_time,
                 "time stamps in simulated seconds (default in real time: wall-clock seconds)");
  dump->add_option("--format", o->format,
                   "candump (a candump -L log, the default) or pcap (LINKTYPE_CAN_SOCKETCAN, one "
                   "bus; a LIN bus: LINKTYPE_LIN); default pcap for a .pcap file and a LIN bus's "
                   "files")
      ->check(CLI::IsMember({"candump", "pcap"}));
  dump->add_flag_callback(
      "-L", [o] { o->format = "candump"; }, "a candump -L log (the default)");
  auto* output = dump->add_option("-o,-f,--output", o->output,
                                  "write to this file (default: standard output, -)");
  dump->add_flag("-l", o->log_file,
                 "log into candump-YYYY-MM-DD_HHMMSS.log in the current directory, as candump -l "
                 "(listen-only is --listen-only)")
      ->excludes(output);
  auto* summary =
      dump->add_option("--summary", o->summary_ms,
                       "instead of a line per frame, a JSON line per bus and identifier every MS "
                       "milliseconds: count, first and last time stamp, last data, bytes changed "
                       "(docs/cli.md)")
          ->check(CLI::Range(1u, 3'600'000u))
          ->option_text("MS")
          ->excludes(output);
  auto dbc = std::make_shared<std::string>();
  dump->add_option("--dbc", *dbc,
                   "also decode each frame the DBC knows (its message and signals, as cantools "
                   "decode --single-line) after its line; through python -m canemu.dbc_decode")
      ->excludes(output)
      ->excludes(summary);
  return {dump, [&socket, o, dbc] {
            if (dbc->empty()) {
              return run_capture(socket, *o);
            }
            if (o->log_file || o->format == "pcap") {
              return fail(
                  "--dbc decodes the lines printed on standard output: not with -l or "
                  "--format pcap");
            }
            const PythonFilter filter = start_python_filter("canemu.dbc_decode", {*dbc});
            if (filter.status != 0) {
              if (filter.status > 0) {
                return filter.status;  // it said why (exit 2: the DBC cannot be read)
              }
              return fail(fmt::format(
                  "--dbc: {} -m canemu.dbc_decode cannot run: {} (it needs the canemu Python "
                  "package and cantools; CANEMU_PYTHON names the interpreter)",
                  filter.interpreter, filter.error));
            }
            const int status = run_capture(socket, *o);
            const int decoder = finish_python_filter(filter);
            return status != 0 ? status : decoder;
          }};
}

}  // namespace canemu::cli
