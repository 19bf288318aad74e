// canemu gen: frames generated onto a bus, in the spirit of can-utils' cangen: an active node of
// its own (an ephemeral device) sending random, incrementing or fixed identifiers, lengths and
// data, one frame every --gap, until --count frames or an interrupt.
//
// Time: in real and scaled time the gap is wall-clock time between handing frames to the node (a
// frame then waits for the bus like any other); waits for room in the transmit FIFO and for the
// last confirmations end after --timeout ms of simulated time without progress, so that a
// simulation running behind the wall clock counts no frame as not sent. In stepped time canemu gen
// moves time itself: it queues a frame and steps simulated time by the gap (at least 1 us), so a
// stepped bus gets traffic without another client stepping; frames then go out at exact simulated
// instants. Random choices come from a seeded generator (--seed, default 1): the same options give
// the same frames.
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/channel.hpp"
#include "canemu/client/connection.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "canemu/ipc/duration.hpp"
#include "canemu/ipc/protocol.hpp"
#include "command.hpp"
#include "lin_send.hpp"

namespace canemu::cli {

namespace {

volatile std::sig_atomic_t g_stop = 0;

void on_stop_signal(int) {
  g_stop = 1;
}

// One of cangen's generation modes: 'r' random, 'i' increment, or a fixed value.
struct Mode {
  enum Kind { random, increment, fixed } kind = random;
  uint64_t value = 0;
};

std::optional<Mode> parse_mode(const std::string& text, bool hex) {
  if (text == "r") {
    return Mode{Mode::random, 0};
  }
  if (text == "i") {
    return Mode{Mode::increment, 0};
  }
  if (text.empty() || text.size() > 16) {
    return std::nullopt;
  }
  uint64_t value = 0;
  for (char ch : text) {
    int digit = ch >= '0' && ch <= '9' ? ch - '0' : -1;
    if (hex && digit < 0) {
      digit = ch >= 'a' && ch <= 'f' ? ch - 'a' + 10 : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10 : -1;
    }
    if (digit < 0) {
      return std::nullopt;
    }
    value = value * (hex ? 16 : 10) + static_cast<uint64_t>(digit);
  }
  return Mode{Mode::fixed, value};
}

struct GenOptions {
  std::string bus;
  std::string gap = "200ms";
  uint64_t count = 0;  // 0: until interrupted
  std::string id = "r";
  std::string length = "r";
  std::string data = "r";
  bool extended = false;
  bool fd = false;
  bool brs = false;
  bool remote = false;
  bool verbose = false;
  bool sim_time = false;
  uint32_t bitrate = 0;
  uint64_t seed = 1;
  int timeout_ms = 2000;
};

// The generator proper: the next frame of the sequence the options describe.
class Generator {
 public:
  Generator(const GenOptions& o, Mode id, Mode length, Mode data, std::vector<uint8_t> fixed_data)
      : o_(o),
        id_(id),
        length_(length),
        data_(data),
        fixed_data_(std::move(fixed_data)),
        rng_(o.seed) {}

