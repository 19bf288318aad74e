// canemu's extensions of the VCI C API (canemu_vci.h), in both libraries.
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "can_api.hpp"
#include "canemu_vci.h"

using namespace canemu::client::vci;

namespace {

// A C API handle, or a C++ API object pointer.
Remote* any_remote(HANDLE h) {
  for (Object::Kind kind :
       {Object::Kind::control, Object::Kind::channel, Object::Kind::scheduler}) {
    if (Remote* r = remote_of(h, kind)) {
      return r;
    }
  }
  return alias_of(h);
}

CANEMU_DEVICEINFO device_info(const DeviceDesc& d) {
  CANEMU_DEVICEINFO info{};
  std::snprintf(info.szName, sizeof info.szName, "%s", d.name.c_str());
  info.VciObjectId.AsInt64 = static_cast<INT64>(d.vci_id);
  info.qwEpochNs = d.epoch_ns;
  info.bControllers = static_cast<UINT8>(d.controller_fd.size());
  info.bEphemeral = d.ephemeral ? 1 : 0;
  for (std::size_t k = 0; k < d.controller_fd.size() && k < CANEMU_MAX_CONTROLLERS; ++k) {
    info.abFd[k] = d.controller_lin[k] ? 2 : d.controller_fd[k] ? 1 : 0;
    std::snprintf(info.aszBus[k], sizeof info.aszBus[k], "%s",
                  k < d.buses.size() ? d.buses[k].c_str() : "");
  }
  return info;
}

}  // namespace

static_assert(sizeof(CANEMU_BUSINFO) == 48);
static_assert(sizeof(CANEMU_DEVICEINFO) == 184);

extern "C" {

HRESULT VCIAPI canemuConnect(const char* pszSocket) {
  forget_call_detail();  // an earlier call's reason is not this one's
  return Library::get().reconnect(pszSocket != nullptr ? pszSocket : "");
}

HRESULT VCIAPI canemuGetControllerState(HANDLE hObject, PUINT8 pbErrorState, PUINT16 pwTec,
                                        PUINT16 pwRec, PUINT8 pbLineState) {
  forget_call_detail();  // an earlier call's reason is not this one's
  Remote* r = any_remote(hObject);
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  canemu::ipc::VciReply reply{};
  if (HRESULT hr = req::simple(*r, canemu::ipc::VciOp::controller_state, {}, &reply);
      hr != VCI_OK) {
    return hr;
  }
  if (pbErrorState != nullptr) {
    *pbErrorState = static_cast<UINT8>(reply.values[0]);
  }
  if (pwTec != nullptr) {
    *pwTec = static_cast<UINT16>(reply.values[1]);
  }
  if (pwRec != nullptr) {
    *pwRec = static_cast<UINT16>(reply.values[2]);
  }
  if (pbLineState != nullptr) {
    *pbLineState = static_cast<UINT8>(reply.values[3]);
  }
  return VCI_OK;
}

HRESULT VCIAPI canemuCreateDevice(const char* pszBus, const char* pszName, PVCIID pVciid,
                                  PCHAR pszNameOut, UINT32 cbNameOut) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (pszBus == nullptr || (pszNameOut != nullptr && cbNameOut < canemu::ipc::kNameSize)) {
    return VCI_E_INVALIDARG;
  }
  canemu::ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(canemu::ipc::VciOp::device_create);
  canemu::ipc::copy_name(m.device, pszName != nullptr ? pszName : "");
  char bus[canemu::ipc::kNameSize] = {};
  std::snprintf(bus, sizeof bus, "%s", pszBus);
  std::memcpy(m.payload, bus, sizeof bus);
  canemu::ipc::VciReply r{};
  if (HRESULT hr = Library::get().call(m, r); hr != VCI_OK) {
    return hr;
  }
  if (pVciid != nullptr) {
    pVciid->AsInt64 = static_cast<INT64>(uint64_t{r.values[0]} | (uint64_t{r.values[1]} << 32));
  }
  if (pszNameOut != nullptr) {
    std::snprintf(pszNameOut, cbNameOut, "%.*s", static_cast<int>(canemu::ipc::kNameSize - 1),
                  reinterpret_cast<const char*>(r.payload));
  }
  return VCI_OK;
}

