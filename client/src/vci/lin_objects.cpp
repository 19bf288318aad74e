// The LIN objects of the VCI C++ API (VCI C++ guide 5.3, 7.7): the socket (ILinSocket), the
// control unit (ILinControl) and message monitors (ILinMonitor), over lin_core.hpp. A
// monitor's reader is a channel's (fifo_objects.hpp) on its LINMSG ring.
#include <memory>

#include "can_objects.hpp"
#include "com.hpp"
#include "fifo_objects.hpp"
#include "lin_core.hpp"

namespace canemu::client::vci::cpp {

namespace {

class LinControl final : public Com<ILinControl, IID_ILinControl> {
 public:
  explicit LinControl(std::unique_ptr<Remote> remote) : r_(std::move(remote)) {
    register_alias(static_cast<ILinControl*>(this), r_.get());
  }
  ~LinControl() override { unregister_alias(static_cast<ILinControl*>(this)); }
  HRESULT InitLine(PLININITLINE p) override {
    if (p == nullptr || p->bReserved != 0) {
      return VCI_E_INVALIDARG;
    }
    return lin_init(*r_, p->bOpMode, p->wBitrate);
  }
  HRESULT ResetLine() override { return req::simple(*r_, ipc::VciOp::lin_reset); }
  HRESULT StartLine() override { return req::simple(*r_, ipc::VciOp::lin_start); }
  HRESULT StopLine() override { return req::simple(*r_, ipc::VciOp::lin_stop); }
  HRESULT GetLineStatus(PLINLINESTATUS p) override {
    return p == nullptr ? VCI_E_INVALIDARG
                        : lin_info(r_->device, r_->controller, r_.get(), nullptr, p);
  }
  HRESULT WriteMessage(BOOL send, PLINMSG msg) override { return lin_write(*r_, send != 0, msg); }

 private:
  std::unique_ptr<Remote> r_;
};

class LinMonitor final : public Com<ILinMonitor, IID_ILinMonitor> {
 public:
  explicit LinMonitor(std::unique_ptr<Remote> remote)
      : m_(static_cast<ChannelObj*>(remote.release())) {
    register_alias(static_cast<ILinMonitor*>(this), m_.get());
  }
  ~LinMonitor() override { unregister_alias(static_cast<ILinMonitor*>(this)); }
  HRESULT Initialize(UINT16 size) override {
    return size == 0 ? VCI_E_INVALIDARG : req::init_lin_monitor(*m_, size, 1);
  }
  HRESULT Activate() override { return lin_monitor_activate(*m_, true); }
  HRESULT Deactivate() override { return lin_monitor_activate(*m_, false); }
  HRESULT GetReader(IFifoReader** pp) override { return get_reader(m_->rings, pp); }
  HRESULT GetStatus(PLINMONITORSTATUS p) override { return lin_monitor_status(*m_, p); }

 private:
  std::unique_ptr<ChannelObj> m_;
};

class LinSocket final : public Com<ILinSocket, IID_ILinSocket> {
 public:
  explicit LinSocket(Bus bus) : bus_(std::move(bus)) {}
  HRESULT GetSocketInfo(PBALSOCKETINFO p) override { return socket_info(bus_, p); }
  HRESULT GetCapabilities(PLINCAPABILITIES p) override {
    return p == nullptr ? VCI_E_INVALIDARG : lin_info(bus_.device, bus_.no, nullptr, p, nullptr);
  }
  HRESULT GetLineStatus(PLINLINESTATUS p) override {
    return p == nullptr ? VCI_E_INVALIDARG : lin_info(bus_.device, bus_.no, nullptr, nullptr, p);
  }
  HRESULT CreateMonitor(BOOL exclusive, PLINMONITOR* pp) override {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    std::unique_ptr<Remote> r;
    if (HRESULT hr = lin_open(bus_.device, bus_.no, Object::Kind::lin_monitor, exclusive != 0, r);
        hr != VCI_OK) {
      return hr;
    }
    *pp = new LinMonitor(std::move(r));
    return VCI_OK;
  }

 private:
  Bus bus_;
};

}  // namespace

HRESULT open_lin_socket(const Bus& bus, REFIID riid, PVOID* ppv) {
  if (same(riid, IID_ILinSocket)) {
    return hand_out(static_cast<ILinSocket*>(new LinSocket(bus)), ppv);
  }
  if (!same(riid, IID_ILinControl)) {
    return VCI_E_NOINTERFACE;
  }
  std::unique_ptr<Remote> r;
  if (HRESULT hr = lin_open(bus.device, bus.no, Object::Kind::lin_control, false, r);
      hr != VCI_OK) {
    return hr;
  }
  return hand_out(static_cast<ILinControl*>(new LinControl(std::move(r))), ppv);
}

}  // namespace canemu::client::vci::cpp
