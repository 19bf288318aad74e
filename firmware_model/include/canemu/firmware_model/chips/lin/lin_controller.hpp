// A LIN controller as an adapter carries it: commander (master) or responder (slave), a
// response table of 64 entries, one transmit buffer, on or off the bus. The adapter firmware
// (adapters/ixxat, the VCI's ILinControl) drives it and turns what it sees into messages.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "canemu/firmware_model/bus/lin_bus.hpp"

namespace canemu::model::lin {

class LinController final : public LinNode {
 public:
  enum class Mode : uint8_t { slave, master };
  enum class SendResult : uint8_t { ok, busy, offline, not_master };

  class Listener {
   public:
    // What the bus showed while the controller was online. `own_response`: this controller's
    // response table (or its own publishing) sent the response of this frame.
    virtual void on_lin(const Event& e, bool own_response) = 0;

   protected:
    ~Listener() = default;
  };

  // The length of the wake-up pulse the controller sends: LIN 2.x's shortest (250 us to 5 ms).
  static constexpr SimDuration kWakeupPulse = microseconds(250);

  explicit LinController(LinBus& bus);
  ~LinController() override;
  LinController(const LinController&) = delete;
  LinController& operator=(const LinController&) = delete;

  void set_listener(Listener* listener) { listener_ = listener; }

  // Mode and bit rate (0: detected from the sync byte of the next header). Offline.
  void configure(Mode mode, uint32_t bitrate);
  // Offline, the response table empty, a request not yet on the wire dropped.
  void reset();
  void start();
  // Offline; a frame on the wire ends as it is.
  void stop();

  bool online() const { return online_; }
  Mode mode() const { return mode_; }
  // The configured bit rate, or the one detected (0 until a header came).
  uint32_t bitrate() const { return bitrate_ != 0 ? bitrate_ : detected_; }
  bool tx_pending() const { return bus_.pending(id_); }

  void set_response(uint8_t id, const Response& response);
  void clear_responses() { table_.fill(std::nullopt); }
  const std::optional<Response>& response(uint8_t id) const { return table_[id & kMaxId]; }

  SendResult send_header(uint8_t id);
  SendResult send_frame(uint8_t id, const Response& response);
  SendResult send_sleep();
  SendResult send_wakeup();

  LinNodeId node() const { return id_; }

  // LinNode
  std::optional<Response> respond(uint8_t id) override;
  void on_lin_event(const Event& e) override;
  uint32_t lin_bitrate() const override { return online_ ? bitrate_ : 0; }

 private:
  SendResult check(bool master_only) const;

  LinBus& bus_;
  LinNodeId id_;
  Listener* listener_ = nullptr;
  Mode mode_ = Mode::slave;
  uint32_t bitrate_ = 0;
  uint32_t detected_ = 0;
  bool online_ = false;
  std::array<std::optional<Response>, kMaxId + 1> table_{};
};

}  // namespace canemu::model::lin
