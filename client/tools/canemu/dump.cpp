// canemu dump: a bus's frames and errors as a candump -L log (a LIN bus: lin_dump.hpp), from a
// channel of an ephemeral device, until interrupted or --count lines. Like candump on a real
// interface, its controller is active and acknowledges what it receives; --listen-only makes it a
// silent observer.
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "canemu/client/channel.hpp"
#include "canemu/client/connection.hpp"
#include "command.hpp"
#include "frame_text.hpp"
#include "lin_dump.hpp"

namespace canemu::cli {

namespace {

volatile std::sig_atomic_t g_stop = 0;

void on_stop_signal(int) {
  g_stop = 1;
}

struct DumpOptions {
  std::string bus;
  uint32_t bitrate = 0;
  uint64_t count = 0;  // 0: until interrupted
  bool no_errors = false;
  bool listen_only = false;
  bool sim_time = false;
};

int run_dump(const std::string& socket, const DumpOptions& o) {
  auto c = connect(socket, "canemu dump");
  if (!c) {
    return fail(c.error().message);
  }
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  auto s = c->call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
  for (uint16_t i = 0; s && i < s->bus_count; ++i) {
    if (ipc::name_of(s->buses[i].name) == o.bus &&
        s->buses[i].kind == static_cast<uint8_t>(ipc::WireBusKind::lin)) {
      const auto base = time_base(*c, o.sim_time);
      if (!base) {
        return fail(base.error().message);
      }
      return run_lin_dump(*c, o.bus, o.bitrate, o.count, *base, g_stop);
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
  std::fprintf(stderr, "canemu: listening on %s as %s (%s, %u bit/s, time stamps in %s)\n",
               o.bus.c_str(), ch->device().c_str(), o.listen_only ? "listen-only" : "acknowledging",
               ch->info().bitrate, base->wall_clock ? "wall-clock seconds" : "simulated seconds");
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
    const std::string frame = candump_frame(*m);
    if (frame.empty()) {
      continue;
    }
    std::printf("%s\n", log_line(*m, o.bus, *base).c_str());
    std::fflush(stdout);
    ++printed;
  }
  return 0;
}

}  // namespace

Command add_dump(CLI::App& app, const std::string& socket) {
  auto* dump = app.add_subcommand("dump", "print a bus's frames and errors as a candump -L log");
  auto o = std::make_shared<DumpOptions>();
  dump->add_option("BUS", o->bus, "bus name")->required();
  dump->add_option("--bitrate", o->bitrate,
                   "the listener's bit/s (default: the bus's; on a LIN bus each header's)");
  dump->add_option("-n,--count", o->count, "stop after this many lines");
  dump->add_flag("--no-errors", o->no_errors, "frames only, no error frames");
  dump->add_flag("-l,--listen-only", o->listen_only,
                 "a silent observer: no acknowledgements, no error flags");
  dump->add_flag("--sim-time", o->sim_time,
                 "time stamps in simulated seconds (default in real time: wall-clock seconds)");
  return {dump, [&socket, o] { return run_dump(socket, *o); }};
}

}  // namespace canemu::cli
