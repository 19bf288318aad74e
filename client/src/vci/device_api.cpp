// The device half of the VCI C API, the same in libvcinpl and libvcinpl2: initialization,
// device enumeration, selection (no dialog on Linux) and opening.
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "vci_core.hpp"
#include "vcinpl.h"

using namespace canemu::client::vci;

namespace {

Device* device_of(HANDLE h) {
  return static_cast<Device*>(lookup(h, Object::Kind::device));
}
Enumerator* enumerator_of(HANDLE h) {
  return static_cast<Enumerator*>(lookup(h, Object::Kind::enumerator));
}

// REFVCIID and REFGUID are references in C++.
const VCIID* ptr(REFVCIID r) {
  return &r;
}
const GUID* ptr(REFGUID r) {
  return &r;
}

// vciSelectDeviceDlg's choice without a dialog: the device $CANEMU_VCI_DEVICE names (by name or
// VCIID text), otherwise the first one listed.
HRESULT choose_device(DeviceDesc& out) {
  std::vector<DeviceDesc> devices;
  if (HRESULT hr = Library::get().list_devices(devices); hr != VCI_OK) {
    return hr;
  }
  const char* wanted = std::getenv("CANEMU_VCI_DEVICE");
  if (wanted == nullptr || *wanted == '\0') {
    if (devices.empty()) {
      set_detail("vciSelectDeviceDlg: canemud has no device to choose");
      return VCI_E_NO_MORE_ITEMS;
    }
    out = devices.front();
    return VCI_OK;
  }
  const auto id = parse_luid(wanted);
  for (const DeviceDesc& d : devices) {
    if (d.name == wanted || (id && static_cast<uint64_t>(id->AsInt64) == d.vci_id)) {
      out = d;
      return VCI_OK;
    }
  }
  set_detail(std::string("vciSelectDeviceDlg: canemud has no device \"") + wanted +
             "\" (named by CANEMU_VCI_DEVICE)");
  return VCI_E_NO_MORE_ITEMS;
}

}  // namespace

extern "C" {

HRESULT VCIAPI vciInitialize(void) {
  // Nothing to set up until the first call that needs canemud: a program that only formats
  // errors or converts identifiers runs without it.
  return VCI_OK;
}

HRESULT VCIAPI vciEnumDeviceOpen(PHANDLE phEnum) {
  if (phEnum == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *phEnum = nullptr;
  auto e = std::make_unique<Enumerator>();
  if (HRESULT hr = Library::get().list_devices(e->devices, &e->generation); hr != VCI_OK) {
    return hr;
  }
  *phEnum = register_object(std::move(e));
  return VCI_OK;
}

HRESULT VCIAPI vciEnumDeviceClose(HANDLE hEnum) {
  return unregister_object(hEnum, Object::Kind::enumerator) ? VCI_OK : VCI_E_INVHANDLE;
}

HRESULT VCIAPI vciEnumDeviceNext(HANDLE hEnum, PVCIDEVICEINFO pInfo) {
  Enumerator* e = enumerator_of(hEnum);
  if (e == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pInfo == nullptr) {
    return VCI_E_INVALIDARG;
  }
  if (e->next >= e->devices.size()) {
    return VCI_E_NO_MORE_ITEMS;
  }
  *pInfo = e->devices[e->next++].info();
  return VCI_OK;
}

HRESULT VCIAPI vciEnumDeviceReset(HANDLE hEnum) {
  Enumerator* e = enumerator_of(hEnum);
  if (e == nullptr) {
    return VCI_E_INVHANDLE;
  }
  // A fresh snapshot: devices that came or went since the last one show.
  std::vector<DeviceDesc> devices;
  uint32_t generation = 0;
  if (HRESULT hr = Library::get().list_devices(devices, &generation); hr != VCI_OK) {
    return hr;
  }
  e->devices = std::move(devices);
  e->generation = generation;
  e->next = 0;
  return VCI_OK;
}

HRESULT VCIAPI vciEnumDeviceWaitEvent(HANDLE hEnum, UINT32 dwMsTimeout) {
  Enumerator* e = enumerator_of(hEnum);
  if (e == nullptr) {
    return VCI_E_INVHANDLE;
  }
  return Library::get().wait_device_change(e->generation, timeout_of(dwMsTimeout));
}

HRESULT VCIAPI vciFindDeviceByHwid(REFGUID rHwid, PVCIID pVciid) {
  if (pVciid == nullptr) {
    return VCI_E_INVALIDARG;
  }
  HRESULT hr = VCI_OK;
  if (auto d = device_by_hwid(*ptr(rHwid), hr)) {
    *pVciid = d->info().VciObjectId;
  }
  return hr;
}

HRESULT VCIAPI vciFindDeviceByClass(REFGUID rClass, UINT32 dwInst, PVCIID pVciid) {
  if (pVciid == nullptr) {
    return VCI_E_INVALIDARG;
  }
  HRESULT hr = VCI_OK;
  if (auto d = device_by_class(*ptr(rClass), dwInst, hr)) {
    *pVciid = d->info().VciObjectId;
  }
  return hr;
}

HRESULT VCIAPI vciSelectDeviceDlg(HWND, PVCIID pVciid) {
  if (pVciid == nullptr) {
    return VCI_E_INVALIDARG;
  }
  DeviceDesc d;
  if (HRESULT hr = choose_device(d); hr != VCI_OK) {
    return hr;
  }
  *pVciid = d.info().VciObjectId;
  return VCI_OK;
}

HRESULT VCIAPI vciDeviceOpenDlg(HWND, PHANDLE phDevice) {
  if (phDevice == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *phDevice = nullptr;
  auto dev = std::make_unique<Device>();
  if (HRESULT hr = choose_device(dev->desc); hr != VCI_OK) {
    return hr;
  }
  *phDevice = register_object(std::move(dev));
  return VCI_OK;
}

HRESULT VCIAPI vciDeviceOpen(REFVCIID rVciid, PHANDLE phDevice) {
  if (phDevice == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *phDevice = nullptr;
  HRESULT hr = VCI_OK;
  if (auto d = device_by_id(ptr(rVciid)->AsInt64, hr)) {
    auto dev = std::make_unique<Device>();
    dev->desc = std::move(*d);
    *phDevice = register_object(std::move(dev));
  }
  return hr;
}

HRESULT VCIAPI vciDeviceClose(HANDLE hDevice) {
  return unregister_object(hDevice, Object::Kind::device) ? VCI_OK : VCI_E_INVHANDLE;
}

HRESULT VCIAPI vciDeviceGetInfo(HANDLE hDevice, PVCIDEVICEINFO pInfo) {
  Device* d = device_of(hDevice);
  if (d == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pInfo == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *pInfo = d->desc.info();
  return VCI_OK;
}

HRESULT VCIAPI vciDeviceGetCaps(HANDLE hDevice, PVCIDEVICECAPS pCaps) {
  Device* d = device_of(hDevice);
  if (d == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pCaps == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *pCaps = d->desc.caps();
  return VCI_OK;
}

}  // extern "C"
