// canemu's extensions of the VCI C API (canemu_vci.h), in both libraries.
#include <cstdio>
#include <cstring>

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

}  // namespace

extern "C" {

HRESULT VCIAPI canemuConnect(const char* pszSocket) {
  return Library::get().reconnect(pszSocket != nullptr ? pszSocket : "");
}

HRESULT VCIAPI canemuGetControllerState(HANDLE hObject, PUINT8 pbErrorState, PUINT16 pwTec,
                                        PUINT16 pwRec, PUINT8 pbLineState) {
  Remote* r = any_remote(hObject);
  if (r == nullptr) {
    return VCI_E_INVHANDLE;
  }
  canemu::ipc::VciReply reply{};
  if (HRESULT hr = Library::get().simple(*r, canemu::ipc::VciOp::controller_state, {}, &reply);
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

}  // extern "C"