  ipc::ChannelMessage next() {
    ipc::ChannelMessage m;
    m.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::frame);
    const uint32_t id_limit = o_.extended ? 0x20000000u : 0x800u;
    switch (id_.kind) {
      case Mode::random:
        m.id = static_cast<uint32_t>(rng_() % id_limit);
        break;
      case Mode::increment:
        m.id = static_cast<uint32_t>(n_ % id_limit);
        break;
      case Mode::fixed:
        m.id = static_cast<uint32_t>(id_.value);
        break;
    }
    m.flags = static_cast<uint8_t>((o_.extended ? ipc::kMsgExtended : 0) |
                                   (o_.remote ? ipc::kMsgRemote : 0) | (o_.fd ? ipc::kMsgFd : 0) |
                                   (o_.brs ? ipc::kMsgBrs : 0));
    // The length: a DLC (0..8, 0..15 for FD) in random and increment mode, bytes when fixed.
    const uint8_t max_dlc = o_.fd ? 15 : 8;
    uint8_t dlc = 0;
    switch (length_.kind) {
      case Mode::random:
        dlc = static_cast<uint8_t>(rng_() % (max_dlc + 1u));
        break;
      case Mode::increment:
        dlc = static_cast<uint8_t>(n_ % (max_dlc + 1u));
        break;
      case Mode::fixed:
        dlc = *model::length_to_dlc(static_cast<uint8_t>(length_.value), o_.fd);
        break;
    }
    if (data_.kind == Mode::fixed && length_.kind != Mode::fixed) {
      dlc = *model::length_to_dlc(static_cast<uint8_t>(fixed_data_.size()), o_.fd);
    }
    m.dlc = dlc;
    const std::size_t bytes = model::dlc_to_length(dlc, o_.fd);
    for (std::size_t k = 0; k < bytes && !o_.remote; ++k) {
      switch (data_.kind) {
        case Mode::random:
          m.data[k] = static_cast<uint8_t>(rng_());
          break;
        case Mode::increment:
          m.data[k] = static_cast<uint8_t>(n_ + k);
          break;
        case Mode::fixed:
          m.data[k] = k < fixed_data_.size() ? fixed_data_[k] : 0;
          break;
      }
    }
    ++n_;
    return m;
  }

