#include "canemu/daemon/vci/vci_service.hpp"
#include "canemu/daemon/base/log.hpp"

#include <cstring>

#include <fmt/format.h>

namespace canemu::daemon {

namespace ixxat = model::ixxat;

VciHandle::~VciHandle() {
  switch (kind_) {
    case Kind::control:
      line_->close_control();
      break;
    case Kind::channel:
      line_->close_channel(channel_);  // before the port goes: the line lets go of it
      break;
    case Kind::scheduler:
      line_->close_scheduler();
      break;
    case Kind::lin_control:
      lin_->close_control();
      break;
    case Kind::lin_monitor:
      lin_->close_monitor(monitor_);  // before the port goes: the line lets go of it
      break;
  }
}

std::unique_ptr<VciPort> VciHandle::replace_port(std::unique_ptr<VciPort> port, RingBudget budget) {
  std::unique_ptr<VciPort> old = std::move(port_);
  port_ = std::move(port);
  budget_ = std::move(budget);
  return old;
}

namespace {

template <class T>
T payload_as(const ipc::VciRequest& m) {
  static_assert(sizeof(T) <= ipc::kVciRequestPayloadSize);
  T t;
  std::memcpy(&t, m.payload, sizeof t);
  return t;
}

template <class T>
void put_payload(ipc::VciReply& r, std::size_t offset, const T& t) {
  std::memcpy(r.payload + offset, &t, sizeof t);
}

bool is_open(ipc::VciOp op) {
  return op == ipc::VciOp::control_open || op == ipc::VciOp::channel_open ||
         op == ipc::VciOp::scheduler_open;
}

ixxat::FilterResult filter_call(ixxat::CanLine& line, std::optional<ixxat::ChannelId> channel,
                                const ipc::VciRequest& m) {
  if (m.args[0] > static_cast<uint32_t>(ixxat::FilterOp::Kind::remove_ids)) {
    return {VCI_E_INVALIDARG, 0};
  }
  ixxat::FilterOp op;
  op.kind = static_cast<ixxat::FilterOp::Kind>(m.args[0]);
  op.select = static_cast<uint8_t>(m.args[1]);
  op.mode = static_cast<uint8_t>(m.args[2]);
  op.code = m.args[3];
  op.mask = m.args[4];
  if (m.args[1] > 0xFF || m.args[2] > 0xFF) {
    return {VCI_E_INVALIDARG, 0};
  }
  return line.filter(channel, op);
}

// The table of a control_detect request as line initializations: BTR pairs (v1) or CANBTP
// pairs (v2), listened to with both identifier widths.
HRESULT start_detection(ixxat::CanLine& line, const ipc::VciRequest& m) {
  std::vector<ixxat::LineInit> entries;
  const uint8_t both = CAN_OPMODE_STANDARD | CAN_OPMODE_EXTENDED;
  if ((m.flags & ipc::kVciV2) != 0) {
    const auto t = payload_as<CANBTPTABLE>(m);
    if (t.bCount == 0 || t.bCount > 64 || m.args[1] > 0xFF || m.args[2] > 0xFF) {
      return VCI_E_INVALIDARG;
    }
    for (uint8_t i = 0; i < t.bCount; ++i) {
      ixxat::LineInit e;
      e.v2 = true;
      e.op_mode = static_cast<uint8_t>((m.args[1] & ~CAN_OPMODE_LISTONLY) | both);
      e.ex_mode = static_cast<uint8_t>(m.args[2]);
      e.sdr = t.asBTP[i].sSdr;
      e.fdr = t.asBTP[i].sFdr;
      entries.push_back(e);
    }
  } else {
    const auto t = payload_as<CANBTRTABLE>(m);
    if (t.bCount == 0 || t.bCount > 64) {
      return VCI_E_INVALIDARG;
    }
    for (uint8_t i = 0; i < t.bCount; ++i) {
      ixxat::LineInit e;
      e.op_mode = static_cast<uint8_t>(both | (m.args[1] & CAN_OPMODE_LOWSPEED));
      e.btr0 = t.abBtr0[i];
      e.btr1 = t.abBtr1[i];
      entries.push_back(e);
    }
  }
  if (m.args[0] == 0 || m.args[0] > 0xFFFF) {
    return VCI_E_INVALIDARG;
  }
  return line.start_detection(entries, model::milliseconds(m.args[0]));
}

}  // namespace

void VciService::handle(VciSession& session, const ipc::VciRequest& m, const Send& send) {
  auto r = ipc::make_message<ipc::VciReply>(m.header.request_id);
  std::array<int, ipc::kChannelFdCount> fds{};
  bool with_fds = false;
  std::vector<int> fifo_fds;
  const auto op = static_cast<ipc::VciOp>(m.op);
  if (is_lin(op)) {
    lin(session, m, r, fds, with_fds);
  } else if (is_open(op)) {
    open(session, m, r);
  } else if (op == ipc::VciOp::fifo_create || op == ipc::VciOp::fifo_access ||
             op == ipc::VciOp::fifo_side) {
    fifos_.handle(&session, session.uid, m, r, fifo_fds);
  } else if (op == ipc::VciOp::device_create) {
    create_device(session, m, r);
  } else if (op == ipc::VciOp::device_remove) {
    // Only the client that created it; objects open on it stay usable until closed.
    r.hresult = session.devices.erase(ipc::name_of(m.device)) == 1 ? VCI_OK : VCI_E_INVALIDARG;
  } else if (op == ipc::VciOp::line_info && m.handle == 0) {
    // A socket's view (ICanSocket): no object of the controller needs to be open.
    std::shared_ptr<ixxat::CanLine> line =
        sim_.devices().vci_line(ipc::name_of(m.device), m.controller);
    r.hresult = line == nullptr ? VCI_E_INVALIDARG : VCI_OK;
    if (line != nullptr) {
      put_payload(r, ipc::kVciCapsOffset, line->capabilities());
      put_payload(r, ipc::kVciCaps2Offset, line->capabilities2());
      put_payload(r, ipc::kVciLineOffset, line->line_status());
      put_payload(r, ipc::kVciLine2Offset, line->line_status2());
    }
  } else if (auto it = session.handles.find(m.handle); it == session.handles.end()) {
    r.hresult = VCI_E_INVALID_HANDLE;
  } else if (op == ipc::VciOp::close) {
    close(session, m.handle);
    r.hresult = VCI_OK;
  } else if (it->second->is_lin()) {
    r.hresult = VCI_E_INVALID_HANDLE;  // not an operation of a LIN object
  } else {
    VciHandle& h = *it->second;
    ixxat::CanLine& line = h.line();
    r.handle = m.handle;
    r.hresult = VCI_OK;
    switch (op) {
      case ipc::VciOp::line_info:
        put_payload(r, ipc::kVciCapsOffset, line.capabilities());
        put_payload(r, ipc::kVciCaps2Offset, line.capabilities2());
        put_payload(r, ipc::kVciLineOffset, line.line_status());
        put_payload(r, ipc::kVciLine2Offset, line.line_status2());
        break;
      case ipc::VciOp::controller_state: {
        const ixxat::ControllerState s = line.controller_state();
        r.values[0] = static_cast<uint32_t>(s.state);
        r.values[1] = s.tec;
        r.values[2] = s.rec;
        r.values[3] = static_cast<uint32_t>(line.state());
        break;
      }
      default:
        if (h.kind() == VciHandle::Kind::control) {
          control(h, m, r);
        } else if (h.kind() == VciHandle::Kind::scheduler) {
          scheduler(h, m, r);
        } else if (op == ipc::VciOp::channel_init) {
          init_channel(h, m, r, fds);
          with_fds = r.hresult == VCI_OK;
        } else if (op == ipc::VciOp::channel_activate) {
          r.hresult = line.activate(h.channel());
        } else if (op == ipc::VciOp::channel_deactivate) {
          r.hresult = line.deactivate(h.channel());
        } else if (op == ipc::VciOp::channel_status) {
          const auto s = line.channel_status(h.channel());
          r.values[0] = s->initialized ? 1 : 0;
          r.values[1] = s->activated ? 1 : 0;
          r.values[2] = s->rx_overrun ? 1 : 0;
          const ipc::VciChannelCounters c{s->counters.received, s->counters.lost,
                                          s->counters.sent,     s->counters.rejected,
                                          s->counters.dropped,  s->counters.not_shown};
          put_payload(r, 0, c);
        } else if (op == ipc::VciOp::channel_filter) {
          const ixxat::FilterResult f = filter_call(line, h.channel(), m);
          r.hresult = f.hr;
          r.values[0] = f.mode;
        } else {
          r.hresult = VCI_E_INVALID_HANDLE;  // not an operation of a channel
        }
        break;
    }
  }
  if (!fifo_fds.empty()) {
    send(&r, sizeof r, std::span<const int>(fifo_fds));
    return;
  }
  send(&r, sizeof r, with_fds ? std::span<const int>(fds) : std::span<const int>());
}

void VciService::open(VciSession& session, const ipc::VciRequest& m, ipc::VciReply& r) {
  const std::string device = ipc::name_of(m.device);
  std::shared_ptr<ixxat::CanLine> line = sim_.devices().vci_line(device, m.controller);
  if (line == nullptr) {
    r.hresult = VCI_E_INVALIDARG;  // no such device or bus number
    return;
  }
  if (session.handles.size() >= kMaxVciHandlesPerClient) {
    r.hresult = VCI_E_OUTOFMEMORY;
    return;
  }
  std::unique_ptr<VciHandle> h;
  switch (static_cast<ipc::VciOp>(m.op)) {
    case ipc::VciOp::control_open:
      r.hresult = line->open_control();
      if (r.hresult == VCI_OK) {
        h = std::make_unique<VciHandle>(VciHandle::Kind::control, line, 0, false);
      }
      break;
    case ipc::VciOp::channel_open: {
      if (receivers(session) >= kMaxVciChannelsPerClient) {
        r.hresult = VCI_E_OUTOFMEMORY;
        return;
      }
      const bool v2 = (m.flags & ipc::kVciV2) != 0;
      auto id = line->open_channel((m.flags & ipc::kVciExclusive) != 0, v2);
      if (!id) {
        r.hresult = id.error();
        return;
      }
      h = std::make_unique<VciHandle>(VciHandle::Kind::channel, line, *id, v2);
      r.hresult = VCI_OK;
      break;
    }
    default:
      r.hresult = line->open_scheduler();
      if (r.hresult == VCI_OK) {
        h = std::make_unique<VciHandle>(VciHandle::Kind::scheduler, line, 0, false);
      }
      break;
  }
  if (h) {
    h->where = fmt::format("{} CAN {}", device, m.controller);
    add_handle(session, std::move(h), r);
  }
}

void VciService::add_handle(VciSession& session, std::unique_ptr<VciHandle> h, ipc::VciReply& r) {
  uint32_t id = session.next_handle++;
  while (id == 0 || session.handles.count(id) != 0) {
    id = session.next_handle++;
  }
  h->uid = session.uid;
  session.handles[id] = std::move(h);
  r.handle = id;
}

void VciService::init_channel(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r,
                              std::array<int, ipc::kChannelFdCount>& fds) {
  const uint32_t rx = m.args[0];
  const uint32_t tx = m.args[1];
  if (rx == 0 || rx > 0xFFFF || tx > 0xFFFF) {
    r.hresult = VCI_E_INVALIDARG;
    return;
  }
  ixxat::CanLine& line = h.line();
  if (line.channel_status(h.channel())->activated) {
    r.hresult = VCI_E_INVALID_STATE;
    return;
  }
  const std::size_t element = h.v2() ? sizeof(CANMSG2) : sizeof(CANMSG);
  if (const std::string why = rings_.refusal(h.uid, (std::size_t{rx} + tx) * element);
      !why.empty()) {
    log::warning("VCI channel of uid {} not initialized: {}", h.uid, why);
    r.hresult = VCI_E_OUTOFMEMORY;
    return;
  }
  auto port = VciPort::create(h.v2(), rx, tx, fmt::format("{}", h.channel()));
  if (!port) {
    r.hresult = VCI_E_OUTOFMEMORY;
    return;
  }
  (*port)->attach(&line);
  ixxat::ChannelSetup setup;
  setup.ext_list_size = m.args[2];
  setup.filter_mode = h.v2() ? static_cast<uint8_t>(m.args[3]) : CAN_FILTER_PASS;
  if (h.v2() && m.args[3] > 0xFF) {
    r.hresult = VCI_E_INVALIDARG;
    return;
  }
  r.hresult = line.init_channel(h.channel(), setup, port->get());
  if (r.hresult != VCI_OK) {
    return;
  }
  VciPort& fresh = **port;
  RingBudget budget = rings_.take(h.uid, fresh.bytes());
  std::unique_ptr<VciPort> old = h.replace_port(std::move(*port), std::move(budget));
  if (old) {
    bells_.unwatch(*old);
  }
  bells_.watch(fresh);
  r.values[0] = fresh.rx_capacity();
  r.values[1] = tx == 0 ? 0 : fresh.tx_capacity();
  r.values[2] = fresh.element_size();
  fds = fresh.client_fds();
}

void VciService::control(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r) {
  ixxat::CanLine& line = h.line();
  switch (static_cast<ipc::VciOp>(m.op)) {
    case ipc::VciOp::control_init: {
      ixxat::LineInit init;
      if ((m.flags & ipc::kVciV2) != 0) {
        const auto p = payload_as<CANINITLINE2>(m);
        init.v2 = true;
        init.op_mode = p.bOpMode;
        init.ex_mode = p.bExMode;
        init.sf_mode = p.bSFMode;
        init.ef_mode = p.bEFMode;
        init.sf_ids = p.dwSFIds;
        init.ef_ids = p.dwEFIds;
        init.sdr = p.sBtpSdr;
        init.fdr = p.sBtpFdr;
      } else {
        const auto p = payload_as<CANINITLINE>(m);
        init.op_mode = p.bOpMode;
        init.btr0 = p.bBtReg0;
        init.btr1 = p.bBtReg1;
      }
      r.hresult = line.init_line(init);
      if (r.hresult == VCI_OK) {
        // A bit/s timing the controller could not take as it was: what it took instead.
        for (const std::string& text : ixxat::timing_conversions(init, line.fd_controller())) {
          log::notice("VCI {}: {}", h.where, text);
        }
      } else if (auto why = ixxat::timing_error(init, line.fd_controller())) {
        log::warning("VCI {}: InitLine refused (VCI_E_INVALIDARG): {}", h.where, *why);
      }
      break;
    }
    case ipc::VciOp::control_reset:
      r.hresult = line.reset_line();
      break;
    case ipc::VciOp::control_start:
      r.hresult = line.start_line();
      break;
    case ipc::VciOp::control_stop:
      r.hresult = line.stop_line();
      break;
    case ipc::VciOp::control_filter: {
      const ixxat::FilterResult f = filter_call(line, std::nullopt, m);
      r.hresult = f.hr;
      r.values[0] = f.mode;
      break;
    }
    case ipc::VciOp::control_detect:
      r.hresult = start_detection(line, m);
      break;
    case ipc::VciOp::control_detect_result: {
      const ixxat::CanLine::Detection d = line.detection();
      r.hresult = d.hr;
      r.values[0] = d.index;
      break;
    }
    default:
      r.hresult = VCI_E_INVALID_HANDLE;  // not an operation of the control unit
      break;
  }
}

void VciService::scheduler(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r) {
  ixxat::CanLine& line = h.line();
  switch (static_cast<ipc::VciOp>(m.op)) {
    case ipc::VciOp::scheduler_resume:
      r.hresult = line.scheduler_resume();
      break;
    case ipc::VciOp::scheduler_suspend:
      r.hresult = line.scheduler_suspend();
      break;
    case ipc::VciOp::scheduler_reset:
      r.hresult = line.scheduler_reset();
      break;
    case ipc::VciOp::scheduler_add: {
      auto index = line.scheduler_add(payload_as<CANCYCLICTXMSG2>(m));
      r.hresult = index ? VCI_OK : index.error();
      r.values[0] = index ? *index : 0xFFFFFFFFU;
      break;
    }
    case ipc::VciOp::scheduler_remove:
      r.hresult = line.scheduler_remove(m.args[0]);
      break;
    case ipc::VciOp::scheduler_start:
      r.hresult = m.args[1] > 0xFFFF
                      ? VCI_E_INVALIDARG
                      : line.scheduler_start(m.args[0], static_cast<uint16_t>(m.args[1]));
      break;
    case ipc::VciOp::scheduler_stop:
      r.hresult = line.scheduler_stop(m.args[0]);
      break;
    case ipc::VciOp::scheduler_status:
      put_payload(r, 0, line.scheduler_status());
      break;
    default:
      r.hresult = VCI_E_INVALID_HANDLE;  // not an operation of the cyclic list
      break;
  }
}

void VciService::close(VciSession& session, uint32_t handle) {
  auto it = session.handles.find(handle);
  if (it == session.handles.end()) {
    return;
  }
  if (VciPort* port = it->second->port(); port != nullptr) {
    bells_.unwatch(*port);
  }
  session.handles.erase(it);
}

void VciService::close_all(VciSession& session) {
  while (!session.handles.empty()) {
    close(session, session.handles.begin()->first);
  }
  session.devices.clear();
  fifos_.release(&session);
}

void VciService::create_device(VciSession& session, const ipc::VciRequest& m, ipc::VciReply& r) {
  char bus_name[ipc::kNameSize];
  std::memcpy(bus_name, m.payload, sizeof bus_name);
  const auto bus = sim_.bus_index(ipc::name_of(bus_name));
  std::string name = ipc::name_of(m.device);
  if (!bus) {
    r.hresult = VCI_E_INVALIDARG;  // no bus of that name
    return;
  }
  if (session.devices.size() >= kMaxVciDevicesPerClient) {
    r.hresult = VCI_E_OUTOFMEMORY;  // too many adapters on this connection
    return;
  }
  if (name.empty()) {
    name = sim_.devices().unique_name("vci");
  } else if (!valid_name(name) || sim_.devices().exists(name)) {
    r.hresult = VCI_E_INVALIDARG;  // the name is taken or not a valid name
    return;
  }
  session.devices.emplace(name, sim_.add_vci_device(name, *bus, session.pid));
  const uint64_t id = sim_.devices().vci_id_of(name);
  r.hresult = VCI_OK;
  r.values[0] = static_cast<uint32_t>(id);
  r.values[1] = static_cast<uint32_t>(id >> 32);
  std::memcpy(r.payload, name.c_str(), std::min(name.size(), ipc::kNameSize - 1));
}

}  // namespace canemu::daemon
