// canemu against a test's canemud run to its end for what it printed or why it refused, or
// started to listen (dump, record) so that nothing sent after it is missed.
#pragma once

#include <chrono>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "canemu/client/lists.hpp"
#include "canemu/ipc/protocol.hpp"
#include "cli_process.hpp"
#include "daemon_process.hpp"

namespace canemu {

// What canemu `args` printed against `d`; it must exit 0 (what it said on stderr otherwise).
inline std::string output_of(const testing::Daemon& d, std::vector<std::string> args) {
  Cli cli(d, std::move(args));
  std::string out = Cli::read_all(cli.out);
  EXPECT_EQ(cli.wait(), 0) << Cli::read_all(cli.err);
  return out;
}

// `text` (what canemu printed) holds each of `parts`.
inline void expect_holds(const std::string& text, std::initializer_list<std::string> parts) {
  for (const std::string& part : parts) {
    EXPECT_NE(text.find(part), std::string::npos) << part << "\nnot in\n" << text;
  }
}

// What canemu `args` said on stderr against `d`, refusing: it must exit 1.
inline std::string refusal_of(const testing::Daemon& d, std::vector<std::string> args) {
  Cli cli(d, std::move(args));
  EXPECT_EQ(cli.wait(), 1) << Cli::read_all(cli.out);
  return Cli::read_all(cli.err);
}

// Starts canemu `args` against `d` into `cli` and waits (10 s at most) until canemud announces a
// device to a client watching for them: the one of the node canemu opened. Call it in
// ASSERT_NO_FATAL_FAILURE.
inline void start_listening(std::optional<Cli>& cli, const testing::Daemon& d,
                            std::vector<std::string> args) {
  auto watcher = testing::connect(d, "watcher");
  ASSERT_TRUE(watcher.subscribe(ipc::kEventDevices));
  cli.emplace(d, std::move(args));
  ASSERT_TRUE(watcher.next_notification(10'000)) << "canemu opened no node within 10 s";
}

// The same for canemu on a LIN bus (dump, record), which opens its device, then its monitor,
// then starts the line, each a request of its own, canemud announcing the device at the first:
// it also waits (10 s at most) until the status shows the LIN node of canemu's device online.
inline void start_listening_lin(std::optional<Cli>& cli, const testing::Daemon& d,
                                std::vector<std::string> args) {
  ASSERT_NO_FATAL_FAILURE(start_listening(cli, d, std::move(args)));
  auto c = testing::connect(d, "lin-watcher");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    const auto devices = client::fetch_device_list(c);
    const auto status = client::fetch_status(c);
    ASSERT_TRUE(devices && status);
    for (const ipc::DeviceEntry& device : devices->devices) {
      if (device.owner_pid != static_cast<uint32_t>(cli->pid)) {
        continue;
      }
      const std::string prefix = ipc::name_of(device.name) + ":";
      for (const ipc::StatusNode& node : status->nodes) {
        if (ipc::name_of(node.name).rfind(prefix, 0) == 0 &&
            node.lin == static_cast<uint8_t>(ipc::WireLinState::online)) {
          return;
        }
      }
    }
  }
  FAIL() << "canemu's LIN node was not online within 10 s";
}

}  // namespace canemu