HRESULT VCIAPI canemuRemoveDevice(const char* pszName) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (pszName == nullptr) {
    return VCI_E_INVALIDARG;
  }
  canemu::ipc::VciRequest m{};
  m.op = static_cast<uint16_t>(canemu::ipc::VciOp::device_remove);
  canemu::ipc::copy_name(m.device, pszName);
  canemu::ipc::VciReply r{};
  return Library::get().call(m, r);
}

HRESULT VCIAPI canemuStepTime(UINT64 qwNanoseconds, UINT64* pqwNow) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (qwNanoseconds == 0 || qwNanoseconds > static_cast<UINT64>(INT64_MAX)) {
    return VCI_E_INVALIDARG;
  }
  int64_t now = 0;
  if (HRESULT hr = Library::get().step(static_cast<int64_t>(qwNanoseconds), now); hr != VCI_OK) {
    return hr;
  }
  if (pqwNow != nullptr) {
    *pqwNow = static_cast<UINT64>(now);
  }
  return VCI_OK;
}

HRESULT VCIAPI canemuEnumBuses(UINT32 dwIndex, PCANEMU_BUSINFO pInfo) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (pInfo == nullptr) {
    return VCI_E_INVALIDARG;
  }
  canemu::client::Status status;
  if (HRESULT hr = Library::get().status(status); hr != VCI_OK) {
    return hr;
  }
  if (dwIndex >= status.buses.size()) {
    return VCI_E_NO_MORE_ITEMS;
  }
  const canemu::ipc::StatusBus& b = status.buses[dwIndex];
  CANEMU_BUSINFO info{};
  std::snprintf(info.szName, sizeof info.szName, "%s", canemu::ipc::name_of(b.name).c_str());
  info.bKind = b.kind;
  info.bLowSpeed = b.low_speed;
  info.dwBitrate = b.bitrate;
  info.dwDataBitrate = b.data_bitrate;
  *pInfo = info;
  return VCI_OK;
}

HRESULT VCIAPI canemuEnumDevices(UINT32 dwIndex, PCANEMU_DEVICEINFO pInfo) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (pInfo == nullptr) {
    return VCI_E_INVALIDARG;
  }
  std::vector<DeviceDesc> devices;
  if (HRESULT hr = Library::get().list_devices(devices); hr != VCI_OK) {
    return hr;
  }
  if (dwIndex >= devices.size()) {
    return VCI_E_NO_MORE_ITEMS;
  }
  *pInfo = device_info(devices[dwIndex]);
  return VCI_OK;
}

HRESULT VCIAPI canemuFindDevice(const char* pszName, PCANEMU_DEVICEINFO pInfo) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (pszName == nullptr || pInfo == nullptr) {
    return VCI_E_INVALIDARG;
  }
  std::vector<DeviceDesc> devices;
  if (HRESULT hr = Library::get().list_devices(devices); hr != VCI_OK) {
    return hr;
  }
  for (const DeviceDesc& d : devices) {
    if (d.name == pszName) {
      *pInfo = device_info(d);
      return VCI_OK;
    }
  }
  set_detail(std::string("no adapter is named \"") + pszName + "\"");
  return VCI_E_NO_MORE_ITEMS;
}

HRESULT VCIAPI canemuGetTime(UINT64* pqwNow, PUINT8 pbTimeMode) {
  forget_call_detail();  // an earlier call's reason is not this one's
  canemu::client::Status status;
  if (HRESULT hr = Library::get().status(status); hr != VCI_OK) {
    return hr;
  }
  if (pqwNow != nullptr) {
    *pqwNow = static_cast<UINT64>(status.sim_time_ns);
  }
  if (pbTimeMode != nullptr) {
    *pbTimeMode = status.time_mode;
  }
  return VCI_OK;
}

HRESULT VCIAPI canemuChannelEventFd(HANDLE hCanChn, int* pFd) {
  forget_call_detail();  // an earlier call's reason is not this one's
  ChannelObj* c = channel_of(hCanChn);
  if (c == nullptr) {
    return VCI_E_INVHANDLE;
  }
  if (pFd == nullptr) {
    return VCI_E_INVALIDARG;
  }
  if (!c->rings) {
    return VCI_E_NOT_INITIALIZED;
  }
  *pFd = channel_poll_fd(*c);
  return VCI_OK;
}

}  // extern "C"
