#include "canemu/daemon/bridges/dds_bridge.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>

#include <fmt/format.h>

#include "canemu/firmware_model/bus/frame.hpp"

#ifdef CANEMU_HAVE_DDS
#include <sys/eventfd.h>
#include <unistd.h>

#include <dds/dds.h>

#include "canemu_dds.h"
#include "dds_frame_fields.hpp"
#include "dds_log.hpp"
#include "ros2_can_msgs.h"
#endif

namespace canemu::daemon {

using namespace canemu::model;

std::string dds_locator(const DdsOptions& o) {
  return fmt::format("{}/{}{}", o.domain, o.partition, o.ros2 ? "+ros2" : "");
}

std::optional<DdsOptions> parse_dds_locator(std::string_view locator) {
  DdsOptions o;
  const auto slash = locator.find('/');
  if (slash == std::string_view::npos) {
    return std::nullopt;
  }
  const std::string_view domain = locator.substr(0, slash);
  std::string_view partition = locator.substr(slash + 1);
  if (partition.ends_with("+ros2")) {
    o.ros2 = true;
    partition.remove_suffix(5);
  }
  int64_t id = -1;
  const auto [end, ec] = std::from_chars(domain.data(), domain.data() + domain.size(), id);
  if (ec != std::errc{} || end != domain.data() + domain.size() || dds_domain_problem(id) ||
      dds_partition_problem(partition)) {
    return std::nullopt;
  }
  o.domain = static_cast<uint32_t>(id);
  o.partition = std::string(partition);
  return o;
}

#ifdef CANEMU_HAVE_DDS

namespace {

// A frame as canemu's own type and back.
canemu_dds_Frame to_dds(SimTime at, const Frame& frame, bool own) {
  canemu_dds_Frame m{};
  m.timestamp_ns = at.ns();
  put_frame_fields(m, frame);
  m.from_tx = own;
  return m;
}

// A sample of `topic` for the bridge to send: offered, or rejected with the reason.
void offer_sample(const canemu_dds_Frame& f, Bridge& bridge, const std::string& topic) {
  const auto m =
      frame_message({f.id, f.extended, f.remote, f.fd, f.brs, f.esi, f.dlc, f.len, f.data});
  if (!m) {
    bridge.reject(BridgeReject::bad_fields,
                  fmt::format("rejected a Frame on {}: {}", topic, m.error().text));
    return;
  }
  bridge.offer(&*m);
}

// ROS 2's can_msgs/msg/Frame (classic frames only: 8 data bytes). An error frame or a dlc above
// 8 is no frame to send.
void offer_sample(const can_msgs_msg_dds__Frame_& f, Bridge& bridge, const std::string& topic) {
  if (f.is_error) {
    bridge.reject(BridgeReject::error_frame,
                  fmt::format("rejected a Frame with is_error on {}: error frames are the "
                              "bus's, not sent",
                              topic));
    return;
  }
  if (f.dlc > 8) {
    bridge.reject(BridgeReject::bad_fields,
                  fmt::format("rejected a Frame on {}: dlc {} is above 8 (can_msgs carries "
                              "classic frames)",
                              topic, f.dlc));
    return;
  }
  ipc::ChannelMessage m;
  m.kind = static_cast<uint8_t>(ipc::ChannelMessageKind::frame);
  m.id = f.id;
  m.dlc = f.dlc;
  m.flags = static_cast<uint8_t>((f.is_extended ? ipc::kMsgExtended : 0) |
                                 (f.is_rtr ? ipc::kMsgRemote : 0));
  if (!f.is_rtr) {
    std::memcpy(m.data, f.data, f.dlc);
  }
  bridge.offer(&m);
}

class DdsTransport final : public BridgeTransport {
 public:
  DdsTransport(std::string bus, DdsOptions options)
      : bus_(std::move(bus)), options_(std::move(options)) {}
  ~DdsTransport() override {
    undecodable_.clear();  // Cyclone's log no longer reaches this bridge
    if (participant_ > 0) {
      dds_delete(participant_);  // and everything in it; waits for running listeners
    }
    if (wake_ >= 0) {
      ::close(wake_);
    }
  }
  DdsTransport(const DdsTransport&) = delete;
  DdsTransport& operator=(const DdsTransport&) = delete;

