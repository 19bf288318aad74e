// simulation.cpu_latency_us: a PM QoS request that keeps idle CPUs in states they leave within
// a bound. canemud holds it while it keeps real or scaled time: it opens the kernel's
// /dev/cpu_dma_latency, writes the bound in microseconds as a 32-bit integer, and keeps the file
// open; the request ends when the file is closed (a reload without the key, stepped time,
// canemud's exit, however it ends). 0 keeps idle CPUs polling, so that a wake-up (a client's
// doorbell, the timer at a frame's end) needs no exit from a halt: on a virtual machine whose
// idle CPUs halt, that exit costs tens of microseconds a wake-up (docs/daemon.md, "Latency").
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "canemu/ipc/unique_fd.hpp"

namespace canemu::daemon {

class CpuLatencyRequest {
 public:
  // The file written: CANEMU_CPU_LATENCY_FILE if set (for tests), else /dev/cpu_dma_latency.
  static std::string file();
  // Holds a request for `us` microseconds, or none (nullopt); a request held for another bound
  // ends once the new one is made. Returns why it could not be made (then the request held
  // before, if any, stays), empty if it was.
  std::string hold(std::optional<uint32_t> us);
  std::optional<uint32_t> held() const { return held_; }

 private:
  ipc::UniqueFd fd_;
  std::optional<uint32_t> held_;
};

}  // namespace canemu::daemon
