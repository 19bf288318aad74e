#include "command.hpp"

#include <time.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "canemu/firmware_model/bus/can_error.hpp"
#include "canemu/ipc/duration.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/socketcan.hpp"

namespace canemu::cli {

double g_connect_wait_s = 0;

client::Result<client::Connection> connect(const std::string& socket, const std::string& name) {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(g_connect_wait_s));
  for (;;) {
    auto c = client::Connection::open(ipc::socket_path(socket), name);
    if (c || std::chrono::steady_clock::now() >= deadline) {
      return c;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

namespace {

int64_t wall_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

client::Result<TimeBase> time_base(client::Connection& c, bool sim_time) {
  const int64_t before = wall_ns();
  auto s = c.call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
  const int64_t after = wall_ns();
  if (!s) {
    return tl::unexpected(s.error());
  }
  const auto mode = static_cast<ipc::WireTimeMode>(s->time_mode);
  if (sim_time || mode != ipc::WireTimeMode::realtime) {
    return TimeBase{0, false, mode};
  }
  return TimeBase{before + (after - before) / 2 - s->sim_time_ns, true, mode};
}

client::Result<ipc::TimeStepReply> step_time(client::Connection& c, int64_t ns) {
  auto req = ipc::make_message<ipc::TimeStepRequest>();
  req.step_ns = ns;
  return c.call<ipc::TimeStepRequest, ipc::TimeStepReply>(req, -1);
}

std::string log_line(const ipc::ChannelMessage& m, const std::string& bus, const TimeBase& base) {
  const auto f = ipc::socketcan::from_message(m);
  return f ? ipc::socketcan::candump_line(m.timestamp_ns + base.offset_ns, bus, *f) : std::string();
}

// The wire's error states are the model's, in the model's order.
static_assert(static_cast<uint8_t>(ipc::WireErrorState::bus_off) ==
              static_cast<uint8_t>(model::ErrorState::bus_off));

std::string error_state_name(uint8_t state) {
  return std::string(model::to_string(static_cast<model::ErrorState>(state)));
}

std::string classic_bus_text(const std::string& bus) {
  return bus + " is a classic CAN bus (CAN FD needs a bus of kind can-fd)";
}

int fail(const std::string& message) {
  std::fprintf(stderr, "canemu: %s\n", message.c_str());
  return 1;
}

std::optional<int64_t> parse_positive_duration(const std::string& text) {
  const auto ns = ipc::parse_duration(text);
  return ns && *ns > 0 ? ns : std::nullopt;
}

}  // namespace canemu::cli
