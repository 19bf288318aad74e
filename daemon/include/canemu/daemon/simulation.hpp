// The emulated world canemud runs: one CanBus per configured bus, one controller model per
// configured adapter controller, all on one scheduler (one simulation island).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/config.hpp"
#include "canemu/firmware_model/can_bus.hpp"
#include "canemu/firmware_model/can_fd_controller.hpp"
#include "canemu/firmware_model/sja1000.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

// SJA1000 BTR0/BTR1 at 16 MHz for `bitrate`, with the sample point closest to `sample_point`
// (per mille); nothing if no register values give that rate exactly.
std::optional<std::pair<uint8_t, uint8_t>> sja1000_btr_for(uint32_t bitrate, uint32_t sample_point);
// The emulated CAN FD controller's timing for a rate in one phase (80 MHz clock).
std::optional<model::BitTiming> fd_timing_for(uint32_t bitrate, uint32_t sample_point,
                                              model::vci::Phase phase);

class Simulation {
 public:
  static tl::expected<std::unique_ptr<Simulation>, std::vector<std::string>> build(
      const Config& config);

  model::SimScheduler& scheduler() { return scheduler_; }
  const Config& config() const { return config_; }
  std::size_t bus_count() const { return buses_.size(); }
  model::CanBus& bus(std::size_t i) { return *buses_[i].bus; }

  // What `canemu status` shows.
  void fill_status(ipc::StatusReply& reply);

 private:
  explicit Simulation(Config config) : config_(std::move(config)) {}

  struct Bus {
    std::unique_ptr<model::CanBus> bus;
    const BusConfig* config;
  };
  struct Controller {
    std::string name;  // "device:N"
    std::size_t bus;
    std::unique_ptr<model::Sja1000> sja1000;
    std::unique_ptr<model::CanFdController> fd;
    model::NodeId node;
    model::CanController& controller() {
      return sja1000 ? static_cast<model::CanController&>(*sja1000) : *fd;
    }
  };

  Config config_;
  model::SimScheduler scheduler_;
  std::vector<Bus> buses_;
  std::vector<Controller> controllers_;
};

}  // namespace canemu::daemon
