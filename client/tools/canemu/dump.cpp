// canemu dump: a bus's frames and errors as a candump -L log (or a pcap capture; a LIN bus:
// lin_dump.hpp, text lines or LINKTYPE_LIN pcap), from a channel of an ephemeral device, until
// interrupted or --count frames.
// Like candump on a real interface, its controller is active and acknowledges what it
// receives; --listen-only makes it a silent observer. run_capture() also serves canemu record.
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/channel.hpp"
#include "canemu/client/connection.hpp"
#include "canemu/client/lists.hpp"
#include "canemu/ipc/capture_writer.hpp"
#include "canemu/ipc/socketcan.hpp"
#include "command.hpp"
#include "frame_text.hpp"
#include "lin_dump.hpp"

namespace canemu::cli {

namespace {

volatile std::sig_atomic_t g_stop = 0;

void on_stop_signal(int) {
  g_stop = 1;
}

}  // namespace

int run_capture(const std::string& socket, const CaptureRun& o) {
  auto c = connect(socket, o.record ? "canemu record" : "canemu dump");
  if (!c) {
    return fail(c.error().message);
  }
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  auto s = client::fetch_status(*c);
  for (std::size_t i = 0; s && i < s->buses.size(); ++i) {
    if (ipc::name_of(s->buses[i].name) == o.bus &&
        s->buses[i].kind == static_cast<uint8_t>(ipc::WireBusKind::lin)) {
      // A LIN bus: text lines on the terminal, pcap (LINKTYPE_LIN) in files.
      const bool to_file = o.record || o.output != "-" || o.format == "pcap";
      if (to_file && o.format == "candump") {
        return fail(ipc::candump_has_no_lin(o.bus));
      }
      const auto base = time_base(*c, o.sim_time);
      if (!base) {
        return fail(base.error().message);
      }
      return to_file ? run_lin_record(*c, o, *base, g_stop)
                     : run_lin_dump(*c, o.bus, o.bitrate, o.count, *base, g_stop);
    }
  }
  client::ChannelOptions co;
  co.bus = o.bus;
  co.bitrate = o.bitrate;
  co.flags = static_cast<uint16_t>((o.listen_only ? ipc::kChannelListenOnly : 0) |
                                   (o.no_errors ? 0 : ipc::kChannelReportErrors));
  co.rx_capacity = 4096;
  auto ch = client::Channel::open(*c, co);
  if (!ch) {
    return fail(ch.error().message);
  }
  const auto base = time_base(*c, o.sim_time);
  if (!base) {
    return fail(base.error().message);
  }
  // Without --format: pcap for a .pcap file (as [[recorder]] does), else candump.
  const bool pcap_path = o.output.size() > 5 && o.output.ends_with(".pcap");
  const auto format = o.format.empty()
                          ? (pcap_path ? ipc::CaptureFormat::pcap : ipc::CaptureFormat::candump)
                          : ipc::parse_capture_format(o.format);
  if (!format) {
    return fail("--format must be candump or pcap, not '" + o.format + "'");
  }
  auto out = ipc::CaptureWriter::open({o.output, *format, o.bus, o.max_bytes, o.max_files});
  if (!out) {
    return fail(out.error().message);
  }
  std::fprintf(stderr, "canemu: listening on %s as %s (%s, %u bit/s, time stamps in %s)\n",
               o.bus.c_str(), ch->device().c_str(), o.listen_only ? "listen-only" : "acknowledging",
               ch->info().bitrate, base->wall_clock ? "wall-clock seconds" : "simulated seconds");
  uint64_t written = 0;
  std::optional<client::IpcError> gone;
  while (!g_stop && (o.count == 0 || written < o.count)) {
    auto m = ch->receive(200);
    if (!m) {
      // Nothing came: canemud may have closed the connection (it stopped, or a reload no
      // longer allows this user), and then nothing comes any more.
      if ((gone = c->lost())) {
        break;
      }
      continue;
    }
    if (m->lost_before != 0) {
      std::fprintf(stderr, "canemu: %u message(s) lost: the output did not keep up\n",
                   m->lost_before);
    }
    const auto f = ipc::socketcan::from_message(*m);
    if (!f) {
      continue;
    }
    out->record(m->timestamp_ns + base->offset_ns, *f);
    if (!out->flush()) {
      return fail(out->error() + fmt::format(" ({} frame(s) lost)", out->lost()));
    }
    ++written;
  }
  if (o.record) {
    std::fprintf(stderr, "canemu: %llu frame(s) recorded in %s (%s)\n",
                 static_cast<unsigned long long>(out->frames()), o.output.c_str(),
                 std::string(ipc::to_string(*format)).c_str());
  }
  return gone ? fail(gone->message) : 0;
}

Command add_dump(CLI::App& app, const std::string& socket) {
  auto* dump = app.add_subcommand("dump", "print a bus's frames and errors as a candump -L log");
  auto o = std::make_shared<CaptureRun>();
  o->output = "-";
  dump->add_option("BUS", o->bus, "bus name")->required();
  dump->add_option("--bitrate", o->bitrate,
                   "the listener's bit/s (default: the bus's; on a LIN bus each header's)");
  dump->add_option("-n,--count", o->count, "stop after this many frames (LIN: lines)");
  dump->add_flag("--no-errors", o->no_errors, "frames only, no error frames");
  dump->add_flag("-l,--listen-only", o->listen_only,
                 "a silent observer: no acknowledgements, no error flags");
  dump->add_flag("--sim-time", o->sim_time,
                 "time stamps in simulated seconds (default in real time: wall-clock seconds)");
  dump->add_option("--format", o->format,
                   "candump (a candump -L log, the default) or pcap (LINKTYPE_CAN_SOCKETCAN; "
                   "a LIN bus: LINKTYPE_LIN); default pcap for a .pcap file and a LIN bus's files")
      ->check(CLI::IsMember({"candump", "pcap"}));
  dump->add_flag_callback(
      "-L", [o] { o->format = "candump"; }, "a candump -L log (the default)");
  dump->add_option("-o,--output", o->output, "write to this file (default: standard output, -)");
  return {dump, [&socket, o] { return run_capture(socket, *o); }};
}

}  // namespace canemu::cli
