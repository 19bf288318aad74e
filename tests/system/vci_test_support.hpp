// What the VCI tests share: a canemud with a configuration of their own, stepped time through
// the canemu extension, and faults loaded into it. Used by the tests of libvcinpl, libvcinpl2
// and libvciapi (each built against its own header); what only one API's tests share is in
// vci_c_test_support.hpp and vci_cpp_test_support.hpp.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <unistd.h>

#include "canemu_vci.h"
#include "daemon_process.hpp"

namespace canemu::testing {

// Two adapters, alpha and beta, each with one SJA1000 on the classic bus can0 (500 kbit/s).
inline const char* const kTwoAdapters =
    "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n"
    "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n\n"
    "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n";

// A configuration file in a fresh directory, removed with the object.
class ConfigFile {
 public:
  explicit ConfigFile(const std::string& text) {
    char dir[] = "/tmp/canemu-vci-XXXXXX";
    dir_ = ::mkdtemp(dir);
    path_ = dir_ + "/canemu.toml";
    FILE* f = std::fopen(path_.c_str(), "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
  }
  ~ConfigFile() {
    ::unlink(path_.c_str());
    ::rmdir(dir_.c_str());
  }
  const std::string& path() const { return path_; }

 private:
  std::string dir_;
  std::string path_;
};

// canemud in stepped time on `config`, and the VCI library pointed at it.
struct VciDaemon {
  ConfigFile config;
  Daemon daemon;
  explicit VciDaemon(const std::string& text = kTwoAdapters)
      : config(text), daemon("stepped", {"--config=" + config.path()}) {
    EXPECT_EQ(canemuConnect(daemon.socket().c_str()), VCI_OK);
  }
  ~VciDaemon() { canemuConnect(nullptr); }
};

// Runs simulated time `ns` further.
inline void step_ns(uint64_t ns) {
  UINT64 now = 0;
  ASSERT_EQ(canemuStepTime(ns, &now), VCI_OK);
}

// Steps simulated time a millisecond at a time until `done` (set by another thread that waits
// for something in simulated time), for at most 30 s of wall time.
inline void step_until(const std::atomic<bool>& done) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!done && std::chrono::steady_clock::now() < give_up) {
    step_ns(1'000'000);
  }
  ASSERT_TRUE(done) << "the waiting call did not return";
}

// Simulated time from canemud's start (each test starts its own canemud at 0), stepped to
// exact instants.
struct SimClock {
  uint64_t now = 0;
  void to(uint64_t t_ns) {
    ASSERT_GT(t_ns, now);
    UINT64 after = 0;
    ASSERT_EQ(canemuStepTime(t_ns - now, &after), VCI_OK);
    now = after;
    ASSERT_EQ(now, t_ns);
  }
};

// The identifiers of `msgs` (CANMSG or CANMSG2), in order.
template <class Msg>
inline std::vector<uint32_t> ids_of(const std::vector<Msg>& msgs) {
  std::vector<uint32_t> ids;
  for (const Msg& m : msgs) {
    ids.push_back(m.dwMsgId);
  }
  return ids;
}

// Loads a fault scenario from `text` into the daemon.
inline void load_faults(const Daemon& d, const std::string& text) {
  auto c = connect(d, "faults");
  auto m = ipc::make_message<ipc::FaultLoadRequest>();
  ipc::copy_name(m.source, "test.toml");
  m.length = static_cast<uint32_t>(text.size());
  std::memcpy(m.text, text.data(), text.size());
  auto r = c.call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(m);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_GT(r->applied, 0u) << r->errors;  // a refused scenario is the test's mistake
}

}  // namespace canemu::testing
