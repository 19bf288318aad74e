// A bus recorded into a file by canemud ([[recorder]]): a listen-only node of its own on the bus
// (model::HostedNode, so it changes nothing on the wire: no acknowledgements, no error flags)
// whose received frames, bus errors and state changes go through ipc::CaptureWriter into a
// candump log or a pcap file, stamped with their simulated instant.
//
// Records are written when the server flushes (once per pass of its loop, before a status
// reply and after a time step), so a test that steps time finds them on disk. A failed write is
// counted (lost()) and its reason kept (error()); the server logs each new failure once.
#pragma once

#include <memory>
#include <string>

#include <tl/expected.hpp>

#include "canemu/daemon/config.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/ipc/capture_writer.hpp"

namespace canemu::daemon {

class Recorder final : private model::ControllerEvents {
 public:
  // Opens the file and starts `node` (a spare node of the bus) listen-only with `settings`.
  static tl::expected<std::unique_ptr<Recorder>, std::string> start(
      const RecorderConfig& config, std::size_t bus, model::HostedNode& node,
      model::HostedNodeSettings settings);
  ~Recorder() override;  // stops the node and writes what is pending
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  const RecorderConfig& config() const { return config_; }
  std::size_t bus() const { return bus_; }
  const ipc::CaptureWriter& writer() const { return writer_; }

  // Writes what is pending. True when frames began to be lost (after a pass that lost none):
  // the server logs writer().error() then, not on every pass of a full disk.
  bool flush();

 private:
  Recorder(const RecorderConfig& config, std::size_t bus, model::HostedNode& node,
           ipc::CaptureWriter writer)
      : config_(config), bus_(bus), node_(node), writer_(std::move(writer)) {}

  void record(const ipc::ChannelMessage& m);
  void frame_received(model::SimTime at, const model::Frame& frame, bool own) override;
  void bus_error(const model::BusErrorEvent& event) override;
  void state_changed(model::SimTime at, model::ErrorState state, uint16_t tec,
                     uint16_t rec) override;

  RecorderConfig config_;
  std::size_t bus_;
  model::HostedNode& node_;
  ipc::CaptureWriter writer_;
  uint64_t reported_lost_ = 0;
  bool failing_ = false;
};

}  // namespace canemu::daemon
