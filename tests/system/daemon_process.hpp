// canemud from this build as a child process for a test, and helpers for its clients.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "../support/canemud_process.hpp"
#include "canemu/client/connection.hpp"

namespace canemu::testing {

// canemud from this build, in `time` mode (plus `args`), for one test.
class Daemon : public CanemudProcess {
 public:
  explicit Daemon(const std::string& time = "stepped", std::vector<std::string> args = {})
      : CanemudProcess(CANEMUD_PATH, with_time(time, std::move(args))) {
    EXPECT_TRUE(ready()) << log();
  }

 private:
  static std::vector<std::string> with_time(const std::string& time,
                                            std::vector<std::string> args) {
    args.insert(args.begin(), "--time=" + time);
    return args;
  }
};

inline client::Connection connect(const Daemon& d, const char* name = "test") {
  auto c = client::Connection::open(d.socket(), name);
  EXPECT_TRUE(c) << c.error().message;
  return std::move(*c);
}

inline ipc::StatusReply status(client::Connection& c) {
  auto r = c.call<ipc::StatusRequest, ipc::StatusReply>(ipc::make_message<ipc::StatusRequest>());
  EXPECT_TRUE(r) << r.error().message;
  return r ? *r : ipc::StatusReply{};
}

}  // namespace canemu::testing
