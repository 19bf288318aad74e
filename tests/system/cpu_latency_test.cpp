// simulation.cpu_latency_us: canemud holds a PM QoS request (the bound written into the file,
// kept open) in real and scaled time, changes or ends it on a reload, makes none in stepped
// time, and goes on without one (naming the file) when it cannot open the file. The file is
// CANEMU_CPU_LATENCY_FILE here, a plain file of the test's own, not the kernel's device.
#include <gtest/gtest.h>

#include <array>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "../support/temp_dir.hpp"
#include "daemon_process.hpp"

namespace canemu {
namespace {

using testing::connect;
using testing::Daemon;
using testing::status;

// Sets CANEMU_CPU_LATENCY_FILE while it lives; the daemons started meanwhile inherit it.
class LatencyFile {
 public:
  explicit LatencyFile(std::string path) : path_(std::move(path)) {
    ::setenv("CANEMU_CPU_LATENCY_FILE", path_.c_str(), 1);
  }
  ~LatencyFile() { ::unsetenv("CANEMU_CPU_LATENCY_FILE"); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// The 32-bit value at the start of the file, or -1 if it has fewer than four bytes.
int64_t written(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::array<char, 4> b{};
  if (!f.read(b.data(), 4)) {
    return -1;
  }
  int32_t v = 0;
  std::memcpy(&v, b.data(), 4);
  return v;
}

// Whether process `pid` has `path` open.
bool holds(pid_t pid, const std::string& path) {
  const std::filesystem::path fds = "/proc/" + std::to_string(pid) + "/fd";
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(fds, ec)) {
    std::error_code ignored;
    if (std::filesystem::read_symlink(e.path(), ignored) == path) {
      return true;
    }
  }
  return false;
}

void write_file(const std::string& file, const std::string& text) {
  std::ofstream(file) << text;
}

TEST(CpuLatency, RealTimeHoldsTheRequestAReloadChangesOrEndsIt) {
  testing::TempDir dir;
  const LatencyFile qos((dir.path / "qos").string());
  std::ofstream(qos.path()).put('x');  // the kernel's device exists before anyone writes it
  const std::string config = (dir.path / "canemud.toml").string();
  write_file(config, "[simulation]\ncpu_latency_us = 0\n\n[[bus]]\nname = \"a\"\n");
  Daemon d("realtime", {"--config=" + config});
  ASSERT_TRUE(d.read_log_until("CPUs asked to wake within 0 us", 10'000)) << d.log();
  EXPECT_EQ(written(qos.path()), 0);
  EXPECT_TRUE(holds(d.pid(), qos.path()));

  write_file(config, "[simulation]\ncpu_latency_us = 25\n\n[[bus]]\nname = \"a\"\n");
  d.signal(SIGHUP);
  ASSERT_TRUE(d.read_log_until("CPUs asked to wake within 25 us", 10'000)) << d.log();
  EXPECT_NE(d.log().find("reload: simulation: cpu_latency_us 25"), std::string::npos) << d.log();
  EXPECT_EQ(written(qos.path()), 25);
  EXPECT_TRUE(holds(d.pid(), qos.path()));

  write_file(config, "[[bus]]\nname = \"a\"\n");
  d.signal(SIGHUP);
  ASSERT_TRUE(d.read_log_until("CPU wake-up latency request of 25 us ended", 10'000)) << d.log();
  EXPECT_NE(d.log().find("reload: simulation: cpu_latency_us removed"), std::string::npos);
  EXPECT_FALSE(holds(d.pid(), qos.path()));
}

TEST(CpuLatency, SteppedTimeMakesNoRequest) {
  testing::TempDir dir;
  const LatencyFile qos((dir.path / "qos").string());
  const std::string config = (dir.path / "canemud.toml").string();
  write_file(config, "[simulation]\ncpu_latency_us = 0\n\n[[bus]]\nname = \"a\"\n");
  Daemon d("stepped", {"--config=" + config});
  auto c = connect(d);
  EXPECT_EQ(status(c).bus_count, 1);  // started and serving
  EXPECT_FALSE(std::filesystem::exists(qos.path()));
  EXPECT_EQ(d.log().find("CPUs asked"), std::string::npos) << d.log();
}

TEST(CpuLatency, AFileItCannotOpenIsNamedAndTheDaemonRunsWithoutTheRequest) {
  testing::TempDir dir;
  const LatencyFile qos((dir.path / "no-such-folder" / "qos").string());
  const std::string config = (dir.path / "canemud.toml").string();
  write_file(config, "[simulation]\ncpu_latency_us = 10\n\n[[bus]]\nname = \"a\"\n");
  Daemon d("realtime", {"--config=" + config});
  ASSERT_TRUE(d.read_log_until("no request made", 10'000)) << d.log();
  EXPECT_NE(d.log().find("simulation.cpu_latency_us 10: no request made: " + qos.path() +
                         ": No such file or directory"),
            std::string::npos)
      << d.log();
  auto c = connect(d);
  EXPECT_EQ(status(c).bus_count, 1);
}

}  // namespace
}  // namespace canemu
