#include "canemu/daemon/bridges/recorder.hpp"

#include <algorithm>

#include "canemu/daemon/base/channel.hpp"
#include "canemu/firmware_model/bus/lin_frame.hpp"
#include "canemu/ipc/socketcan.hpp"

namespace canemu::daemon {

namespace {

namespace lin = model::lin;
namespace lp = ipc::lin_pcap;

ipc::CaptureOptions capture_options(const RecorderConfig& config, bool is_lin) {
  ipc::CaptureOptions options;
  options.path = config.path;
  options.format = config.pcap ? ipc::CaptureFormat::pcap : ipc::CaptureFormat::candump;
  options.bus = config.bus;
  options.max_bytes = config.max_size;
  options.max_files = config.max_files;
  options.lin = is_lin;
  return options;
}

}  // namespace

lp::Message lin_pcap_message(const lin::Event& e) {
  lp::Message m;
  const bool known = e.id != lin::Event::kNoId;
  if (known) {
    m.pid = lin::protected_id(e.id);
    if ((e.id & lin::kMaxId) >= 0x3E) {
      m.errors |= lp::kErrorInvalidId;
    }
  }
  const auto received = [&] {
    m.length = std::min(e.response.size, lin::kMaxData);
    std::copy(e.response.data.begin(), e.response.data.begin() + m.length, m.data);
    m.checksum = e.checksum_byte;
  };
  switch (e.kind) {
    case lin::Event::Kind::frame:
      received();
      m.checksum_type = e.response.checksum == lin::Checksum::enhanced ? lp::ChecksumType::enhanced
                                                                       : lp::ChecksumType::classic;
      return m;
    case lin::Event::Kind::wakeup:
      return lp::event(lp::kEventWakeUp);
    case lin::Event::Kind::sleep:
      return lp::event(lp::kEventGoToSleep);
    case lin::Event::Kind::error:
      break;
  }
  switch (e.error) {
    case lin::ErrorKind::inactive:
      return lp::event(lp::kEventInactivity);
    case lin::ErrorKind::no_response:
      m.errors |= lp::kErrorNoSlaveResponse;
      break;
    case lin::ErrorKind::checksum:
      received();
      m.errors |= lp::kErrorChecksum;
      break;
    case lin::ErrorKind::parity:
      m.errors |= lp::kErrorParity;
      break;
    case lin::ErrorKind::bit:
    case lin::ErrorKind::sync:
    case lin::ErrorKind::other:
      m.errors |= lp::kErrorFraming;
      break;
  }
  return m;
}

Result<std::unique_ptr<Recorder>> Recorder::start(const RecorderConfig& config, std::size_t bus,
                                                  model::HostedNode& node,
                                                  model::HostedNodeSettings settings) {
  auto writer = ipc::CaptureWriter::open(capture_options(config, false));
  if (!writer) {
    return fail(Errc::io, "recorder of " + config.bus + ": " + writer.error().message);
  }
  std::unique_ptr<Recorder> r(new Recorder(config, bus, std::move(*writer)));
  r->node_ = &node;
  settings.listen_only = true;
  node.start(settings, r.get(), [] { return std::optional<model::TxFrame>(); });
  return r;
}

Result<std::unique_ptr<Recorder>> Recorder::start_lin(const RecorderConfig& config, std::size_t bus,
                                                      lin::LinBus& lin_bus) {
  auto writer = ipc::CaptureWriter::open(capture_options(config, true));
  if (!writer) {
    return fail(Errc::io, "recorder of " + config.bus + ": " + writer.error().message);
  }
  std::unique_ptr<Recorder> r(new Recorder(config, bus, std::move(*writer)));
  r->lin_bus_ = &lin_bus;
  r->lin_node_ = lin_bus.attach(*r);
  return r;
}

Recorder::~Recorder() {
  if (node_ != nullptr) {
    node_->stop();
  }
  if (lin_bus_ != nullptr) {
    lin_bus_->detach(lin_node_);
  }
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
    record(to_error_message(event, node_->controller().confinement().state()));
  }
}

void Recorder::state_changed(model::SimTime at, model::ErrorState state, uint16_t tec,
                             uint16_t rec) {
  if (config_.errors) {
    record(to_state_message(at, state, tec, rec));
  }
}

void Recorder::on_lin_event(const lin::Event& e) {
  const lp::Message m = lin_pcap_message(e);
  if (m.type == lp::MessageType::frame && e.kind == lin::Event::Kind::error && !config_.errors) {
    return;  // frames and events only
  }
  writer_.record(e.at.ns(), m);
}

}  // namespace canemu::daemon
