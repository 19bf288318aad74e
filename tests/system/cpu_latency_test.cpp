// simulation.cpu_latency_us: canemud holds a PM QoS request (the bound written into the file,
// kept open) in real and scaled time, changes or ends it on a reload, makes none in stepped
// time, and goes on without one (naming the file) when it cannot open the file. The file is
// CANEMU_CPU_LATENCY_FILE here, a plain file of the test's own, not the kernel's device.
#include <gtest/gtest.h>

#include <array>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <sys/stat.h>

#include "../support/scoped_env.hpp"
#include "../support/temp_dir.hpp"
#include "daemon_process.hpp"

namespace canemu {
namespace {

using testing::connect;
using testing::Daemon;
using testing::status;
using testing::write_file;

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

// How many of process `pid`'s descriptors are open on the file at `path` (compared by device
// and inode, not by name).
int opened(pid_t pid, const std::string& path) {
  struct stat want {};
  if (::stat(path.c_str(), &want) != 0) {
    return 0;
  }
  int n = 0;
  const std::filesystem::path fds = "/proc/" + std::to_string(pid) + "/fd";
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(fds, ec)) {
    struct stat got {};
    if (::stat(e.path().c_str(), &got) == 0 && got.st_dev == want.st_dev &&
        got.st_ino == want.st_ino) {
      ++n;
    }
  }
  return n;
}

// A folder of the test's own, the file canemud is to write its request into
// (CANEMU_CPU_LATENCY_FILE: one byte in it, as the kernel's device exists before anyone writes
// it; or, unless `made`, nothing there yet), and canemud's configuration with one bus and
// `cpu_latency_us` (none if negative).
struct Rig {
  explicit Rig(int64_t bound, bool made = true)
      : qos((dir.path / "qos").string()),
        env("CANEMU_CPU_LATENCY_FILE", qos),
        config((dir.path / "canemud.toml").string()) {
    if (made) {
      std::ofstream(qos).put('x');
    }
    set(bound);
  }
  void set(int64_t bound) const {
    write_file(config,
               (bound < 0 ? std::string()
                          : "[simulation]\ncpu_latency_us = " + std::to_string(bound) + "\n\n") +
                   "[[bus]]\nname = \"a\"\n");
  }
  testing::TempDir dir;
  std::string qos;
  testing::ScopedEnv env;
  std::string config;
};

TEST(CpuLatency, RealTimeHoldsTheRequestAReloadChangesOrEndsIt) {
  const Rig rig(0);
  const std::string& qos = rig.qos;
  Daemon d("realtime", {"--config=" + rig.config});
  ASSERT_TRUE(d.read_log_until("CPUs asked to wake within 0 us", 10'000)) << d.log();
  EXPECT_EQ(written(qos), 0);
  EXPECT_EQ(opened(d.pid(), qos), 1);

  rig.set(25);
  d.signal(SIGHUP);
  ASSERT_TRUE(d.read_log_until("CPUs asked to wake within 25 us", 10'000)) << d.log();
  EXPECT_NE(d.log().find("reload: simulation: cpu_latency_us 25"), std::string::npos) << d.log();
  EXPECT_EQ(written(qos), 25);
  EXPECT_EQ(opened(d.pid(), qos), 1);

  rig.set(-1);
  d.signal(SIGHUP);
  ASSERT_TRUE(d.read_log_until("CPU wake-up latency request of 25 us ended", 10'000)) << d.log();
  EXPECT_NE(d.log().find("reload: simulation: cpu_latency_us removed"), std::string::npos);
  EXPECT_EQ(opened(d.pid(), qos), 0);
}

TEST(CpuLatency, ARequestThatCannotBeChangedStaysAsItWas) {
  const Rig rig(0);
  const std::string& qos = rig.qos;
  Daemon d("realtime", {"--config=" + rig.config});
  ASSERT_TRUE(d.read_log_until("CPUs asked to wake within 0 us", 10'000)) << d.log();
  std::filesystem::remove(qos);  // the next open fails; the one held stays open
  rig.set(25);
  d.signal(SIGHUP);
  ASSERT_TRUE(d.read_log_until("the request of 0 us stays", 10'000)) << d.log();
  EXPECT_NE(d.log().find("simulation.cpu_latency_us 25: no request made: " + qos +
                         ": No such file or directory"),
            std::string::npos)
      << d.log();
  EXPECT_EQ(d.log().find("request of 0 us ended"), std::string::npos) << d.log();
}

// A file whose open would wait (a FIFO nobody reads) does not hold up the loop: refused at once.
TEST(CpuLatency, AFileWhoseOpenWouldWaitIsRefusedAtOnce) {
  const Rig rig(5, false);
  ASSERT_EQ(::mkfifo(rig.qos.c_str(), 0600), 0);
  Daemon d("realtime", {"--config=" + rig.config});
  ASSERT_TRUE(d.read_log_until("no request made", 10'000)) << d.log();
  EXPECT_NE(d.log().find("simulation.cpu_latency_us 5: no request made: " + rig.qos),
            std::string::npos)
      << d.log();
  auto c = connect(d);
  EXPECT_EQ(status(c).bus_count, 1);
}

TEST(CpuLatency, SteppedTimeMakesNoRequest) {
  const Rig rig(0);
  const std::string& qos = rig.qos;
  Daemon d("stepped", {"--config=" + rig.config});
  auto c = connect(d);
  EXPECT_EQ(status(c).bus_count, 1);  // started and serving, past where a request is made
  EXPECT_EQ(written(qos), -1);        // still the one byte written above
  EXPECT_EQ(opened(d.pid(), qos), 0);
  EXPECT_EQ(d.log().find("cpu_latency"), std::string::npos) << d.log();
  EXPECT_EQ(d.log().find("CPUs asked"), std::string::npos) << d.log();
}

TEST(CpuLatency, AFileItCannotOpenIsNamedAndTheDaemonRunsWithoutTheRequest) {
  const Rig rig(10, false);
  const std::string& qos = rig.qos;
  Daemon d("realtime", {"--config=" + rig.config});
  ASSERT_TRUE(d.read_log_until("no request made", 10'000)) << d.log();
  EXPECT_NE(d.log().find("simulation.cpu_latency_us 10: no request made: " + qos +
                         ": No such file or directory"),
            std::string::npos)
      << d.log();
  auto c = connect(d);
  EXPECT_EQ(status(c).bus_count, 1);
}

}  // namespace
}  // namespace canemu