 private:
  const GenOptions& o_;
  Mode id_, length_, data_;
  std::vector<uint8_t> fixed_data_;
  std::mt19937_64 rng_;
  uint64_t n_ = 0;
};

// cangen's -g: a number is milliseconds ("10", "0.5"); with a unit, any duration ("500us").
std::optional<int64_t> parse_gap(const std::string& text, std::string& shown) {
  const bool bare = !text.empty() && text.find_first_not_of("0123456789.") == std::string::npos;
  shown = bare && text != "0" ? text + "ms" : text;
  return ipc::parse_duration(shown);
}

int run_gen(const std::string& socket, GenOptions o) {
  std::string gap_text;
  const auto gap = parse_gap(o.gap, gap_text);
  if (!gap) {
    return fail(fmt::format(
        "-g '{}' is not a duration (milliseconds as cangen's -g: 10, 0.5; or with a unit: 0, "
        "10ms, 500us)",
        o.gap));
  }
  o.gap = gap_text;
  // Hex as candump writes it; a 0x in front is allowed.
  const bool prefixed = o.id.size() > 2 && o.id[0] == '0' && (o.id[1] == 'x' || o.id[1] == 'X');
  const auto id = parse_mode(prefixed ? o.id.substr(2) : o.id, true);
  const uint64_t id_limit = o.extended ? 0x1FFFFFFF : 0x7FF;
  if (!id || (id->kind == Mode::fixed && id->value > id_limit)) {
    return fail(fmt::format("-I '{}': r, i or a hex identifier up to {:X}{}", o.id, id_limit,
                            o.extended ? "" : " (29-bit ones with -e)"));
  }
  const auto length = parse_mode(o.length, false);
  if (!length || (length->kind == Mode::fixed &&
                  (length->value > (o.fd ? 64u : 8u) ||
                   !model::length_to_dlc(static_cast<uint8_t>(length->value), o.fd)))) {
    return fail(fmt::format("-L '{}': r, i or a {} length in bytes ({})", o.length,
                            o.fd ? "CAN FD" : "classic CAN",
                            o.fd ? "0..8, 12, 16, 20, 24, 32, 48, 64" : "0..8"));
  }
  std::optional<Mode> data = parse_mode(o.data, true);
  std::vector<uint8_t> fixed_data;
  if (o.data != "r" && o.data != "i") {
    if (o.data.size() % 2 != 0 || o.data.size() > (o.fd ? 128u : 16u)) {
      data.reset();
    } else {
      for (std::size_t k = 0; k < o.data.size(); k += 2) {
        const auto byte = parse_mode(o.data.substr(k, 2), true);
        if (!byte) {
          data.reset();
          break;
        }
        fixed_data.push_back(static_cast<uint8_t>(byte->value));
      }
      if (data && !model::length_to_dlc(static_cast<uint8_t>(fixed_data.size()), o.fd)) {
        data.reset();
      }
    }
  }
  if (!data) {
    return fail(fmt::format("-D '{}': r, i or the payload in hex pairs (a {} length)", o.data,
                            o.fd ? "CAN FD" : "classic CAN"));
  }
  if (o.brs && !o.fd) {
    return fail("-b (bit-rate switch) needs -f (CAN FD frames)");
  }
  if (o.remote && o.fd) {
    return fail("-R: CAN FD has no remote frames");
  }

  auto c = connect(socket, "canemu gen");
  if (!c) {
    return fail(c.error().message);
  }
  const auto base = time_base(*c, o.sim_time);
  if (!base) {
    return fail(base.error().message);
  }
  const bool stepped = base->stepped();
  if (const auto kind = bus_kind(*c, o.bus); o.fd && kind && kind->first == ipc::WireBusKind::can) {
    return fail("-f: " + classic_bus_text(o.bus));
  }
  client::ChannelOptions co;
  co.bus = o.bus;
  co.bitrate = o.bitrate;
  co.flags = ipc::kChannelReportTx;
  co.tx_capacity = 256;
  co.rx_capacity = 4096;
  auto ch = client::Channel::open(*c, co);
  if (!ch) {
    return fail(ch.error().message);
  }
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  std::fprintf(stderr, "canemu: generating on %s as %s (%u bit/s, a frame every %s)\n",
               o.bus.c_str(), ch->device().c_str(), ch->info().bitrate, o.gap.c_str());

  Generator gen(o, *id, *length, *data, fixed_data);
  uint64_t queued = 0, sent = 0, dropped = 0;
  // Real and scaled time: the node's progress in simulated time. Waits end after --timeout ms
  // of simulated time without a frame sent or given up, never after wall-clock time: a
  // simulation behind the wall clock (a busy machine, a slow scale) delays the confirmations
  // but loses nothing, while a frame nobody acknowledges is retried for that long.
  int64_t progress_ns = 0;
  const auto confirmations = [&](int wait_ms) {
    int handled = 0;
    while (auto m = ch->receive(wait_ms)) {
      wait_ms = 0;
      if (m->kind == static_cast<uint8_t>(ipc::ChannelMessageKind::tx_done)) {
        ++sent;
        ++handled;
        progress_ns = std::max(progress_ns, m->timestamp_ns);
        if (o.verbose) {
          m->kind = static_cast<uint8_t>(ipc::ChannelMessageKind::frame);
          std::printf("%s\n", log_line(*m, o.bus, *base).c_str());
          std::fflush(stdout);
        }
      } else if (m->kind == static_cast<uint8_t>(ipc::ChannelMessageKind::tx_dropped)) {
        ++dropped;
        ++handled;
        progress_ns = std::max(progress_ns, m->timestamp_ns);
      }
      if (sent + dropped == queued) {
        break;
      }
    }
    return handled;
  };
  // The simulated instant a wait began (or the last progress since): a stall is --timeout ms of
  // simulated time after it with nothing confirmed.
  int64_t wait_from_ns = 0;
  const auto begin_wait = [&] {
    auto now = ch->status();
    wait_from_ns = now ? now->sim_time_ns : 0;
  };
  const auto stalled = [&] {
    auto now = ch->status();
    return !now || now->sim_time_ns - std::max(wait_from_ns, progress_ns) >=
                       int64_t{o.timeout_ms} * 1'000'000;
  };
  const int64_t step_ns = std::max<int64_t>(*gap, 1000);
  bool stuck = false;
  while (!g_stop && !stuck && (o.count == 0 || queued < o.count)) {
    const ipc::ChannelMessage next = gen.next();
    auto put = ch->send(next, stepped ? o.timeout_ms : 0);
    if (!put && !stepped && put.error().error_number == EAGAIN) {
      // The transmit FIFO is full: wait for room while the node makes progress.
      begin_wait();
      while (!put && put.error().error_number == EAGAIN && !g_stop) {
        if (confirmations(10) == 0 && stalled()) {
          stuck = true;
          break;
        }
        put = ch->send(next, 0);
      }
    }
    if (!put) {
      if (!stuck && !g_stop) {
        std::fprintf(stderr, "canemu: %s\n", put.error().message.c_str());
      }
      break;
    }
    ++queued;
    if (stepped) {
      auto r = step_time(*c, step_ns);
      if (!r) {
        return fail(r.error().message);
      }
    } else if (*gap > 0) {
      std::this_thread::sleep_for(std::chrono::nanoseconds(*gap));
    }
    confirmations(0);
  }
  // The frames still on their way get their time on the bus: stepped, up to 10 s of simulated
  // time in 10 ms steps (256 frames at 5 kbit/s take about 7 s); otherwise until --timeout ms of
  // simulated time pass without one sent.
  if (!stepped && sent + dropped < queued && !stuck) {
    begin_wait();
  }
  for (int round = 0; sent + dropped < queued && !stuck && (!stepped || round < 1000); ++round) {
    if (stepped) {
      auto r = step_time(*c, 10'000'000);
      if (!r) {
        return fail(r.error().message);
      }
      confirmations(0);
    } else if (confirmations(50) == 0 && stalled()) {
      break;
    }
  }
  const uint64_t pending = queued - sent - dropped;
  std::fprintf(stderr, "canemu: %llu frame(s) sent on %s", static_cast<unsigned long long>(sent),
               o.bus.c_str());
  if (dropped != 0) {
    std::fprintf(stderr, ", %llu given up by its node after errors",
                 static_cast<unsigned long long>(dropped));
  }
  if (pending != 0) {
    std::fprintf(stderr, ", %llu not sent: is a node on %s acknowledging at %u bit/s?",
                 static_cast<unsigned long long>(pending), o.bus.c_str(), ch->info().bitrate);
  }
  std::fprintf(stderr, "\n");
  return dropped == 0 && pending == 0 ? 0 : 1;
}

}  // namespace

