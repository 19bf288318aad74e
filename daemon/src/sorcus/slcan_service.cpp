#include "canemu/daemon/sorcus/slcan_service.hpp"

#include <algorithm>
#include <cstring>
#include <optional>

#include <fmt/format.h>

#include "service_replies.hpp"

namespace canemu::daemon {

namespace {

using model::sorcus::SlcanServiceCall;

}  // namespace

SlcanService::~SlcanService() {
  for (const std::shared_ptr<SlcanDevice>& d : hooked_) {
    d->on_service = nullptr;
    d->on_request = nullptr;
  }
}

void SlcanService::hook(const std::shared_ptr<SlcanDevice>& device) {
  if (!hooked_.insert(device).second) {
    return;
  }
  const unsigned slot = device->module().slot();
  device->on_service = [this, slot](const SlcanServiceCall& c) {
    SlcanSession* s = owner_[slot];
    if (s == nullptr) {
      return;
    }
    auto m = ipc::make_message<ipc::SlcanEventMsg>(0);
    m.kind = static_cast<uint8_t>(c.kind == SlcanServiceCall::Kind::message
                                      ? ipc::SlcanEventKind::message
                                      : ipc::SlcanEventKind::error);
    m.slot = static_cast<uint8_t>(slot);
    m.task = c.task;
    m.func = c.func;
    m.handle = c.handle;
    m.status = c.kind == SlcanServiceCall::Kind::error ? c.status : c.id;
    m.sim_time_ns = c.at.ns();
    s->outbox.push_back(bytes_of(m));
  };
  device->on_request = [this, slot](model::SimTime at, USHORT word) {
    SlcanSession* s = owner_[slot];
    if (s == nullptr) {
      return;
    }
    auto m = ipc::make_message<ipc::SlcanEventMsg>(0);
    m.kind = static_cast<uint8_t>(ipc::SlcanEventKind::service_request);
    m.slot = static_cast<uint8_t>(slot);
    m.word = word;
    m.sim_time_ns = at.ns();
    s->outbox.push_back(bytes_of(m));
  };
}

void SlcanService::startup(SlcanSession& session, ipc::SlcanReply& r) {
  // «Das S-Link mit der niedrigsten Steckplatznummer wird der Instanz des Treiberprogramms mit
  // der niedrigsten Tasknummer zugeordnet»: every configured slot no one else holds.
  for (const DeviceRegistry::Slcan& s : sim_.devices().slcan()) {
    const unsigned slot = s.device->module().slot();
    if (owner_[slot] != nullptr && owner_[slot] != &session) {
      continue;
    }
    hook(s.device);
    owner_[slot] = &session;
    session.slots.insert(slot);
    (void)s.device->module().bib_startup();
  }
  uint32_t mask = 0;
  for (unsigned slot : session.slots) {
    mask |= 1u << slot;
  }
  r.value = mask;
}

void SlcanService::handle(SlcanSession& session, const ipc::SlcanRequest& m, const Send& send) {
  const uint32_t id = m.header.request_id;
  auto r = ipc::make_message<ipc::SlcanReply>(id);
  const auto op = static_cast<ipc::SlcanOp>(m.op);
  if (op == ipc::SlcanOp::bib_startup) {
    startup(session, r);
    r.sim_time_ns = sim_.scheduler().now().ns();
    send(&r, sizeof r, {});
    return;
  }
  // The EEPROM may also be read and written on a slot nobody holds (canemu eeprom).
  const bool eeprom = op == ipc::SlcanOp::eeprom_read || op == ipc::SlcanOp::eeprom_write;
  if (m.slot >= owner_.size() ||
      (owner_[m.slot] != &session && !(eeprom && owner_[m.slot] == nullptr))) {
    protocol_error(send, id, ipc::ErrorCode::no_such_channel,
                   fmt::format("slot {} is not this client's (sl064_bib_startup gives the "
                               "configured slots no other client holds)",
                               m.slot));
    return;
  }
  std::shared_ptr<SlcanDevice> device = sim_.devices().find_slcan_slot(m.slot);
  if (device == nullptr) {
    protocol_error(send, id, ipc::ErrorCode::no_such_channel,
                   fmt::format("slot {} has no SL-CANi", m.slot));
    return;
  }
  std::string error;
  if (!call(*device, session, m, r, error)) {
    protocol_error(send, id, ipc::ErrorCode::bad_argument, error);
    return;
  }
  r.diagnosis = device->module().last_diagnosis();
  r.sim_time_ns = sim_.scheduler().now().ns();
  send(&r, sizeof r, {});
}

bool SlcanService::call(SlcanDevice& device, SlcanSession& session, const ipc::SlcanRequest& m,
                        ipc::SlcanReply& r, std::string& error) {
  model::sorcus::SlcanModule& mod = device.module();
  switch (static_cast<ipc::SlcanOp>(m.op)) {
    case ipc::SlcanOp::config_module:
      r.ret = mod.config_module(m.task, m.func);
      return true;
    case ipc::SlcanOp::config_msg_object: {
      const SL064MsgType c{m.value, m.flags, m.task, m.func};
      SL064Handle h = 0;
      r.ret = mod.config_msg_object(c, h);
      r.handle = h;
      return true;
    }
    case ipc::SlcanOp::clear_configuration:
      r.ret = mod.clear_configuration();
      return true;
    case ipc::SlcanOp::start_com:
      r.ret = mod.start_com();
      return true;
    case ipc::SlcanOp::stop_com:
      r.ret = mod.stop_com();
      return true;
    case ipc::SlcanOp::get_diagnosis:
      r.value = mod.get_diagnosis();
      return true;
    case ipc::SlcanOp::set_data: {
      // More than 8 bytes reaches the driver as such (it refuses them with 2Ah).
      std::array<uint8_t, 9> d{};
      std::memcpy(d.data(), m.data, sizeof m.data);
      r.ret = mod.set_data(m.handle,
                           std::span<const uint8_t>(d.data(), std::min<std::size_t>(m.size, 9)));
      return true;
    }
    case ipc::SlcanOp::get_data: {
      std::array<uint8_t, 8> d{};
      uint8_t size = m.size;
      r.ret = mod.get_data(m.handle, d, size);
      r.size = size;
      std::memcpy(r.data, d.data(), 8);
      return true;
    }
    case ipc::SlcanOp::send_data:
      r.ret = mod.send_data(m.handle);
      return true;
    case ipc::SlcanOp::send_data_request:
      r.ret = mod.send_data_request(m.handle);
      return true;
    case ipc::SlcanOp::clear_msg:
      r.ret = mod.clear_msg(m.handle);
      return true;
    case ipc::SlcanOp::set_acceptance_mask: {
      ULONG mask = m.value;
      r.ret = mod.set_acceptance_mask(mask, m.flags, m.task, m.func);
      r.value = mask;
      return true;
    }
    case ipc::SlcanOp::get_id: {
      ULONG v = 0;
      r.ret = mod.get_id(m.handle, v,
                         (m.flags & ipc::kSlcanGetIdOfCall) != 0 && m.handle == 0
                             ? std::optional<ULONG>(m.value)
                             : std::nullopt);
      r.value = v;
      return true;
    }
    case ipc::SlcanOp::get_msg_count: {
      ULONG v = 0;
      r.ret = mod.get_msg_count(m.handle, v);
      r.value = v;
      return true;
    }
    case ipc::SlcanOp::set_led:
      mod.set_led(static_cast<UCHAR>(m.value != 0));
      return true;
    case ipc::SlcanOp::get_led:
      r.value = mod.get_led();
      return true;
    case ipc::SlcanOp::evaluate_srq: {
      SL064Handle h = 0;
      r.ret = mod.evaluate_srq(h);
      r.handle = h;
      return true;
    }
    case ipc::SlcanOp::enable_int_mask:
      mod.enable_int_mask();
      return true;
    case ipc::SlcanOp::end_of_srq:
      mod.end_of_srq();
      return true;
    case ipc::SlcanOp::install_routine:
      mod.install_routine(m.task, m.func);
      session.routines.insert({m.slot, m.task, m.func});
      return true;
    case ipc::SlcanOp::remove_routine:
      mod.remove_routine(m.task, m.func);
      session.routines.erase({m.slot, m.task, m.func});
      return true;
    case ipc::SlcanOp::eeprom_read:
      std::copy(mod.eeprom().begin(), mod.eeprom().end(), r.eeprom);
      return true;
    case ipc::SlcanOp::eeprom_write:
      if (auto w = device.write_eeprom(m.value, m.handle); !w) {
        error = "EEPROM: " + w.error().what();
        return false;
      }
      std::copy(mod.eeprom().begin(), mod.eeprom().end(), r.eeprom);
      return true;
    case ipc::SlcanOp::bib_startup:
      break;
  }
  error = fmt::format("unknown SL-CANi operation {}", m.op);
  return false;
}

void SlcanService::close_all(SlcanSession& session) {
  for (unsigned slot : session.slots) {
    if (owner_[slot] == &session) {
      owner_[slot] = nullptr;
    }
    if (auto device = sim_.devices().find_slcan_slot(slot)) {
      for (const auto& [s, task, func] : session.routines) {
        if (s == slot) {
          device->module().remove_routine(task, func);
        }
      }
      device->module().reset();
    }
  }
  session.slots.clear();
  session.routines.clear();
  session.outbox.clear();
}

}  // namespace canemu::daemon
