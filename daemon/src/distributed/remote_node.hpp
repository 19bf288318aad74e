// The nodes this daemon runs on other daemons' buses (RemoteNode), for the files of buses across
// hosts. Private to them; only in builds with Cyclone DDS.
#pragma once

#include "distributed_impl.hpp"

namespace canemu::daemon {

// A node of this daemon's on a bus another daemon simulates: the driver above it (an ephemeral
// channel, a VCI line, a bridge, a recorder) sees a HostedNode; its controller is a node of the
// owner's simulation, programmed, fed and heard through the link.
class RemoteNode final : public HostedNode {
 public:
  RemoteNode(SimScheduler& scheduler, CanBus& placeholder, Distributed::Impl& link, uint32_t number,
             std::size_t bus, std::string bus_name, std::string owner, bool fd)
      : HostedNode(scheduler, placeholder),
        link_(&link),
        number_(number),
        bus_(bus),
        bus_name_(std::move(bus_name)),
        owner_(std::move(owner)),
        fd_(fd),
        device_(fmt::format("n{}", number)),
        id_(placeholder.attach(mirror_)) {
    link.nodes.push_back(this);
  }
  ~RemoteNode() override {
    if (link_ != nullptr) {
      if (programmed_) {
        request(canemu_net_REQ_CLOSE);
      }
      std::erase(link_->nodes, this);
    }
  }

  NodeId node() const override { return id_; }
  CanController& controller() override { return mirror_; }
  bool fd_capable() const override { return fd_; }
  const std::string& owner() const { return owner_; }
  const std::string& bus_name() const { return bus_name_; }
  uint32_t number() const { return number_; }
  bool in_use() const { return programmed_; }
  std::size_t bus() const { return bus_; }
  // What the owner reported of this node: frames, errors, arbitration lost.
  const NodeStats& stats() const { return stats_; }
  void unlink() { link_ = nullptr; }

  void set_device(const std::string& device) {
    device_ = device;
    if (programmed_) {
      request(canemu_net_REQ_NAME);
    }
  }

  // The owner (again) answers: the node is opened there as it is here.
  void replay() {
    if (!programmed_) {
      return;
    }
    send_open();
    if (online_) {
      request(canemu_net_REQ_ONLINE);
    }
    if (reported_off_) {  // back on the bus, error-active with fresh counters
      reported_off_ = false;
      mirror_.confinement().reset();
      events()->state_changed(now(), ErrorState::active, 0, 0);
    }
    kick();
  }

  // The owner is gone: the node is off the bus until it comes back.
  void owner_lost() {
    if (!programmed_ || !online_ || reported_off_) {
      return;
    }
    reported_off_ = true;
    FaultConfinement& fc = mirror_.confinement();
    fc.set_counters(256, fc.rec());
    events()->state_changed(now(), ErrorState::bus_off, fc.tec(), fc.rec());
  }

  void deliver(const canemu_net_Event& e, SimTime at) {
    if (e.opened != opened_) {
      return;  // for the node as it was opened before
    }
    ::canemu::model::ControllerEvents* ev = events();
    switch (e.kind) {
      case canemu_net_EV_RX:
      case canemu_net_EV_TX_DONE:
      case canemu_net_EV_DROPPED:
      case canemu_net_EV_OVERRUN: {
        auto f = frame_of_fields(e);
        if (!f) {
          link_->drop(
              NetDrop::malformed,
              fmt::format("dropped an event ({}) of daemon {} for node {} of bus {}: its "
                          "frame (id 0x{:X}, dlc {}, {} bytes) is none",
                          event_name(e.kind), owner_, device_, bus_name_, e.id, e.dlc, e.len));
          return;
        }
        if (e.kind == canemu_net_EV_RX) {
          stats_.frames_received += e.own ? 0 : 1;
          ev->frame_received(at, *f, e.own);
        } else if (e.kind == canemu_net_EV_TX_DONE) {
          ++stats_.frames_sent;
          ev->frame_transmitted(at, *f);
        } else if (e.kind == canemu_net_EV_DROPPED) {
          ev->transmission_dropped(at, *f);
        } else {
          ev->overrun(at, *f);
        }
        return;
      }
      case canemu_net_EV_ARB_LOST:
        ++stats_.arbitration_lost;
        ev->arbitration_lost(at, e.bit);
        return;
      case canemu_net_EV_ERROR: {
        mirror_.confinement().set_counters(e.tec, e.rec);
        BusErrorEvent b;
        b.at = at;
        b.type = static_cast<CanErrorType>(std::min<uint8_t>(e.error_type, 4));
        b.role = e.role == 0 ? ErrorRole::transmitter : ErrorRole::receiver;
        b.bit = e.bit;
        b.destuffed_bit = e.destuffed_bit;
        b.field = static_cast<Field>(std::min<uint8_t>(e.field, static_cast<uint8_t>(Field::eof)));
        b.extended_frame = e.extended_frame;
        b.in_frame = e.in_frame;
        b.data_phase = e.data_phase;
        b.tec = e.tec;
        b.rec = e.rec;
        ++(b.role == ErrorRole::transmitter ? stats_.errors_as_transmitter
                                            : stats_.errors_as_receiver)[b.type];
        ev->bus_error(b);
        return;
      }
      case canemu_net_EV_STATE:
        mirror_.confinement().set_counters(e.tec, e.rec);
        ev->state_changed(at, static_cast<ErrorState>(std::min<uint8_t>(e.state, 3)), e.tec, e.rec);
        return;
      case canemu_net_EV_REFUSED:
        log::warning("node {} of bus {} (owner {}): {}", device_, bus_name_, owner_,
                     printable(get(e.text)));
        owner_lost();
        return;
      default:
        return;
    }
  }

