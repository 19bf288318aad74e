// The CAN objects of the VCI C++ API (see can_objects.hpp): control unit, channel, cyclic list
// and socket, each a template over its two interface versions (`v2`: the CANMSG2/CANBTP one).
#include "can_objects.hpp"

#include <cstring>
#include <memory>

#include "can_api.hpp"
#include "com.hpp"
#include "fifo_objects.hpp"

namespace canemu::client::vci::cpp {

using ipc::VciOp;

namespace {

template <class T>
HRESULT line_struct_of(const Bus& bus, const Remote* remote, std::size_t offset, T* out) {
  if (out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  canemu::ipc::VciReply reply{};
  const HRESULT hr = remote != nullptr ? req::line_info(*remote, reply)
                                       : req::line_info(bus.device, bus.no, reply);
  if (hr == VCI_OK) {
    std::memcpy(out, reply.payload + offset, sizeof(T));
  }
  return hr;
}

HRESULT filter_of(const Remote& r, VciOp op, uint32_t kind, UINT8 select, UINT8 mode, UINT32 code,
                  UINT32 mask, PUINT8 mode_out) {
  if (select != CAN_FILTER_STD && select != CAN_FILTER_EXT) {
    return VCI_E_INVALIDARG;
  }
  return req::filter(r, op, kind, select == CAN_FILTER_EXT, mode, code, mask, mode_out);
}

template <class Interface, const IID& iid, bool v2>
class Control final : public Com<Interface, iid> {
 public:
  Control(Bus bus, std::unique_ptr<Remote> remote) : bus_(std::move(bus)), r_(std::move(remote)) {
    register_alias(static_cast<Interface*>(this), r_.get());
  }
  ~Control() override { unregister_alias(static_cast<Interface*>(this)); }
  HRESULT ResetLine() override { return req::simple(*r_, VciOp::control_reset); }
  HRESULT StartLine() override { return req::simple(*r_, VciOp::control_start); }
  HRESULT StopLine() override { return req::simple(*r_, VciOp::control_stop); }
  HRESULT SetAccFilter(UINT8 s, UINT32 code, UINT32 mask) override {
    return filter_of(*r_, VciOp::control_filter, req::kFilterAcceptance, s, 0, code, mask, nullptr);
  }
  HRESULT AddFilterIds(UINT8 s, UINT32 code, UINT32 mask) override {
    return filter_of(*r_, VciOp::control_filter, req::kFilterAddIds, s, 0, code, mask, nullptr);
  }
  HRESULT RemFilterIds(UINT8 s, UINT32 code, UINT32 mask) override {
    return filter_of(*r_, VciOp::control_filter, req::kFilterRemoveIds, s, 0, code, mask, nullptr);
  }

  // ICanControl
  HRESULT DetectBaud(UINT16 timeout_ms, PCANBTRTABLE table) {
    if (table == nullptr || table->bCount == 0 || table->bCount > 64) {
      return VCI_E_INVALIDARG;
    }
    // bIndex CAN_OPMODE_LOWSPEED asks for the low-speed coupling (only on a low-speed bus).
    const uint8_t op_mode = table->bIndex == CAN_OPMODE_LOWSPEED ? CAN_OPMODE_LOWSPEED : 0;
    uint32_t index = 0;
    const HRESULT hr = req::detect(*r_, false, table, sizeof *table, timeout_ms, op_mode, 0, index);
    if (hr == VCI_OK) {
      table->bIndex = static_cast<UINT8>(index);
    }
    return hr;
  }
  HRESULT InitLine(PCANINITLINE p) {
    return p == nullptr ? VCI_E_INVALIDARG : req::init_line(*r_, p, sizeof *p, false);
  }
  HRESULT GetLineStatus(PCANLINESTATUS p) {
    return line_struct_of(bus_, r_.get(), canemu::ipc::kVciLineOffset, p);
  }
  // ICanControl2
  HRESULT DetectBaud(UINT8 op_mode, UINT8 ex_mode, UINT16 timeout_ms, PCANBTPTABLE table) {
    if (table == nullptr || table->bCount == 0 || table->bCount > 64) {
      return VCI_E_INVALIDARG;
    }
    uint32_t index = 0;
    const HRESULT hr =
        req::detect(*r_, true, table, sizeof *table, timeout_ms, op_mode, ex_mode, index);
    if (hr == VCI_OK) {
      table->bIndex = static_cast<UINT8>(index);
    }
    return hr;
  }
  HRESULT InitLine(PCANINITLINE2 p) {
    return p == nullptr ? VCI_E_INVALIDARG : req::init_line(*r_, p, sizeof *p, true);
  }
  HRESULT GetLineStatus(PCANLINESTATUS2 p) {
    return line_struct_of(bus_, r_.get(), canemu::ipc::kVciLine2Offset, p);
  }
  HRESULT GetFilterMode(UINT8 s, PUINT8 mode) {
    if (mode == nullptr) {
      return VCI_E_INVALIDARG;
    }
    return filter_of(*r_, VciOp::control_filter, req::kFilterGetMode, s, 0, 0, 0, mode);
  }
  HRESULT SetFilterMode(UINT8 s, UINT8 mode, PUINT8 previous) {
    return filter_of(*r_, VciOp::control_filter, req::kFilterSetMode, s, mode, 0, 0, previous);
  }

 private:
  Bus bus_;
  std::unique_ptr<Remote> r_;
};
using CanControl1 = Control<ICanControl, IID_ICanControl, false>;
using CanControl2 = Control<ICanControl2, IID_ICanControl2, true>;

HRESULT open_remote(const Bus& bus, Object::Kind kind, bool v2, bool exclusive,
                    std::unique_ptr<Remote>& out) {
  return req::open_can(kind, v2, exclusive, bus.device, bus.no, out);
}

template <class Interface, const IID& iid, bool v2>
class Channel final : public Com<Interface, iid> {
 public:
  Channel(Bus bus, std::unique_ptr<Remote> remote)
      : bus_(std::move(bus)), c_(static_cast<ChannelObj*>(remote.release())) {
    register_alias(static_cast<Interface*>(this), c_.get());
  }
  ~Channel() override { unregister_alias(static_cast<Interface*>(this)); }
  HRESULT GetReader(IFifoReader** pp) override { return get_reader(c_->rings, pp); }
  HRESULT GetWriter(IFifoWriter** pp) override { return get_writer(c_->rings, pp); }
  HRESULT Activate() override { return req::simple(*c_, VciOp::channel_activate); }
  HRESULT Deactivate() override { return req::simple(*c_, VciOp::channel_deactivate); }

  // ICanChannel
  HRESULT Initialize(UINT16 rx, UINT16 tx) {
    if (rx == 0) {
      return VCI_E_INVALIDARG;
    }
    return req::init_channel(*c_, rx, 1, tx, 1, 0, CAN_FILTER_PASS);
  }
  HRESULT GetStatus(PCANCHANSTATUS p) {
    return channel_status_of(*c_, canemu::ipc::kVciLineOffset, p);
  }
  // ICanChannel2
  HRESULT Initialize(UINT32 rx, UINT32 tx, UINT32 filter_size, UINT8 mode) {
    if (rx == 0) {
      return VCI_E_INVALIDARG;
    }
    return req::init_channel(*c_, rx, 1, tx, 1, filter_size, mode);
  }
  HRESULT GetStatus(PCANCHANSTATUS2 p) {
    return channel_status_of(*c_, canemu::ipc::kVciLine2Offset, p);
  }
  HRESULT GetControl(PCANCONTROL2* pp) {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    std::unique_ptr<Remote> r;
    if (HRESULT hr = open_remote(bus_, Object::Kind::control, true, false, r); hr != VCI_OK) {
      return hr;
    }
    *pp = new CanControl2(bus_, std::move(r));
    return VCI_OK;
  }
  HRESULT GetFilterMode(UINT8 s, PUINT8 mode) {
    if (mode == nullptr) {
      return VCI_E_INVALIDARG;
    }
    return filter_of(*c_, VciOp::channel_filter, req::kFilterGetMode, s, 0, 0, 0, mode);
  }
  HRESULT SetFilterMode(UINT8 s, UINT8 mode, PUINT8 previous) {
    return filter_of(*c_, VciOp::channel_filter, req::kFilterSetMode, s, mode, 0, 0, previous);
  }
  HRESULT SetAccFilter(UINT8 s, UINT32 code, UINT32 mask) {
    return filter_of(*c_, VciOp::channel_filter, req::kFilterAcceptance, s, 0, code, mask, nullptr);
  }
  HRESULT AddFilterIds(UINT8 s, UINT32 code, UINT32 mask) {
    return filter_of(*c_, VciOp::channel_filter, req::kFilterAddIds, s, 0, code, mask, nullptr);
  }
  HRESULT RemFilterIds(UINT8 s, UINT32 code, UINT32 mask) {
    return filter_of(*c_, VciOp::channel_filter, req::kFilterRemoveIds, s, 0, code, mask, nullptr);
  }

 private:
  Bus bus_;
  std::unique_ptr<ChannelObj> c_;
};
using CanChannel1 = Channel<ICanChannel, IID_ICanChannel, false>;
using CanChannel2 = Channel<ICanChannel2, IID_ICanChannel2, true>;

template <class Interface, const IID& iid, bool v2>
class Scheduler final : public Com<Interface, iid> {
 public:
  Scheduler(Bus bus, std::unique_ptr<Remote> remote) : bus_(std::move(bus)), r_(std::move(remote)) {
    register_alias(static_cast<Interface*>(this), r_.get());
  }
  ~Scheduler() override { unregister_alias(static_cast<Interface*>(this)); }
  HRESULT Resume() override { return req::simple(*r_, VciOp::scheduler_resume); }
  HRESULT Suspend() override { return req::simple(*r_, VciOp::scheduler_suspend); }
  HRESULT Reset() override { return req::simple(*r_, VciOp::scheduler_reset); }
  HRESULT RemMessage(UINT32 i) override { return req::simple(*r_, VciOp::scheduler_remove, {i}); }
  HRESULT StartMessage(UINT32 i, UINT16 n) override {
    return req::simple(*r_, VciOp::scheduler_start, {i, n});
  }
  HRESULT StopMessage(UINT32 i) override { return req::simple(*r_, VciOp::scheduler_stop, {i}); }
  // ICanScheduler
  HRESULT GetStatus(PCANSCHEDULERSTATUS p) {
    return p == nullptr ? VCI_E_INVALIDARG : scheduler_status_of(*r_, &p->bTaskStat, p->abMsgStat);
  }
  HRESULT AddMessage(PCANCYCLICTXMSG p, PUINT32 index) {
    if (p == nullptr) {
      return failed_add(index);
    }
    return req::scheduler_add(*r_, to_cyclic2(*p), index);
  }
  // ICanScheduler2
  HRESULT GetStatus(PCANSCHEDULERSTATUS2 p) {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    if (HRESULT hr = line_struct_of(bus_, r_.get(), canemu::ipc::kVciLine2Offset, &p->sLineStatus);
        hr != VCI_OK) {
      return hr;
    }
    return scheduler_status_of(*r_, &p->bTaskStat, p->abMsgStat);
  }
  HRESULT AddMessage(PCANCYCLICTXMSG2 p, PUINT32 index) {
    return p == nullptr ? failed_add(index) : req::scheduler_add(*r_, *p, index);
  }

 private:
  static HRESULT failed_add(PUINT32 index) {
    if (index != nullptr) {
      *index = 0xFFFFFFFFU;
    }
    return VCI_E_INVALIDARG;
  }
  Bus bus_;
  std::unique_ptr<Remote> r_;
};

template <class Interface, const IID& iid, bool v2>
class Socket final : public Com<Interface, iid> {
 public:
  explicit Socket(Bus bus) : bus_(std::move(bus)) {}
  HRESULT GetSocketInfo(PBALSOCKETINFO p) override { return socket_info(bus_, p); }
  // ICanSocket
  HRESULT GetCapabilities(PCANCAPABILITIES p) {
    return line_struct_of(bus_, nullptr, canemu::ipc::kVciCapsOffset, p);
  }
  HRESULT GetLineStatus(PCANLINESTATUS p) {
    return line_struct_of(bus_, nullptr, canemu::ipc::kVciLineOffset, p);
  }
  HRESULT CreateChannel(BOOL exclusive, PCANCHANNEL* pp) { return create(exclusive, pp); }
  // ICanSocket2
  HRESULT GetCapabilities(PCANCAPABILITIES2 p) {
    return line_struct_of(bus_, nullptr, canemu::ipc::kVciCaps2Offset, p);
  }
  HRESULT GetLineStatus(PCANLINESTATUS2 p) {
    return line_struct_of(bus_, nullptr, canemu::ipc::kVciLine2Offset, p);
  }
  HRESULT CreateChannel(BOOL exclusive, PCANCHANNEL2* pp) { return create(exclusive, pp); }

 private:
  template <class P>
  HRESULT create(BOOL exclusive, P** pp) {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    std::unique_ptr<Remote> r;
    if (HRESULT hr = open_remote(bus_, Object::Kind::channel, v2, exclusive != 0, r);
        hr != VCI_OK) {
      return hr;
    }
    if constexpr (v2) {
      *pp = new CanChannel2(bus_, std::move(r));
    } else {
      *pp = new CanChannel1(bus_, std::move(r));
    }
    return VCI_OK;
  }
  Bus bus_;
};

}  // namespace

HRESULT socket_info(const Bus& bus, PBALSOCKETINFO p) {
  if (p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  p->Obid.AsInt64 = static_cast<INT64>((bus.device.vci_id << 8) | bus.no);
  p->Type = bus.device.caps().BusCtrlTypes[bus.no];
  p->BusNo = static_cast<UINT16>(bus.no);
  return VCI_OK;
}

HRESULT open_socket(const Bus& bus, REFIID riid, PVOID* ppv) {
  std::unique_ptr<Remote> r;
  if (same(riid, IID_ICanSocket)) {
    return hand_out(static_cast<ICanSocket*>(new Socket<ICanSocket, IID_ICanSocket, false>(bus)),
                    ppv);
  }
  if (same(riid, IID_ICanSocket2)) {
    return hand_out(static_cast<ICanSocket2*>(new Socket<ICanSocket2, IID_ICanSocket2, true>(bus)),
                    ppv);
  }
  const bool control1 = same(riid, IID_ICanControl);
  const bool control2 = same(riid, IID_ICanControl2);
  const bool list1 = same(riid, IID_ICanScheduler);
  const bool list2 = same(riid, IID_ICanScheduler2);
  if (!control1 && !control2 && !list1 && !list2) {
    return VCI_E_NOINTERFACE;
  }
  const Object::Kind kind = control1 || control2 ? Object::Kind::control : Object::Kind::scheduler;
  if (HRESULT hr = open_remote(bus, kind, control2 || list2, false, r); hr != VCI_OK) {
    return hr;
  }
  if (control1) {
    return hand_out(static_cast<ICanControl*>(new CanControl1(bus, std::move(r))), ppv);
  }
  if (control2) {
    return hand_out(static_cast<ICanControl2*>(new CanControl2(bus, std::move(r))), ppv);
  }
  if (list1) {
    return hand_out(static_cast<ICanScheduler*>(
                        new Scheduler<ICanScheduler, IID_ICanScheduler, false>(bus, std::move(r))),
                    ppv);
  }
  return hand_out(static_cast<ICanScheduler2*>(
                      new Scheduler<ICanScheduler2, IID_ICanScheduler2, true>(bus, std::move(r))),
                  ppv);
}

}  // namespace canemu::client::vci::cpp
