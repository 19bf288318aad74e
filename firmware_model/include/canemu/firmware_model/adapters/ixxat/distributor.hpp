// The channels of a VCI controller and the firmware's distributor between them
// (VCI C++ guide 5.2.2, 7.6.5-7.6.6; decisions in docs/vci.md): opening (exclusive or
// shared), initialization with the channel's FIFOs and, on v2 channels, its own filters and
// SRRA; activation; every message for the channels (event messages to all, received frames
// through each v2 channel's filter, self-reception echoes by the rules of v1 and v2 channels);
// and, for transmission, the next message from the channels' transmit FIFOs: high-priority
// messages first, the channels in turn.
#pragma once

#include <cstdint>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/firmware_model/adapters/ixxat/filter.hpp"
#include "canemu/firmware_model/bus/frame.hpp"
#include "vci/cantype.h"
#include "vci/vcierr.h"

namespace canemu::model::ixxat {

// A channel's FIFOs as the firmware sees them.
class ChannelPort {
 public:
  virtual ~ChannelPort() = default;
  // Stores a message in the receive FIFO; false when it is full (the message is then lost).
  virtual bool put(const CANMSG2& msg) = 0;
  // The message at the head of the transmit FIFO, left in place; nothing when it is empty or
  // the channel has no transmit FIFO.
  virtual std::optional<CANMSG2> peek() = 0;
  virtual void pop() = 0;
  // The firmware stopped reading with messages left (it took its share of this round): the
  // port must make sure it is asked again, after its host has served the others.
  virtual void defer() {}
};

using ChannelId = uint32_t;

struct ChannelSetup {
  uint32_t ext_list_size = 0;             // v2: 29-bit ID list size (0: no list)
  uint8_t filter_mode = CAN_FILTER_PASS;  // v2: both filters' mode, optionally | CAN_FILTER_SRRA
};

struct ChannelCounters {
  uint64_t received = 0;   // messages stored in the receive FIFO
  uint64_t lost = 0;       // messages the receive FIFO had no room for
  uint64_t sent = 0;       // frames of this channel that went out
  uint64_t rejected = 0;   // transmit FIFO entries that were not frames the line can send
  uint64_t dropped = 0;    // single-shot frames given up
  uint64_t not_shown = 0;  // v1 channels: CAN FD frames with more than 8 bytes
};

struct ChannelStatus {
  bool initialized = false;
  bool activated = false;
  bool rx_overrun = false;  // sticky until the channel is initialized again
  ChannelCounters counters;
};

class Distributor {
 public:
  // --- the channels ---
  // VCI_E_ACCESSDENIED next to an exclusive channel, or for an exclusive one next to others.
  tl::expected<ChannelId, HRESULT> open(bool exclusive, bool v2);
  void close(ChannelId id);
  bool empty() const { return channels_.empty(); }
  // The channel's FIFOs are `port` (not owned; valid until the channel is closed or
  // initialized again); counters and overrun cleared. Only while inactive.
  HRESULT init(ChannelId id, const ChannelSetup& setup, ChannelPort* port);
  HRESULT activate(ChannelId id);
  HRESULT deactivate(ChannelId id);
  std::optional<ChannelStatus> status(ChannelId id) const;
  // A v2 channel's filters and whether the channel is active, for a filter call; the error
  // for an unknown (VCI_E_INVALID_HANDLE), v1 (VCI_E_NOT_IMPLEMENTED) or uninitialized
  // (VCI_E_NOT_INITIALIZED) channel.
  tl::expected<std::pair<FilterPair*, bool>, HRESULT> filters(ChannelId id);

