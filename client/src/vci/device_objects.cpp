// The device objects of the VCI C++ API (see device_objects.hpp).
#include "device_objects.hpp"

#include <algorithm>
#include <atomic>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "can_objects.hpp"
#include "com.hpp"
#include "lin_core.hpp"

namespace canemu::client::vci::cpp {

namespace {

class Bal final : public Com<IBalObject, IID_IBalObject> {
 public:
  explicit Bal(DeviceDesc d) : d_(std::move(d)) {}
  HRESULT GetFeatures(PBALFEATURES p) override {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    *p = BALFEATURES{};
    p->FwMajorVersion = 1;
    p->FwMinorVersion = 0;
    const VCIDEVICECAPS caps = d_.caps();
    p->BusSocketCount = caps.BusCtrlCount;
    std::memcpy(p->BusSocketType, caps.BusCtrlTypes, sizeof caps.BusCtrlTypes);
    return VCI_OK;
  }
  HRESULT OpenSocket(UINT32 bus_no, REFIID riid, PVOID* ppv) override {
    if (!null_out(ppv)) {
      return VCI_E_INVALIDARG;
    }
    if (bus_no >= d_.controller_fd.size()) {
      return VCI_E_INVALIDARG;
    }
    if (is_lin_controller(d_, bus_no)) {
      return open_lin_socket(Bus{d_, bus_no}, riid, ppv);
    }
    return open_socket(Bus{d_, bus_no}, riid, ppv);
  }

 private:
  DeviceDesc d_;
};

class VciDevice final : public Com<IVciDevice, IID_IVciDevice> {
 public:
  explicit VciDevice(DeviceDesc d) : d_(std::move(d)) {}
  HRESULT GetDeviceInfo(PVCIDEVICEINFO p) override {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    *p = d_.info();
    return VCI_OK;
  }
  HRESULT GetDeviceCaps(PVCIDEVICECAPS p) override {
    if (p == nullptr) {
      return VCI_E_INVALIDARG;
    }
    *p = d_.caps();
    return VCI_OK;
  }
  HRESULT OpenComponent(REFCLSID rclsid, REFIID riid, PVOID* ppv) override {
    if (!null_out(ppv)) {
      return VCI_E_INVALIDARG;
    }
    if (!same(rclsid, CLSID_VCIBAL)) {
      return VCI_E_INVALIDARG;  // the BAL is the only component
    }
    if (!same(riid, IID_IBalObject) && !same(riid, IID_IUnknown)) {
      return VCI_E_NOINTERFACE;
    }
    return hand_out(static_cast<IBalObject*>(new Bal(d_)), ppv);
  }

 private:
  DeviceDesc d_;
};

class EnumDevice final : public Com<IVciEnumDevice, IID_IVciEnumDevice> {
 public:
  EnumDevice(std::vector<DeviceDesc> devices, uint32_t generation)
      : devices_(std::move(devices)), generation_(generation) {}
  ~EnumDevice() override { stop_watch(); }
  HRESULT Next(UINT32 n, PVCIDEVICEINFO out, PUINT32 fetched) override {
    if (out == nullptr || (fetched == nullptr && n != 1)) {
      return VCI_E_INVALIDARG;
    }
    UINT32 k = 0;
    for (; k < n && next_ < devices_.size(); ++k) {
      out[k] = devices_[next_++].info();
    }
    if (fetched != nullptr) {
      *fetched = k;
    }
    return k == 0 && n > 0 ? VCI_E_NO_MORE_ITEMS : VCI_OK;
  }
  HRESULT Skip(UINT32 n) override {
    next_ = std::min<std::size_t>(devices_.size(), next_ + n);
    return VCI_OK;
  }
  HRESULT Reset() override {
    std::vector<DeviceDesc> fresh;
    uint32_t generation = 0;
    if (HRESULT hr = Library::get().list_devices(fresh, &generation); hr != VCI_OK) {
      return hr;
    }
    devices_ = std::move(fresh);
    generation_ = generation;
    next_ = 0;
    return VCI_OK;
  }
  HRESULT AssignEvent(HANDLE event) override {
    stop_watch();
    if (event == nullptr) {
      return VCI_OK;
    }
    // A thread of its own waits for device changes and signals the event.
    stop_ = std::make_shared<std::atomic<bool>>(false);
    watcher_ = std::thread([stop = stop_, event, generation = generation_]() mutable {
      while (!*stop) {
        if (Library::get().wait_device_change(generation, 200) == VCI_OK && !*stop) {
          SetEvent(event);
          std::vector<DeviceDesc> ignored;
          Library::get().list_devices(ignored, &generation);
        }
      }
    });
    return VCI_OK;
  }

 private:
  void stop_watch() {
    if (watcher_.joinable()) {
      *stop_ = true;
      watcher_.join();
    }
  }
  std::vector<DeviceDesc> devices_;
  std::size_t next_ = 0;
  uint32_t generation_ = 0;
  std::shared_ptr<std::atomic<bool>> stop_;
  std::thread watcher_;
};

class DeviceManager final : public Com<IVciDeviceManager, IID_IVciDeviceManager> {
 public:
  HRESULT EnumDevices(IVciEnumDevice** pp) override {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    std::vector<DeviceDesc> devices;
    uint32_t generation = 0;
    if (HRESULT hr = Library::get().list_devices(devices, &generation); hr != VCI_OK) {
      return hr;
    }
    *pp = new EnumDevice(std::move(devices), generation);
    return VCI_OK;
  }
  HRESULT OpenDevice(REFVCIID id, IVciDevice** pp) override {
    if (!null_out(pp)) {
      return VCI_E_INVALIDARG;
    }
    HRESULT hr = VCI_OK;
    if (auto d = device_by_id(id.AsInt64, hr)) {
      *pp = new VciDevice(std::move(*d));
    }
    return hr;
  }
};

}  // namespace

IVciDeviceManager* new_device_manager() {
  return new DeviceManager;
}

IVciDevice* new_device(DeviceDesc d) {
  return new VciDevice(std::move(d));
}

}  // namespace canemu::client::vci::cpp