  // Opens the participant, the topics and their readers and writers; what failed, if anything.
  Result<> open() {
    wake_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (wake_ < 0) {
      return fail(Errc::io, fmt::format("eventfd: {}", std::strerror(errno)));
    }
    participant_ = dds_create_participant(options_.domain, nullptr, nullptr);
    if (participant_ < 0) {
      return fail(
          Errc::io,
          fmt::format("Cyclone DDS cannot join domain {}: {} (CYCLONEDDS_URI: {})", options_.domain,
                      dds_strretcode(participant_),
                      std::getenv("CYCLONEDDS_URI") ? std::getenv("CYCLONEDDS_URI") : "unset"));
    }
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, 0);
    dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
    dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, static_cast<int32_t>(kDdsDepth));
    dds_qos_t* ours = dds_create_qos();
    dds_copy_qos(ours, qos);
    dds_qset_partition1(ours, options_.partition.c_str());
    // Readers keep all, up to what a bridge queues: a writer that outruns canemud is held back
    // by reliable flow control (its write waits up to its max_blocking_time, then fails where
    // the writer sees it) instead of losing samples unseen.
    dds_qos_t* inbound = dds_create_qos();
    dds_copy_qos(inbound, qos);
    dds_qset_history(inbound, DDS_HISTORY_KEEP_ALL, 0);
    dds_qset_resource_limits(inbound, static_cast<int32_t>(kDdsReaderSamples), DDS_LENGTH_UNLIMITED,
                             DDS_LENGTH_UNLIMITED);
    dds_listener_t* listener = dds_create_listener(this);
    dds_lset_data_available(listener, &DdsTransport::on_data);

    const std::string& p = options_.topic_prefix;
    const dds_entity_t publisher = dds_create_publisher(participant_, ours, nullptr);
    const dds_entity_t subscriber = dds_create_subscriber(participant_, ours, nullptr);
    frames_ = writer(publisher, &canemu_dds_Frame_desc, p + "frames", qos);
    errors_ = writer(publisher, &canemu_dds_BusError_desc, p + "errors", qos);
    states_ = writer(publisher, &canemu_dds_NodeState_desc, p + "states", qos);
    tx_topic_ = p + "tx";
    tx_ = reader(subscriber, &canemu_dds_Frame_desc, tx_topic_, inbound, listener);
    watch_undecodable(tx_topic_);
    bool ok =
        publisher > 0 && subscriber > 0 && frames_ > 0 && errors_ > 0 && states_ > 0 && tx_ > 0;
    if (ok && options_.ros2) {
      const std::string base = "rt/" + bus_ + "/";
      ros_from_ = writer(participant_, &can_msgs_msg_dds__Frame__desc, base + "from_can_bus", qos);
      ros_to_topic_ = base + "to_can_bus";
      ros_to_ =
          reader(participant_, &can_msgs_msg_dds__Frame__desc, ros_to_topic_, inbound, listener);
      watch_undecodable(ros_to_topic_);
      ok = ros_from_ > 0 && ros_to_ > 0;
    }
    dds_delete_listener(listener);
    dds_delete_qos(inbound);
    dds_delete_qos(ours);
    dds_delete_qos(qos);
    if (!ok) {
      return fail(Errc::io,
                  fmt::format("Cyclone DDS cannot make the topics {}* of {} in domain {}: {}", p,
                              bus_, options_.domain, dds_strretcode(failure_)));
    }
    return {};
  }

  int fd() const override { return wake_; }
  std::string name() const override { return "DDS bridge of " + bus_; }