  // --- to the channels ---
  // To every active channel (INFO, STATUS, ERROR, TIMEOVR messages). A receive FIFO without
  // room loses the message: counted, the channel's overrun set, the next stored message
  // marked ovr.
  void broadcast(const CANMSG2& msg);
  // A received data frame the control unit's filter passed, as `msg`: to every active channel
  // whose own filter passes it; the last stage that filters sets afc.
  void distribute(const Frame& frame, const CANMSG2& msg);
  // Self reception of `frame`, sent from channel `from` (nothing: the cyclic list), as `echo`
  // (srr set): every v1 channel and the sender get it as it is; other v2 channels with SRRA
  // through their filter, srr cleared unless the frame is the cyclic list's.
  void echo(const Frame& frame, const CANMSG2& echo, std::optional<ChannelId> from);

  // --- from the channels ---
  // The next message to send and its channel: high-priority messages first, then any, the
  // channels in turn after the one that sent last. `convert` makes of a message what the line
  // sends (a std::optional); messages it refuses (nothing) are taken from their FIFO and
  // counted as rejected. A high-priority message never overtakes the messages ahead of it in
  // its FIFO. One pass over the channels: each FIFO's head is looked at and converted once.
  // At most kRejectBudget refused messages are taken from one FIFO per call: a channel that
  // fills its FIFO with messages the line cannot send as fast as they are taken is deferred
  // (ChannelPort::defer) instead of holding the firmware.
  template <class T>
  struct Taken {
    CANMSG2 msg;
    ChannelId channel;
    T converted;
  };
  template <class Convert>
  auto take_converted(Convert&& convert)
      -> std::optional<Taken<typename std::invoke_result_t<Convert&, const CANMSG2&>::value_type>>;
  static constexpr uint32_t kRejectBudget = 1024;
  void count_sent(ChannelId id);
  void count_dropped(ChannelId id);

 private:
  struct Channel {
    ChannelId id = 0;
    bool v2 = false;
    bool initialized = false;
    bool active = false;
    bool srra = false;
    bool overrun = false;       // fRxOverrun
    bool lost_pending = false;  // the next stored message gets ovr
    ChannelPort* port = nullptr;
    std::optional<FilterPair> filters;  // v2
    ChannelCounters counters;
  };

  Channel* find(ChannelId id);
  const Channel* find(ChannelId id) const;
  void deliver(Channel& c, const CANMSG2& msg);
  // `msg` (a data frame's) through a v2 channel's own filter to the channel, unless it blocks;
  // afc set unless the filter passes everything.
  void deliver_filtered(Channel& c, const Frame& frame, const CANMSG2& msg);
  std::vector<Channel> channels_;
  ChannelId next_id_ = 1;
  bool exclusive_ = false;
  std::size_t rr_next_ = 0;  // the channel to look at first
};

template <class Convert>
auto Distributor::take_converted(Convert&& convert)
    -> std::optional<Taken<typename std::invoke_result_t<Convert&, const CANMSG2&>::value_type>> {
  using T = typename std::invoke_result_t<Convert&, const CANMSG2&>::value_type;
  const std::size_t n = channels_.size();
  // The first sendable head in turn, unless one of high priority comes after it.
  std::optional<Taken<T>> first;
  std::size_t first_index = 0;
  bool urgent = false;
  for (std::size_t k = 0; k < n && !urgent; ++k) {
    const std::size_t i = (rr_next_ + k) % n;
    Channel& c = channels_[i];
    if (!c.active || c.port == nullptr) {
      continue;
    }
    uint32_t rejected = 0;
    while (std::optional<CANMSG2> m = c.port->peek()) {
      std::optional<T> t = convert(*m);
      if (!t) {
        c.port->pop();
        ++c.counters.rejected;  // not a frame this line can send: dropped, counted
        if (++rejected == kRejectBudget) {
          c.port->defer();
          break;
        }
        continue;
      }
      urgent = m->uMsgInfo.Bits.hpm != 0;
      if (!first || urgent) {
        first.emplace(Taken<T>{*m, c.id, std::move(*t)});
        first_index = i;
      }
      break;
    }
  }
  if (first) {
    channels_[first_index].port->pop();
    rr_next_ = (first_index + 1) % n;
  }
  return first;
}

}  // namespace canemu::model::ixxat
