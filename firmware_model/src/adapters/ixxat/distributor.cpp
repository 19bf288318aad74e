#include "canemu/firmware_model/adapters/ixxat/distributor.hpp"

namespace canemu::model::ixxat {

namespace {

uint32_t payload_length(const CANMSG2& m) {
  const auto& b = m.uMsgInfo.Bits;
  return static_cast<uint32_t>(dlc_to_length(static_cast<uint8_t>(b.dlc), b.edl || b.fdr));
}

}  // namespace

Distributor::Channel* Distributor::find(ChannelId id) {
  for (Channel& c : channels_) {
    if (c.id == id) {
      return &c;
    }
  }
  return nullptr;
}

const Distributor::Channel* Distributor::find(ChannelId id) const {
  return const_cast<Distributor*>(this)->find(id);
}

tl::expected<ChannelId, HRESULT> Distributor::open(bool exclusive, bool v2) {
  if (exclusive_ || (exclusive && !channels_.empty())) {
    return tl::unexpected(VCI_E_ACCESSDENIED);
  }
  Channel c;
  c.id = next_id_++;
  c.v2 = v2;
  channels_.push_back(std::move(c));
  exclusive_ = exclusive;
  return channels_.back().id;
}

void Distributor::close(ChannelId id) {
  std::erase_if(channels_, [id](const Channel& c) { return c.id == id; });
  if (channels_.empty()) {
    exclusive_ = false;
  }
}

HRESULT Distributor::init(ChannelId id, const ChannelSetup& setup, ChannelPort* port) {
  Channel* c = find(id);
  if (c == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  if (c->active) {
    return VCI_E_INVALID_STATE;
  }
  if (c->v2) {
    const uint8_t mode = setup.filter_mode & static_cast<uint8_t>(~CAN_FILTER_SRRA);
    if (!valid_filter_mode(mode)) {
      return VCI_E_INVALIDARG;
    }
    c->srra = (setup.filter_mode & CAN_FILTER_SRRA) != 0;
    c->filters.emplace(FilterPair{IdFilter(false, kStdListCapacity, mode),
                                  IdFilter(true, setup.ext_list_size, mode)});
  }
  c->port = port;
  c->initialized = true;
  c->overrun = false;
  c->lost_pending = false;
  c->counters = ChannelCounters{};
  return VCI_OK;
}

HRESULT Distributor::activate(ChannelId id) {
  Channel* c = find(id);
  if (c == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  if (!c->initialized) {
    return VCI_E_NOT_INITIALIZED;
  }
  c->active = true;
  return VCI_OK;
}

HRESULT Distributor::deactivate(ChannelId id) {
  Channel* c = find(id);
  if (c == nullptr) {
    return VCI_E_INVALID_HANDLE;
  }
  c->active = false;
  return VCI_OK;
}

std::optional<ChannelStatus> Distributor::status(ChannelId id) const {
  const Channel* c = find(id);
  if (c == nullptr) {
    return std::nullopt;
  }
  return ChannelStatus{c->initialized, c->active, c->overrun, c->counters};
}

tl::expected<std::pair<FilterPair*, bool>, HRESULT> Distributor::filters(ChannelId id) {
  Channel* c = find(id);
  if (c == nullptr) {
    return tl::unexpected(VCI_E_INVALID_HANDLE);
  }
  if (!c->v2) {
    return tl::unexpected(VCI_E_NOT_IMPLEMENTED);
  }
  if (!c->filters) {
    return tl::unexpected(VCI_E_NOT_INITIALIZED);
  }
  return std::make_pair(&*c->filters, c->active);
}

void Distributor::deliver(Channel& c, const CANMSG2& msg) {
  if (!c.active || c.port == nullptr) {
    return;
  }
  if (!c.v2 && msg.uMsgInfo.Bits.type == CAN_MSGTYPE_DATA && payload_length(msg) > 8) {
    ++c.counters.not_shown;  // a CANMSG has no room for it
    return;
  }
  bool put;
  if (c.lost_pending) {
    CANMSG2 marked = msg;
    marked.uMsgInfo.Bits.ovr = 1;
    put = c.port->put(marked);
  } else {
    put = c.port->put(msg);
  }
  if (put) {
    ++c.counters.received;
    c.lost_pending = false;
  } else {
    ++c.counters.lost;
    c.overrun = true;
    c.lost_pending = true;
  }
}

void Distributor::broadcast(const CANMSG2& msg) {
  for (Channel& c : channels_) {
    deliver(c, msg);
  }
}

void Distributor::deliver_filtered(Channel& c, const Frame& frame, const CANMSG2& msg) {
  if (!c.filters) {
    deliver(c, msg);  // v1 channels have no filter of their own
    return;
  }
  const uint8_t a = c.filters->accept(frame.id(), frame.extended(), frame.remote());
  if (a == CAN_ACCEPT_REJECT) {
    return;
  }
  if (c.filters->select(frame.extended()).mode() == CAN_FILTER_PASS) {
    deliver(c, msg);
    return;
  }
  CANMSG2 copy = msg;
  copy.uMsgInfo.Bits.afc = a;  // the last stage that filters sets it
  deliver(c, copy);
}

void Distributor::distribute(const Frame& frame, const CANMSG2& msg) {
  for (Channel& c : channels_) {
    if (c.active) {
      deliver_filtered(c, frame, msg);
    }
  }
}

void Distributor::echo(const Frame& frame, const CANMSG2& echo, std::optional<ChannelId> from) {
  for (Channel& c : channels_) {
    if (!c.active) {
      continue;
    }
    if (!c.v2 || (from && c.id == *from)) {
      deliver(c, echo);
      continue;
    }
    if (!c.srra) {
      continue;
    }
    // Another channel's frame: as if it came from another controller, through the channel's
    // filter, srr cleared. The cyclic list's frames are no channel's but the line's own: they
    // keep srr, so that a program can tell them from the bus's traffic.
    CANMSG2 copy = echo;
    copy.uMsgInfo.Bits.srr = from ? 0 : 1;
    deliver_filtered(c, frame, copy);
  }
}

void Distributor::count_sent(ChannelId id) {
  if (Channel* c = find(id)) {
    ++c->counters.sent;
  }
}

void Distributor::count_dropped(ChannelId id) {
  if (Channel* c = find(id)) {
    ++c->counters.dropped;
  }
}

}  // namespace canemu::model::ixxat
