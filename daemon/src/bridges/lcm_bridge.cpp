#include "canemu/daemon/bridges/lcm_bridge.hpp"

#include <cctype>
#include <cstring>

#include <fmt/format.h>

#include "canemu/firmware_model/bus/frame.hpp"

#ifdef CANEMU_HAVE_LCM
#include <lcm/lcm.h>

#include "canemu_lcm_error_t.h"
#include "canemu_lcm_frame_t.h"
#include "canemu_lcm_state_t.h"
#endif

namespace canemu::daemon {

using namespace canemu::model;

#ifdef CANEMU_HAVE_LCM

namespace {

class LcmTransport final : public BridgeTransport {
 public:
  LcmTransport(std::string bus, lcm_t* lcm, const std::string& prefix)
      : bus_(std::move(bus)),
        lcm_(lcm),
        frames_(prefix + "FRAMES"),
        errors_(prefix + "ERRORS"),
        states_(prefix + "STATES"),
        tx_(prefix + "TX") {}
  ~LcmTransport() override {
    if (subscription_ != nullptr) {
      lcm_unsubscribe(lcm_, subscription_);
    }
    lcm_destroy(lcm_);
  }
  LcmTransport(const LcmTransport&) = delete;
  LcmTransport& operator=(const LcmTransport&) = delete;

  bool subscribe() {
    // The channel is a regular expression: every character but letters and digits escaped.
    std::string regex;
    for (char ch : tx_) {
      if (!std::isalnum(static_cast<unsigned char>(ch))) {
        regex += '\\';
      }
      regex += ch;
    }
    subscription_ = lcm_subscribe(lcm_, regex.c_str(), &LcmTransport::on_tx, this);
    return subscription_ != nullptr;
  }

  lcm_t* lcm() { return lcm_; }
  int fd() const override { return lcm_get_fileno(lcm_); }
  std::string name() const override { return "LCM bridge of " + bus_; }

  void receive(Bridge& bridge) override {
    receiving_ = &bridge;
    for (int i = 0; i < kMaxHandlesPerKick; ++i) {
      if (lcm_handle_timeout(lcm_, 0) <= 0) {
        break;  // nothing more (0), or the instance failed (< 0): nothing to read
      }
    }
    receiving_ = nullptr;
  }

  bool carries_own_frames() const override { return true; }

  Delivery frame(SimTime at, const Frame& frame, bool own) override {
    canemu_lcm_frame_t m{};
    m.timestamp_ns = at.ns();
    m.id = static_cast<int32_t>(frame.id());
    m.extended = frame.extended() ? 1 : 0;
    m.remote = frame.remote() ? 1 : 0;
    m.fd = frame.fd() ? 1 : 0;
    m.brs = frame.brs() ? 1 : 0;
    m.esi = frame.esi() ? 1 : 0;
    m.dlc = static_cast<int8_t>(frame.dlc());
    m.len = static_cast<int8_t>(frame.length());
    std::memcpy(m.data, frame.data().data(), frame.length());
    m.from_tx = own ? 1 : 0;
    return delivered(canemu_lcm_frame_t_publish(lcm_, frames_.c_str(), &m));
  }

  Delivery error(const BusErrorEvent& e, ErrorState state) override {
    const std::string field(to_string(e.field));
    canemu_lcm_error_t m{};
    m.timestamp_ns = e.at.ns();
    m.type = static_cast<int8_t>(e.type);
    m.role = static_cast<int8_t>(e.role);
    m.bit = static_cast<int16_t>(e.bit);
    m.destuffed_bit = static_cast<int16_t>(e.destuffed_bit);
    m.field = const_cast<char*>(field.c_str());
    m.in_frame = e.in_frame ? 1 : 0;
    m.state = static_cast<int8_t>(state);
    m.tec = static_cast<int16_t>(e.tec);
    m.rec = static_cast<int16_t>(e.rec);
    return delivered(canemu_lcm_error_t_publish(lcm_, errors_.c_str(), &m));
  }

  Delivery state(SimTime at, ErrorState state, uint16_t tec, uint16_t rec) override {
    return publish_state(at, state, tec, rec, false);
  }