 private:
  void program(const HostedNodeSettings& settings) override {
    stats_ = NodeStats{};  // a node configured afresh starts counting afresh, as a local one
    settings_ = settings;
    programmed_ = true;
    online_ = false;
    reported_off_ = false;
    mirror_.confinement().reset();
    send_open();
  }
  void go_on_bus(const HostedNodeSettings&) override {
    online_ = true;
    request(canemu_net_REQ_ONLINE);  // without the owner (yet): frames wait for replay()
  }
  void go_off_bus() override {
    online_ = false;
    request(canemu_net_REQ_OFFLINE);
  }
  void leave_bus_off(const HostedNodeSettings&) override { request(canemu_net_REQ_RESTART); }
  bool buffer_free() override { return usable(); }
  bool usable() const { return link_ != nullptr && link_->usable(link_->sim.bus_config(bus_)); }
  void load(const TxFrame& tx) override {
    canemu_net_Request r{};
    r.kind = canemu_net_REQ_TX;
    r.single_shot = tx.single_shot;
    r.self_reception = tx.self_reception;
    put_frame_fields(r, tx.frame);
    send(r);
  }
  void abort_tx() override {}
  void release_received() override {}
  void released() override {
    if (programmed_) {
      request(canemu_net_REQ_CLOSE);  // the owner gives its node back
    }
    programmed_ = false;
    online_ = false;
    reported_off_ = false;
  }
  uint32_t tx_window() const override { return kTxWindow; }
  bool restarts_itself() const override { return true; }

  void send_open() {
    canemu_net_Request r{};
    r.kind = canemu_net_REQ_OPEN;
    r.fd = fd_ && settings_.fd;
    r.listen_only = settings_.listen_only;
    r.btr0 = settings_.btr0;
    r.btr1 = settings_.btr1;
    if (!r.fd && settings_.nominal.clock_hz == 0) {
      // An SJA1000 programmed by its registers alone (a VCI line's BTR0/BTR1): the timing they
      // give, which the owner checks.
      if (auto t = sja1000::decode_btr(settings_.btr0, settings_.btr1)) {
        settings_.nominal = *t;
      }
    }
    r.clock_hz = settings_.nominal.clock_hz;
    r.n_prescaler = settings_.nominal.prescaler;
    r.n_tseg1 = settings_.nominal.tseg1;
    r.n_tseg2 = settings_.nominal.tseg2;
    r.n_sjw = settings_.nominal.sjw;
    r.d_prescaler = settings_.data.prescaler;
    r.d_tseg1 = settings_.data.tseg1;
    r.d_tseg2 = settings_.data.tseg2;
    r.d_sjw = settings_.data.sjw;
    r.restart_ns = settings_.restart_delay.ns();
    if (auto seq = send(r)) {
      opened_ = *seq;
    }
  }
  // Online, offline, restart, name, close: for a node the owner has opened (a driver that
  // stops a line it has closed already asks nothing of the owner).
  void request(uint8_t kind) {
    if (!programmed_) {
      return;
    }
    canemu_net_Request r{};
    r.kind = kind;
    send(r);
  }
  std::optional<uint64_t> send(canemu_net_Request& r) {
    if (!usable()) {
      return std::nullopt;  // replay() sends what matters once the owner answers
    }
    r.node = number_;
    put(r.bus, bus_name_);
    put(r.device, device_);
    if (!link_->send_request(owner_, r)) {
      return std::nullopt;
    }
    return r.seq;
  }

  Distributed::Impl* link_;
  uint32_t number_;
  std::size_t bus_;
  std::string bus_name_;
  std::string owner_;
  bool fd_;
  std::string device_;
  MirrorController mirror_;
  NodeId id_;
  HostedNodeSettings settings_;
  bool programmed_ = false;
  bool online_ = false;
  bool reported_off_ = false;  // owner_lost() told the driver the node is off the bus
  uint64_t opened_ = 0;
  NodeStats stats_;
};

}  // namespace canemu::daemon
