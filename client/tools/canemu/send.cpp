// canemu send: frames in cansend syntax onto a bus, through a channel of an ephemeral device;
// each confirmed frame printed as candump would log it.
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/channel.hpp"
#include "canemu/client/connection.hpp"
#include "command.hpp"
#include "frame_text.hpp"
#include "lin_send.hpp"

namespace canemu::cli {

namespace {

struct SendOptions {
  std::string bus;
  std::vector<std::string> frames;
  uint32_t bitrate = 0;
  std::string step;
  int timeout_ms = 2000;
  bool sim_time = false;
  bool classic = false;  // LIN: the classic checksum
};

// On a LIN bus: its own frame syntax, one frame after another (lin_send.hpp).
int send_lin(client::Connection& c, const SendOptions& o, std::optional<int64_t> step_ns,
             const TimeBase& base) {
  std::vector<LINMSG> frames;
  for (const std::string& text : o.frames) {
    std::string error;
    auto m = parse_lin_send(text, o.classic, error);
    if (!m) {
      return fail(fmt::format("'{}': {}", text, error));
    }
    frames.push_back(*m);
  }
  LinSendOptions lo;
  lo.bus = o.bus;
  lo.bitrate = o.bitrate;
  lo.classic = o.classic;
  lo.step_ns = step_ns;
  lo.timeout_ms = o.timeout_ms;
  return run_lin_send(c, frames, lo, base);
}

int run_send(const std::string& socket, const SendOptions& o) {
  std::optional<int64_t> step_ns;
  if (!o.step.empty()) {
    step_ns = parse_positive_duration(o.step);
    if (!step_ns) {
      return fail(fmt::format("'{}' is not a duration (examples: 150ns, 20us, 10ms, 2s)", o.step));
    }
  }
  auto c = connect(socket, "canemu send");
  if (!c) {
    return fail(c.error().message);
  }
  const auto base = time_base(*c, o.sim_time);
  if (!base) {
    return fail(base.error().message);
  }
  const bool stepped = base->stepped();
  if (stepped && !step_ns) {
    return fail(
        "simulated time is stepped: frames go out only while time moves; add --step "
        "DURATION to step after queueing them");
  }
  if (!stepped && step_ns) {
    return fail("--step needs stepped time; canemud runs " +
                std::string(ipc::to_string(base->mode)));
  }
  const auto kind = bus_kind(*c, o.bus);
  if (kind && kind->first == ipc::WireBusKind::lin) {
    return send_lin(*c, o, step_ns, *base);
  }
  const bool classic_bus = kind && kind->first == ipc::WireBusKind::can;
  std::vector<ipc::ChannelMessage> messages;
  for (const std::string& text : o.frames) {
    std::string error;
    auto m = parse_cansend(text, error);
    if (!m) {
      return fail(fmt::format("'{}': {}", text, error));
    }
    // As cansend on an interface without CAN FD: refused before anything is sent.
    if ((m->flags & ipc::kMsgFd) != 0 && classic_bus) {
      return fail(fmt::format("'{}': a CAN FD frame, and {}", text, classic_bus_text(o.bus)));
    }
    messages.push_back(*m);
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
  for (std::size_t k = 0; k < messages.size() && !ch->info().fd_capable; ++k) {
    if ((messages[k].flags & ipc::kMsgFd) != 0) {
      return fail(fmt::format("'{}': a CAN FD frame, and {} sends classic CAN frames only",
                              o.frames[k], ch->device()));
    }
  }
  for (const ipc::ChannelMessage& m : messages) {
    auto sent = ch->send(m, o.timeout_ms);
    if (!sent) {
      return fail(sent.error().message);
    }
  }
  if (step_ns) {
    auto r = step_time(*c, *step_ns);
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
      std::printf("%s\n", log_line(*m, o.bus, *base).c_str());
      ++done;
    } else if (m->kind == static_cast<uint8_t>(ipc::ChannelMessageKind::tx_dropped)) {
      m->kind = static_cast<uint8_t>(ipc::ChannelMessageKind::frame);
      std::fprintf(stderr, "canemu: %s: not sent (its node gave it up after an error)\n",
                   candump_frame(*m).c_str());
      ++failed;
      ++done;
    }
  }
  return failed == 0 ? 0 : 1;
}

}  // namespace

Command add_send(CLI::App& app, const std::string& socket) {
  auto* send = app.add_subcommand("send", "send frames on a bus, e.g. 'send can0 123#1122'");
  auto o = std::make_shared<SendOptions>();
  send->add_option("BUS", o->bus, "bus name")->required();
  send->add_option(
          "FRAME", o->frames,
          "cansend syntax: 123#1122, 12345678#R4, 123##1AABB, 123#1122334455667788_E; on a LIN "
          "bus 10#0102 "
          "(published), 10# (the header alone), sleep")
      ->required();
  send->add_flag("--classic", o->classic, "LIN: the classic checksum (default enhanced)");
  send->add_option("--bitrate", o->bitrate, "the sender's bit/s (default: the bus's)");
  send->add_option("--step", o->step, "stepped time: step this long after queueing");
  send->add_option("--timeout", o->timeout_ms, "ms to wait for the frames (default 2000)")
      ->check(CLI::Range(0, 3'600'000));
  send->add_flag("--sim-time", o->sim_time,
                 "time stamps in simulated seconds (default in real time: wall-clock seconds)");
  return {send, [&socket, o] { return run_send(socket, *o); }};
}

}  // namespace canemu::cli
