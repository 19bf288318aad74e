// A bus recorded into a file by canemud ([[recorder]]): a listen-only node of its own on the bus
// (model::HostedNode, so it changes nothing on the wire: no acknowledgements, no error flags)
// whose received frames, bus errors and state changes go through ipc::CaptureWriter into a
// candump log or a pcap file, stamped with their simulated instant.
//
// On a LIN bus the node is a listener of the LinBus that takes each header's bit rate and
// answers nothing; the frames, errors and events it sees go into a pcap file with LINKTYPE_LIN
// (lin_pcap_message(); docs/lin.md, "Recording a LIN bus").
//
// Records are written when the server flushes (once per pass of its loop, before a status
// reply and after a time step), so a test that steps time finds them on disk. A failed write is
// counted (lost()) and its reason kept (error()); the server logs each new failure once.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <tl/expected.hpp>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/config/config.hpp"
#include "canemu/firmware_model/bus/lin_bus.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/ipc/capture_writer.hpp"
#include "canemu/ipc/lin_pcap.hpp"

namespace canemu::daemon {

// The LINKTYPE_LIN record of what a LIN listener saw: a frame (its protected identifier,
// data, checksum and kind; identifiers 3Eh and 3Fh with the invalid-ID bit), an error (the
// no-response, checksum, parity bits; sync, bit and break errors as framing errors; what was
// received of the frame: the PID when the identifier is known, else 0, and for a checksum error
// the characters), or an event (go-to-sleep command, 4 s of inactivity, wake-up).
ipc::lin_pcap::Message lin_pcap_message(const model::lin::Event& e);

class Recorder final : private model::ControllerEvents, private model::lin::LinNode {
 public:
  // Opens the file and starts `node` (a spare node of the bus) listen-only with `settings`.
  static Result<std::unique_ptr<Recorder>> start(const RecorderConfig& config, std::size_t bus,
                                                 model::HostedNode& node,
                                                 model::HostedNodeSettings settings);
  // A LIN bus: opens the file (pcap) and attaches a listener of its own to `lin_bus`.
  static Result<std::unique_ptr<Recorder>> start_lin(const RecorderConfig& config, std::size_t bus,
                                                     model::lin::LinBus& lin_bus);
  ~Recorder() override;  // stops (detaches) the node and writes what is pending
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  const RecorderConfig& config() const { return config_; }
  std::size_t bus() const { return bus_; }
  const ipc::CaptureWriter& writer() const { return writer_; }

  // Writes what is pending. True when frames began to be lost (after a pass that lost none):
  // the server logs writer().error() then, not on every pass of a full disk.
  bool flush();

 private:
  Recorder(const RecorderConfig& config, std::size_t bus, ipc::CaptureWriter writer)
      : config_(config), bus_(bus), writer_(std::move(writer)) {}

  void record(const ipc::ChannelMessage& m);
  void frame_received(model::SimTime at, const model::Frame& frame, bool own) override;
  void bus_error(const model::BusErrorEvent& event) override;
  void state_changed(model::SimTime at, model::ErrorState state, uint16_t tec,
                     uint16_t rec) override;

  std::optional<model::lin::Response> respond(uint8_t) override { return std::nullopt; }
  void on_lin_event(const model::lin::Event& e) override;
  uint32_t lin_bitrate() const override { return 0; }  // each header's

  RecorderConfig config_;
  std::size_t bus_;
  model::HostedNode* node_ = nullptr;      // CAN
  model::lin::LinBus* lin_bus_ = nullptr;  // LIN
  model::lin::LinNodeId lin_node_ = model::lin::kNoNode;
  ipc::CaptureWriter writer_;
  uint64_t reported_lost_ = 0;
  bool failing_ = false;
};

}  // namespace canemu::daemon
