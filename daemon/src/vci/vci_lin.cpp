// The LIN requests of the VCI personality (ipc::VciOp::lin_*): a client's control units and
// monitors on the LIN controllers of configured IXXAT adapters (model::ixxat::LinLine).
#include <cstring>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/vci/vci_service.hpp"

namespace canemu::daemon {

namespace ixxat = model::ixxat;

Result<std::unique_ptr<VciLinPort>> VciLinPort::create(uint32_t capacity, const std::string& name) {
  auto rings = ipc::RingPair::create(capacity, 1, sizeof(LINMSG), "canemu-lin", name);
  if (!rings) {
    return fail(Errc::io, rings.error().message);
  }
  return std::unique_ptr<VciLinPort>(new VciLinPort(std::move(*rings)));
}

void VciLinPort::put(const LINMSG& msg) {
  if (rx_.put(&msg) == ipc::RingStatus::full) {
    rx_.count_overrun();
  }
}

namespace {

void put_lin_info(const ixxat::LinLine& line, ipc::VciReply& r) {
  const LINCAPABILITIES caps = line.capabilities();
  const LINLINESTATUS status = line.line_status();
  std::memcpy(r.payload + ipc::kVciCapsOffset, &caps, sizeof caps);
  std::memcpy(r.payload + ipc::kVciLineOffset, &status, sizeof status);
}

// The calls of a control unit; VCI_E_INVALID_HANDLE for any other.
HRESULT control_call(ixxat::LinLine& line, const ipc::VciRequest& m) {
  switch (static_cast<ipc::VciOp>(m.op)) {
    case ipc::VciOp::lin_init: {
      if (m.args[0] > 0xFF || m.args[1] > 0xFFFF) {
        return VCI_E_INVALIDARG;
      }
      LININITLINE init{};
      init.bOpMode = static_cast<uint8_t>(m.args[0]);
      init.wBitrate = static_cast<uint16_t>(m.args[1]);
      return line.init_line(init);
    }
    case ipc::VciOp::lin_reset:
      return line.reset_line();
    case ipc::VciOp::lin_start:
      return line.start_line();
    case ipc::VciOp::lin_stop:
      return line.stop_line();
    case ipc::VciOp::lin_write: {
      LINMSG msg;
      std::memcpy(&msg, m.payload, sizeof msg);
      return m.args[0] > 1 ? VCI_E_INVALIDARG : line.write_message(m.args[0] == 1, msg);
    }
    default:
      return VCI_E_INVALID_HANDLE;
  }
}

// The calls of a monitor but its initialization; VCI_E_INVALID_HANDLE for any other.
HRESULT monitor_call(ixxat::LinLine& line, ixxat::MonitorId id, const ipc::VciRequest& m,
                     ipc::VciReply& r) {
  switch (static_cast<ipc::VciOp>(m.op)) {
    case ipc::VciOp::lin_monitor_activate:
      return line.activate(id);
    case ipc::VciOp::lin_monitor_deactivate:
      return line.deactivate(id);
    case ipc::VciOp::lin_monitor_status: {
      const auto s = line.monitor_state(id);
      r.values[0] = s->initialized ? 1 : 0;
      r.values[1] = s->activated ? 1 : 0;
      r.values[2] = s->rx_overrun ? 1 : 0;
      ipc::VciChannelCounters c{};
      c.received = s->received;
      c.lost = s->lost;
      std::memcpy(r.payload, &c, sizeof c);
      return VCI_OK;
    }
    default:
      return VCI_E_INVALID_HANDLE;
  }
}

}  // namespace

bool VciService::is_lin(ipc::VciOp op) {
  const auto v = static_cast<uint16_t>(op);
  return v >= static_cast<uint16_t>(ipc::VciOp::lin_control_open) &&
         v <= static_cast<uint16_t>(ipc::VciOp::lin_monitor_status);
}

void VciService::lin(VciSession& session, const ipc::VciRequest& m, ipc::VciReply& r,
                     std::array<int, ipc::kChannelFdCount>& fds, bool& with_fds) {
  const auto op = static_cast<ipc::VciOp>(m.op);
  if (op == ipc::VciOp::lin_control_open || op == ipc::VciOp::lin_monitor_open) {
    lin_open(session, m, r);
    return;
  }
  if (op == ipc::VciOp::lin_info && m.handle == 0) {
    // A socket's view (ILinSocket): no object of the controller needs to be open.
    auto line = sim_.devices().vci_lin_line(ipc::name_of(m.device), m.controller);
    r.hresult = line == nullptr ? VCI_E_INVALIDARG : VCI_OK;
    if (line != nullptr) {
      put_lin_info(*line, r);
    }
    return;
  }
  auto it = session.handles.find(m.handle);
  if (it == session.handles.end() || !it->second->is_lin()) {
    r.hresult = VCI_E_INVALID_HANDLE;
    return;
  }
  r.handle = m.handle;
  lin_call(*it->second, m, r, fds, with_fds);
}

void VciService::lin_open(VciSession& session, const ipc::VciRequest& m, ipc::VciReply& r) {
  auto line = sim_.devices().vci_lin_line(ipc::name_of(m.device), m.controller);
  if (line == nullptr) {
    r.hresult = VCI_E_INVALIDARG;  // no such device, or the number is not a LIN controller's
    return;
  }
  if (session.handles.size() >= kMaxVciHandlesPerClient) {
    r.hresult = VCI_E_OUTOFMEMORY;
    return;
  }
  if (static_cast<ipc::VciOp>(m.op) == ipc::VciOp::lin_control_open) {
    r.hresult = line->open_control();
    if (r.hresult == VCI_OK) {
      add_handle(session, std::make_unique<VciHandle>(VciHandle::Kind::lin_control, line, 0), r);
    }
    return;
  }
  if (receivers(session) >= kMaxVciChannelsPerClient) {
    r.hresult = VCI_E_OUTOFMEMORY;
    return;
  }
  auto id = line->open_monitor((m.flags & ipc::kVciExclusive) != 0);
  r.hresult = id ? VCI_OK : id.error();
  if (id) {
    add_handle(session, std::make_unique<VciHandle>(VciHandle::Kind::lin_monitor, line, *id), r);
  }
}

void VciService::lin_call(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r,
                          std::array<int, ipc::kChannelFdCount>& fds, bool& with_fds) {
  const auto op = static_cast<ipc::VciOp>(m.op);
  if (op == ipc::VciOp::lin_info) {
    put_lin_info(h.lin(), r);
    r.hresult = VCI_OK;
  } else if (h.kind() == VciHandle::Kind::lin_control) {
    r.hresult = control_call(h.lin(), m);
  } else if (op == ipc::VciOp::lin_monitor_init) {
    lin_monitor_init(h, m, r, fds, with_fds);
  } else {
    r.hresult = monitor_call(h.lin(), h.monitor(), m, r);
  }
}

void VciService::lin_monitor_init(VciHandle& h, const ipc::VciRequest& m, ipc::VciReply& r,
                                  std::array<int, ipc::kChannelFdCount>& fds, bool& with_fds) {
  const uint32_t rx = m.args[0];
  if (rx == 0 || rx > 0xFFFF) {
    r.hresult = VCI_E_INVALIDARG;
    return;
  }
  ixxat::LinLine& line = h.lin();
  if (line.monitor_state(h.monitor())->activated) {
    r.hresult = VCI_E_INVALID_STATE;
    return;
  }
  if (const std::string why = rings_.refusal(h.uid, (std::size_t{rx} + 1) * sizeof(LINMSG));
      !why.empty()) {
    log::warning("LIN monitor of uid {} not initialized: {}", h.uid, why);
    r.hresult = VCI_E_OUTOFMEMORY;
    return;
  }
  auto port = VciLinPort::create(rx, fmt::format("{}", h.monitor()));
  if (!port) {
    r.hresult = VCI_E_OUTOFMEMORY;
    return;
  }
  r.hresult = line.init_monitor(h.monitor(), port->get());
  if (r.hresult != VCI_OK) {
    return;
  }
  VciLinPort& fresh = **port;
  RingBudget budget = rings_.take(h.uid, fresh.bytes());
  h.replace_lin_port(std::move(*port), std::move(budget));
  r.values[0] = fresh.capacity();
  r.values[1] = 0;
  r.values[2] = sizeof(LINMSG);
  fds = fresh.client_fds();
  with_fds = true;
}

}  // namespace canemu::daemon
