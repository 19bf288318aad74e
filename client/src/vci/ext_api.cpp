// canemu's extensions of the VCI C API (canemu_vci.h), in both libraries.
#include "can_api.hpp"
#include "canemu_vci.h"

using namespace canemu::client::vci;

namespace {

Remote* any_remote(HANDLE h) {
  for (Object::Kind kind :
       {Object::Kind::control, Object::Kind::channel, Object::Kind::scheduler}) {
    if (Remote* r = remote_of(h, kind)) {
      return r;
    }
  }
  return nullptr;
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
