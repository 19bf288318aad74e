// What every subcommand of the canemu command line shares: how it is registered with the
// parser and run, and how it reports failure.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace CLI {
class App;
}

namespace canemu::cli {

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
Command add_send(CLI::App& app, const std::string& socket);
Command add_dump(CLI::App& app, const std::string& socket);
Command add_fault(CLI::App& app, const std::string& socket);
Command add_time(CLI::App& app, const std::string& socket);
Command add_calc(CLI::App& app);

// Prints "canemu: <message>" to stderr; returns the exit code of a failed command (1).
int fail(const std::string& message);

// A positive duration from the command line ("150ns", "20us", "10ms", "2s").
std::optional<int64_t> parse_positive_duration(const std::string& text);

}  // namespace canemu::cli
