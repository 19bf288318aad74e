#include "canemu/daemon/recorder.hpp"

#include "canemu/daemon/channel.hpp"
#include "canemu/ipc/socketcan.hpp"

namespace canemu::daemon {

tl::expected<std::unique_ptr<Recorder>, std::string> Recorder::start(
    const RecorderConfig& config, std::size_t bus, model::HostedNode& node,
    model::HostedNodeSettings settings) {
  ipc::CaptureOptions options;
  options.path = config.path;
  options.format = config.pcap ? ipc::CaptureFormat::pcap : ipc::CaptureFormat::candump;
  options.bus = config.bus;
  options.max_bytes = config.max_size;
  options.max_files = config.max_files;
  auto writer = ipc::CaptureWriter::open(std::move(options));
  if (!writer) {
    return tl::unexpected("recorder of " + config.bus + ": " + writer.error().message);
  }
  std::unique_ptr<Recorder> r(new Recorder(config, bus, node, std::move(*writer)));
  settings.listen_only = true;
  node.start(settings, r.get(), [] { return std::optional<model::TxFrame>(); });
  return r;
}

Recorder::~Recorder() {
  node_.stop();
  writer_.flush();
}

bool Recorder::flush() {
  writer_.flush();
  const bool losing = writer_.lost() > reported_lost_;
  const bool news = losing && !failing_;
  failing_ = losing;
  reported_lost_ = writer_.lost();
  return news;
}

void Recorder::record(const ipc::ChannelMessage& m) {
  if (const auto f = ipc::socketcan::from_message(m)) {
    writer_.record(m.timestamp_ns, *f);
  }
}

void Recorder::frame_received(model::SimTime at, const model::Frame& frame, bool own) {
  record(to_message(at, frame, ipc::ChannelMessageKind::frame, own));
}

void Recorder::bus_error(const model::BusErrorEvent& event) {
  if (config_.errors) {
    record(to_error_message(event, node_.controller().confinement().state()));
  }
}

void Recorder::state_changed(model::SimTime at, model::ErrorState state, uint16_t tec,
                             uint16_t rec) {
  if (config_.errors) {
    record(to_state_message(at, state, tec, rec));
  }
}

}  // namespace canemu::daemon