  void receive(Bridge& bridge) override {
    uint64_t rung = 0;
    [[maybe_unused]] const auto n = ::read(wake_, &rung, sizeof rung);
    // Samples Cyclone could not decode never reach a reader: its log says so (dds_log.hpp),
    // and they are counted here, as what is no frame.
    for (auto& [topic, counter] : undecodable_) {
      if (const uint64_t lost = counter->take(); lost > 0) {
        bridge.reject(BridgeReject::not_a_frame,
                      fmt::format("rejected {} sample{} on {} that Cyclone DDS could not decode "
                                  "(another type of the same name?)",
                                  lost, lost == 1 ? "" : "s", topic),
                      lost);
      }
    }
    // Both readers are served on every turn, whatever the first one had.
    const bool more_frames = take<canemu_dds_Frame>(tx_, bridge, tx_topic_);
    const bool more_ros = take<can_msgs_msg_dds__Frame_>(ros_to_, bridge, ros_to_topic_);
    const bool more = more_frames || more_ros;
    if (more) {
      ring();  // the rest on the loop's next turn
    }
  }

  bool carries_own_frames() const override { return true; }

  Delivery frame(SimTime at, const Frame& frame, bool own) override {
    const canemu_dds_Frame m = to_dds(at, frame, own);
    Delivery d = delivered(dds_write(frames_, &m));
    if (ros_from_ > 0 && !frame.fd()) {
      can_msgs_msg_dds__Frame_ r{};
      r.header.stamp.sec = static_cast<int32_t>(at.ns() / 1'000'000'000);
      r.header.stamp.nanosec = static_cast<uint32_t>(at.ns() % 1'000'000'000);
      r.header.frame_id = const_cast<char*>(bus_.c_str());
      r.id = frame.id();
      r.is_rtr = frame.remote();
      r.is_extended = frame.extended();
      r.is_error = false;
      // As SocketCAN's len: the data bytes, or a remote frame's requested length.
      r.dlc = static_cast<uint8_t>(frame.remote() ? std::min<unsigned>(frame.dlc(), 8)
                                                  : frame.length());
      std::memcpy(r.data, frame.data().data(), frame.length());
      if (delivered(dds_write(ros_from_, &r)) == Delivery::refused) {
        d = Delivery::refused;
      }
    }
    return d;
  }

  Delivery error(const BusErrorEvent& e, ErrorState state) override {
    canemu_dds_BusError m{};
    m.timestamp_ns = e.at.ns();
    m.type = static_cast<uint8_t>(e.type);
    m.role = static_cast<uint8_t>(e.role);
    m.bit = static_cast<uint16_t>(e.bit);
    m.destuffed_bit = static_cast<uint16_t>(e.destuffed_bit);
    const std::string_view field = to_string(e.field);
    std::memcpy(m.field, field.data(), std::min(field.size(), sizeof m.field - 1));
    m.in_frame = e.in_frame;
    m.state = static_cast<uint8_t>(state);
    m.tec = static_cast<uint16_t>(e.tec);
    m.rec = static_cast<uint16_t>(e.rec);
    return delivered(dds_write(errors_, &m));
  }

  Delivery state(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) override {
    return publish_state(at, state, tec, rec, false);
  }

  Delivery restarted(SimTime at, uint16_t tec, uint16_t rec) override {
    return publish_state(at, ErrorState::bus_off, tec, rec, true);
  }

 private:
  static constexpr uint32_t kMaxTakesPerKick = 256;
  static constexpr uint32_t kBatch = 32;

  static Delivery delivered(dds_return_t status) {
    return status == DDS_RETCODE_OK ? Delivery::sent : Delivery::refused;
  }

  dds_entity_t writer(dds_entity_t parent, const dds_topic_descriptor_t* type,
                      const std::string& name, const dds_qos_t* qos) {
    const dds_entity_t topic = dds_create_topic(participant_, type, name.c_str(), nullptr, nullptr);
    const dds_entity_t w = topic > 0 ? dds_create_writer(parent, topic, qos, nullptr) : topic;
    if (w < 0) {
      failure_ = w;
    }
    return w;
  }

  dds_entity_t reader(dds_entity_t parent, const dds_topic_descriptor_t* type,
                      const std::string& name, const dds_qos_t* qos,
                      const dds_listener_t* listener) {
    const dds_entity_t topic = dds_create_topic(participant_, type, name.c_str(), nullptr, nullptr);
    const dds_entity_t r = topic > 0 ? dds_create_reader(parent, topic, qos, listener) : topic;
    if (r < 0) {
      failure_ = r;
    }
    return r;
  }

  // On a thread of Cyclone's: something arrived for a reader.
  static void on_data(dds_entity_t, void* self) { static_cast<DdsTransport*>(self)->ring(); }
  void ring() {
    const uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(wake_, &one, sizeof one);
  }

  // Takes up to kMaxTakesPerKick samples of `reader` (loaned from Cyclone), offering each valid
  // one; true if there may be more.
  template <typename Sample>
  bool take(dds_entity_t reader, Bridge& bridge, const std::string& topic) {
    if (reader <= 0) {
      return false;
    }
    uint32_t taken = 0;
    while (taken < kMaxTakesPerKick) {
      void* samples[kBatch] = {};
      dds_sample_info_t infos[kBatch];
      const dds_return_t n = dds_take(reader, samples, infos, kBatch, kBatch);
      if (n <= 0) {
        return false;
      }
      for (dds_return_t i = 0; i < n; ++i) {
        if (infos[i].valid_data) {
          offer_sample(*static_cast<const Sample*>(samples[i]), bridge, topic);
        }
      }
      dds_return_loan(reader, samples, n);
      taken += static_cast<uint32_t>(n);
      if (static_cast<uint32_t>(n) < kBatch) {
        return false;
      }
    }
    return true;
  }

  Delivery publish_state(SimTime at, ErrorState state, uint16_t tec, uint16_t rec, bool restarted) {
    canemu_dds_NodeState m{};
    m.timestamp_ns = at.ns();
    m.state = static_cast<uint8_t>(state);
    m.tec = tec;
    m.rec = rec;
    m.restarted = restarted;
    return delivered(dds_write(states_, &m));
  }

  void watch_undecodable(const std::string& topic) {
    undecodable_.emplace_back(
        topic, std::make_unique<UndecodableSamples>(options_.domain, topic, [this] { ring(); }));
  }

  std::string bus_;
  DdsOptions options_;
  std::string tx_topic_, ros_to_topic_;
  std::vector<std::pair<std::string, std::unique_ptr<UndecodableSamples>>> undecodable_;
  int wake_ = -1;
  dds_entity_t participant_ = 0;
  dds_entity_t frames_ = 0, errors_ = 0, states_ = 0, tx_ = 0, ros_from_ = 0, ros_to_ = 0;
  dds_return_t failure_ = DDS_RETCODE_OK;
};

}  // namespace

bool dds_available() {
  return true;
}

Result<std::unique_ptr<BridgeTransport>> open_dds(const std::string& bus,
                                                  const DdsOptions& options) {
  DdsOptions o = options;
  if (o.topic_prefix.empty()) {
    o.topic_prefix = default_dds_prefix(bus);
  }
  auto t = std::make_unique<DdsTransport>(bus, std::move(o));
  if (auto opened = t->open(); !opened) {
    return tl::unexpected(opened.error());
  }
  return t;
}

#else

bool dds_available() {
  return false;
}

Result<std::unique_ptr<BridgeTransport>> open_dds(const std::string&, const DdsOptions&) {
  return fail(Errc::unavailable, "canemud was built without DDS (cyclonedds-dev, idlc)");
}

#endif

}  // namespace canemu::daemon