  Delivery restarted(SimTime at, uint16_t tec, uint16_t rec) override {
    return publish_state(at, ErrorState::bus_off, tec, rec, true);
  }

 private:
  static Delivery delivered(int status) { return status == 0 ? Delivery::sent : Delivery::refused; }

  Delivery publish_state(SimTime at, ErrorState state, uint16_t tec, uint16_t rec, bool restarted) {
    canemu_lcm_state_t m{};
    m.timestamp_ns = at.ns();
    m.state = static_cast<int8_t>(state);
    m.tec = static_cast<int16_t>(tec);
    m.rec = static_cast<int16_t>(rec);
    m.restarted = restarted ? 1 : 0;
    return delivered(canemu_lcm_state_t_publish(lcm_, states_.c_str(), &m));
  }

  static void on_tx(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
    auto* self = static_cast<LcmTransport*>(user);
    if (self->receiving_ == nullptr) {
      return;
    }
    Bridge& bridge = *self->receiving_;
    canemu_lcm_frame_t f{};
    if (!decode(rbuf->data, rbuf->data_size, f)) {
      bridge.reject(BridgeReject::not_a_frame,
                    fmt::format("rejected a message on {} that is no canemu_lcm.frame_t ({} bytes)",
                                channel, rbuf->data_size));
      return;
    }
    const auto m =
        frame_message({f.id, f.extended != 0, f.remote != 0, f.fd != 0, f.brs != 0, f.esi != 0,
                       f.dlc, f.len, reinterpret_cast<const uint8_t*>(f.data)});
    if (!m) {
      bridge.reject(BridgeReject::bad_fields,
                    fmt::format("rejected a frame_t on {}: {}", channel, m.error().text));
      return;
    }
    bridge.offer(&*m);
  }

  // A frame_t in `data`, all of it; false if the bytes are none.
  static bool decode(const void* data, uint32_t size, canemu_lcm_frame_t& f) {
    if (size > static_cast<uint32_t>(INT32_MAX)) {
      return false;
    }
    const int used = canemu_lcm_frame_t_decode(data, 0, static_cast<int>(size), &f);
    if (used < 0) {
      return false;
    }
    canemu_lcm_frame_t_decode_cleanup(
        &f);  // frees nothing: the type has no arrays of variable size
    return static_cast<uint32_t>(used) == size;
  }

  static constexpr int kMaxHandlesPerKick = 256;
  std::string bus_;
  lcm_t* lcm_;
  std::string frames_, errors_, states_, tx_;
  lcm_subscription_t* subscription_ = nullptr;
  Bridge* receiving_ = nullptr;
};

}  // namespace

bool lcm_available() {
  return true;
}

Result<std::unique_ptr<BridgeTransport>> open_lcm(const std::string& bus, const std::string& url,
                                                  const std::string& prefix) {
  lcm_t* lcm = lcm_create(url.c_str());
  if (lcm == nullptr) {
    return fail(Errc::io, "LCM cannot open \"" + url + "\"" +
                              (url.starts_with("udpm://")
                                   ? " (UDP multicast needs a multicast route, even on one host: "
                                     "docs/bridges.md)"
                                   : ""));
  }
  auto t = std::make_unique<LcmTransport>(bus, lcm, prefix);
  if (!t->subscribe()) {
    return fail(Errc::io, "LCM on \"" + url + "\" cannot subscribe to " + prefix + "TX");
  }
  if (t->fd() < 0) {
    return fail(Errc::io, "LCM on \"" + url + "\" has no descriptor to wait on");
  }
  return t;
}

_lcm_t* lcm_instance(BridgeTransport& transport) {
  auto* t = dynamic_cast<LcmTransport*>(&transport);
  return t != nullptr ? t->lcm() : nullptr;
}

#else

bool lcm_available() {
  return false;
}

Result<std::unique_ptr<BridgeTransport>> open_lcm(const std::string&, const std::string&,
                                                  const std::string&) {
  return fail(Errc::unavailable, "canemud was built without LCM (liblcm-dev, lcm-gen)");
}

_lcm_t* lcm_instance(BridgeTransport&) {
  return nullptr;
}

#endif

}  // namespace canemu::daemon