Command add_gen(CLI::App& app, const std::string& socket) {
  auto* gen = app.add_subcommand(
      "gen", "generate frames on a bus as cangen does, e.g. 'gen can0 -g 10ms -n 100'");
  auto o = std::make_shared<GenOptions>();
  gen->add_option("BUS", o->bus, "bus name")->required();
  gen->add_option("-g,--gap", o->gap,
                  "time between frames: ms as cangen's -g (10, 0.5), or with a unit (500us); "
                  "default 200ms, 0 back to back");
  gen->add_option("-n,--count", o->count, "stop after this many frames (default: until Ctrl-C)");
  gen->add_option("-I,--id", o->id,
                  "identifier: r random (default), i increment, or hex (123 or 0x123)");
  gen->add_option("-L,--length", o->length,
                  "length: r random DLC (default), i increment, or bytes");
  gen->add_option("-D,--data", o->data, "data: r random (default), i increment, or hex bytes");
  gen->add_flag("-e,--extended", o->extended, "29-bit identifiers");
  gen->add_flag("-f,--fd", o->fd, "CAN FD frames (the bus must be can-fd)");
  gen->add_flag("-b,--brs", o->brs, "CAN FD with bit-rate switch");
  gen->add_flag("-R,--remote", o->remote, "remote frames");
  gen->add_flag("-v,--verbose", o->verbose, "print each frame sent as a candump -L line");
  gen->add_flag("--sim-time", o->sim_time,
                "time stamps in simulated seconds (default in real time: wall-clock seconds)");
  gen->add_option("--bitrate", o->bitrate, "the sender's bit/s (default: the bus's)");
  gen->add_option("--seed", o->seed, "seed of the random choices (default 1)");
  gen->add_option("--timeout", o->timeout_ms,
                  "ms of simulated time without a frame sent before giving up, when the "
                  "transmit FIFO is full and at the end (default 2000)")
      ->check(CLI::Range(0, 3'600'000));
  return {gen, [&socket, o] { return run_gen(socket, *o); }};
}

}  // namespace canemu::cli
