// What every subcommand of the canemu command line shares: how it is registered with the
// parser and run, and how it reports failure.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/channel_message.hpp"
#include "canemu/ipc/protocol.hpp"
#include "canemu/ipc/text_file.hpp"

namespace CLI {
class App;
}

namespace canemu::cli {

// A file the CLI reads for the daemon (a scenario, LIN tables) is at most this long.
inline constexpr std::size_t kMaxTextFileBytes = std::size_t{1} << 20;

// A subcommand as main() sees it: its parser (set when the user chose it) and what runs it.
// `run` returns the process's exit code; it may throw std::exception for a bad argument.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

// Each adds its subcommand to `app`, in the order `--help` lists them. `socket` is canemud's
// control socket as given on the command line (empty: the default); it is read when the
// command runs.
Command add_status(CLI::App& app, const std::string& socket);
Command add_metrics(CLI::App& app, const std::string& socket);
Command add_timeline(CLI::App& app, const std::string& socket);
Command add_plot(CLI::App& app, const std::string& socket);
Command add_send(CLI::App& app, const std::string& socket);
Command add_gen(CLI::App& app, const std::string& socket);
Command add_dump(CLI::App& app, const std::string& socket);
Command add_record(CLI::App& app, const std::string& socket);
Command add_bridge(CLI::App& app, const std::string& socket);
Command add_fault(CLI::App& app, const std::string& socket);
Command add_time(CLI::App& app, const std::string& socket);
Command add_eeprom(CLI::App& app, const std::string& socket);
Command add_lin(CLI::App& app, const std::string& socket);
Command add_restbus(CLI::App& app, const std::string& socket);
Command add_signal(CLI::App& app, const std::string& socket);
Command add_web(CLI::App& app, const std::string& socket);
Command add_calc(CLI::App& app);

// How long connect() keeps trying while nobody listens on the socket (the global --wait option),
// in seconds; 0: one try.
extern double g_connect_wait_s;

// A connection to canemud at `socket` (empty: the default path) as client `name`, retried every
// 50 ms for up to g_connect_wait_s seconds while the daemon is not there yet.
client::Result<client::Connection> connect(const std::string& socket, const std::string& name);

// What is added to simulated time to print a time stamp, as python-can's interface does: in real
// time the wall-clock (epoch) instant of simulated time 0, measured once; in stepped and scaled
// time, or with `sim_time`, nothing (simulated seconds).
// It also gives canemud's time mode, read in the same status request.
struct TimeBase {
  int64_t offset_ns = 0;
  bool wall_clock = false;
  ipc::WireTimeMode mode = ipc::WireTimeMode::realtime;
  bool stepped() const { return mode == ipc::WireTimeMode::stepped; }
};
client::Result<TimeBase> time_base(client::Connection& c, bool sim_time);

// Moves canemud's stepped time on by `ns`; the daemon's error text on failure.
client::Result<ipc::TimeStepReply> step_time(client::Connection& c, int64_t ns);

// One line of a candump -L log with the time stamp on `base`.
std::string log_line(const ipc::ChannelMessage& m, const std::string& bus, const TimeBase& base);

// What canemu dump and canemu record do: a channel on `bus` (dump: on each bus of `bus_args`)
// whose frames and errors go to `output` ("-": standard output) as a candump log or pcap
// capture, until interrupted or `count` frames (0: no limit).
struct CaptureRun {
  std::string bus;
  // dump: candump's bus arguments, <bus>[,filter]* or any (dump_filter.hpp); empty: `bus`.
  std::vector<std::string> bus_args;
  std::string output;
  bool log_file = false;  // dump -l: into candump-YYYY-MM-DD_HHMMSS.log, as candump -l
  std::string format;     // "candump", "pcap"; empty: by the file name and the bus (dump.cpp)
  uint32_t bitrate = 0;
  uint64_t count = 0;
  uint64_t max_bytes = 0;  // rotation (record only)
  uint32_t max_files = 10;
  bool no_errors = false;
  bool listen_only = false;
  bool sim_time = false;
  bool record = false;  // says what it wrote when it stops
  uint32_t summary_ms =
      0;  // dump --summary: a line per bus and identifier this often (dump_summary.hpp)
};
int run_capture(const std::string& socket, const CaptureRun& run);

// A node's error state from the protocol (WireErrorState) by the model's name: "error-active"...
std::string error_state_name(uint8_t state);

// Why CAN FD frames cannot go on `bus`, a classic CAN bus: "can0 is a classic CAN bus (...)".
std::string classic_bus_text(const std::string& bus);

// Prints "canemu: <message>" to stderr; returns the exit code of a failed command (1).
int fail(const std::string& message);

// A positive duration from the command line ("150ns", "20us", "10ms", "2s").
std::optional<int64_t> parse_positive_duration(const std::string& text);

}  // namespace canemu::cli
